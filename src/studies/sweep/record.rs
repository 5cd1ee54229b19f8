//! What a sweep keeps of each run, and the two tables made of them: the runs (one row per run,
//! in the order of the runs) and, when asked, every sample.
//!
//! The runs' columns, a stable naming (docs/commands.md, "sweep"):
//! `run` (its index in the design, from 0), the design's names (the values the run took),
//! `status` (`ok`, `failed` or `unprepared`), `failure_time` and `failure` (when and why a run
//! stopped, or why it could not be prepared), `steps`, `end_time` (the last sample's time), then
//! for every quantity `q` of the samples (the declared coordinates, their rates `q'`, the
//! energies, the program's outputs): `end(q)`, `min(q)` and `max(q)`, its value at the last
//! sample and its extremes over the run.
//! The samples' columns: `run`, `time`, then the quantities by their names.

use super::table::{Column, Kind, Table};

/// How a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// To the end of its duration.
    Ok,
    /// Stopped before its end: the integration failed (`failure_time`, `failure`).
    Failed,
    /// Its values cannot be prepared (a loop that cannot be assembled, say): `failure`.
    Unprepared,
    /// Stopped by a signal; never written: the run is done again on `--resume`.
    Interrupted,
}

impl Status {
    pub fn name(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::Failed => "failed",
            Status::Unprepared => "unprepared",
            Status::Interrupted => "interrupted",
        }
    }

    pub fn from_name(name: &str) -> Option<Status> {
        [
            Status::Ok,
            Status::Failed,
            Status::Unprepared,
            Status::Interrupted,
        ]
        .into_iter()
        .find(|s| s.name() == name)
    }
}

/// One run's result.
#[derive(Clone, Debug, PartialEq)]
pub struct RunRecord {
    pub run: usize,
    /// The design's values for this run.
    pub values: Vec<f64>,
    pub status: Status,
    pub failure_time: Option<f64>,
    pub failure: Option<String>,
    /// The integrator's steps, rejected ones included (none when unprepared).
    pub steps: Option<u64>,
    pub end_time: Option<f64>,
    /// Per quantity: at the last sample, smallest, largest (none without samples).
    pub end: Vec<Option<f64>>,
    pub min: Vec<Option<f64>>,
    pub max: Vec<Option<f64>>,
    /// Every sample (time, then the quantities), when asked for.
    pub samples: Vec<Vec<f64>>,
}

impl RunRecord {
    /// A run whose values cannot be prepared, and why.
    pub fn failed_to_prepare(run: usize, values: &[f64], why: String) -> RunRecord {
        RunRecord {
            run,
            values: values.to_vec(),
            status: Status::Unprepared,
            failure_time: None,
            failure: Some(why),
            steps: None,
            end_time: None,
            end: Vec::new(),
            min: Vec::new(),
            max: Vec::new(),
            samples: Vec::new(),
        }
    }
}

/// The type of a column of the runs' table, by its name.
pub fn runs_column_kind(name: &str) -> Kind {
    match name {
        "run" => Kind::Index,
        "steps" => Kind::Count,
        "status" => Kind::Label,
        "failure" => Kind::Text,
        _ => Kind::Number,
    }
}

/// The type of a column of the samples' table, by its name.
pub fn samples_column_kind(name: &str) -> Kind {
    match name {
        "run" => Kind::Index,
        _ => Kind::Number,
    }
}

/// The runs' table of `records` (in the order given), for a design of `names` and samples of
/// `quantities`.
pub fn runs_table(names: &[String], quantities: &[String], records: &[RunRecord]) -> Table {
    let mut columns = Vec::new();
    let numbers = |name: String, cell: &dyn Fn(&RunRecord) -> Option<f64>| {
        Column::numbers(name, records.iter().map(cell).collect())
    };
    let runs = records.iter().map(|r| Some(r.run as i64)).collect();
    columns.push(Column::integers("run".into(), Kind::Index, runs));
    for (k, name) in names.iter().enumerate() {
        columns.push(numbers(name.clone(), &|r| r.values.get(k).copied()));
    }
    let statuses = records.iter().map(|r| Some(r.status.name().to_string()));
    columns.push(Column::texts(
        "status".into(),
        Kind::Label,
        statuses.collect(),
    ));
    columns.push(numbers("failure_time".into(), &|r| r.failure_time));
    let failures = records.iter().map(|r| r.failure.clone()).collect();
    columns.push(Column::texts("failure".into(), Kind::Text, failures));
    let steps = records.iter().map(|r| r.steps.map(|s| s as i64)).collect();
    columns.push(Column::integers("steps".into(), Kind::Count, steps));
    columns.push(numbers("end_time".into(), &|r| r.end_time));
    for (k, quantity) in quantities.iter().enumerate() {
        columns.push(numbers(format!("end({quantity})"), &|r| {
            r.end.get(k).copied().flatten()
        }));
        columns.push(numbers(format!("min({quantity})"), &|r| {
            r.min.get(k).copied().flatten()
        }));
        columns.push(numbers(format!("max({quantity})"), &|r| {
            r.max.get(k).copied().flatten()
        }));
    }
    Table { columns }
}

/// The samples' table of `records`: a row per sample, the runs in the order given.
pub fn samples_table(quantities: &[String], records: &[RunRecord]) -> Table {
    let rows = || {
        records
            .iter()
            .flat_map(|r| r.samples.iter().map(move |s| (r.run, s)))
    };
    let runs = rows().map(|(run, _)| Some(run as i64)).collect();
    let mut columns = vec![Column::integers("run".into(), Kind::Index, runs)];
    let names = std::iter::once("time".to_string()).chain(quantities.iter().cloned());
    for (k, name) in names.enumerate() {
        let cells = rows().map(|(_, sample)| sample.get(k).copied()).collect();
        columns.push(Column::numbers(name, cells));
    }
    Table { columns }
}
