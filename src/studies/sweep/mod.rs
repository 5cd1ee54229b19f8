//! Sweeps (`lsdc sweep`): one program run many times in one process, over a grid, a list or
//! a sample of values (`design`, its distributions in `distribution`), every core running
//! runs of one shared preparation (`runs`); a record per run (`record`) journaled as it
//! finishes (`journal`), so that an interrupted sweep resumes; the results as a table written
//! as CSV or Parquet (`table`). A sweep splits into deterministic shards for a cluster's job
//! array, and [`gather`] merges the shards' files into the file of the whole sweep, bit for bit.

pub mod design;
pub mod distribution;
pub mod journal;
pub mod record;
pub mod runs;
pub mod table;

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use self::journal::Journal;
use self::record::{runs_column_kind, samples_column_kind, RunRecord};
use self::runs::{run_all, Stop, Sweep};
use self::table::Table;

/// The K-th of N parts of a sweep (`--shard K/N`, K from 1): the runs from ⌊(K−1)R/N⌋ to
/// ⌊KR/N⌋ of R, contiguous, so that the parts' files put end to end are the whole sweep's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl Shard {
    /// The whole sweep.
    pub const WHOLE: Shard = Shard { index: 1, count: 1 };

    /// Reads `K/N` (1 ≤ K ≤ N); `index_from_zero` reads K from 0, as a Kubernetes Indexed
    /// Job's `JOB_COMPLETION_INDEX` gives it.
    pub fn parse(text: &str, index_from_zero: bool) -> Result<Shard, String> {
        let form = || format!("`--shard {text}`: write K/N, the K-th of N parts, 1 ≤ K ≤ N");
        let (k, n) = text.split_once('/').ok_or_else(form)?;
        let k: usize = k.trim().parse().map_err(|_| form())?;
        let n: usize = n.trim().parse().map_err(|_| form())?;
        let k = k + usize::from(index_from_zero);
        match (1..=n).contains(&k) {
            true => Ok(Shard { index: k, count: n }),
            false => Err(form()),
        }
    }

    /// The runs of this part of a sweep of `total` runs.
    pub fn runs(&self, total: usize) -> Range<usize> {
        let bound = |k: usize| (k as u128 * total as u128 / self.count as u128) as usize;
        bound(self.index - 1)..bound(self.index)
    }
}

/// How a sweep goes: its part, its journal, its threads, what stops it.
pub struct Execution<'a> {
    pub shard: Shard,
    /// Where finished runs are journaled (none when the results go to standard output).
    pub journal: Option<PathBuf>,
    /// Go on with the journal's finished runs rather than start again.
    pub resume: bool,
    /// Threads; every core with `None`.
    pub threads: Option<usize>,
    pub stop: &'a Stop,
    /// Says what the sweep names itself in its journal (the program and the settings: what the
    /// design does not say).
    pub context: String,
}

/// A sweep's runs, done now or found in its journal.
pub struct Outcome {
    /// The records of the part's finished runs, in the order of the runs.
    pub records: Vec<RunRecord>,
    /// The part's runs.
    pub runs: Range<usize>,
    /// How many of the records came from the journal.
    pub resumed: usize,
}

impl Outcome {
    /// Whether every run of the part is finished.
    pub fn complete(&self) -> bool {
        self.records.len() == self.runs.len()
    }
}

/// The name of the sweep in its journal: everything its records depend on.
pub fn fingerprint(sweep: &Sweep<'_>, execution: &Execution<'_>) -> String {
    let values: Vec<u8> = (sweep.design.runs.iter().flatten())
        .flat_map(|x| x.to_bits().to_le_bytes())
        .collect();
    let described = format!(
        "names={:?};quantities={:?};samples={};shard={}/{};context={}",
        sweep.design.names,
        sweep.quantity_names,
        sweep.keep_samples,
        execution.shard.index,
        execution.shard.count,
        execution.context,
    );
    format!(
        "lsdc sweep 1; {} runs; design {:016x}; sweep {:016x}",
        sweep.run_count(),
        journal::digest(&values),
        journal::digest(described.as_bytes())
    )
}

/// Runs the part of `sweep` that `execution` names (those the journal already has excepted),
/// `progress` told of every finished run (done, of how many).
pub fn execute(
    sweep: &Sweep<'_>,
    execution: &Execution<'_>,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Outcome, String> {
    let runs = execution.shard.runs(sweep.run_count());
    let fingerprint = fingerprint(sweep, execution);
    let (mut journal, mut finished) = match &execution.journal {
        None => (None, BTreeMap::new()),
        Some(path) if execution.resume => {
            let (journal, finished) = Journal::resume(path, &fingerprint)?;
            (Some(journal), finished)
        }
        Some(path) => (Some(Journal::create(path, &fingerprint)?), BTreeMap::new()),
    };
    finished.retain(|run, _| runs.contains(run));
    let resumed = finished.len();
    let pending: Vec<usize> = runs.clone().filter(|r| !finished.contains_key(r)).collect();
    progress(finished.len(), runs.len());
    let mut written = Ok(());
    run_all(
        sweep,
        &pending,
        execution.threads,
        execution.stop,
        &mut |record| {
            if let (Some(journal), Ok(())) = (&mut journal, &written) {
                written = journal.append(&record);
            }
            finished.insert(record.run, record);
            progress(finished.len(), runs.len());
        },
    )?;
    written?;
    let outcome = Outcome {
        records: finished.into_values().collect(),
        runs,
        resumed,
    };
    if let (true, Some(journal)) = (outcome.complete(), journal) {
        journal.remove()?;
    }
    Ok(outcome)
}

/// What [`gather`] merged.
#[derive(Debug)]
pub struct Gathered {
    pub table: Table,
    /// Whether the parts are tables of samples (`--samples`) rather than of runs.
    pub samples: bool,
}

/// Merges the files of a sweep's parts (its shards' `-o` files, or their `--samples` files, in
/// any order) into the table of the whole sweep: the rows in the order of the runs. An error
/// when the parts' columns differ, a run is in two parts, or (for runs) runs are missing.
pub fn gather(parts: &[PathBuf]) -> Result<Gathered, String> {
    let mut tables = Vec::new();
    for path in parts {
        let peek = Table::read(path, runs_column_kind).map_err(|e| in_file(path, &e))?;
        let samples = !peek.names().contains(&"status");
        let table = match samples {
            true => Table::read(path, samples_column_kind).map_err(|e| in_file(path, &e))?,
            false => peek,
        };
        tables.push((format!("`{}`", path.display()), table));
    }
    gather_tables(tables)
}

/// Merges the tables of a sweep's parts, each with how errors name it (its file), as
/// [`gather`] merges their files.
pub fn gather_tables(tables: Vec<(String, Table)>) -> Result<Gathered, String> {
    let kind = |table: &Table| !table.names().contains(&"status");
    for (name, table) in &tables {
        if table.names().first() != Some(&"run") {
            return Err(format!(
                "{name}: not a sweep's table (its first column is not `run`)"
            ));
        }
    }
    let Some((first_name, first)) = tables.first() else {
        return Err("no part to gather".to_string());
    };
    let (first_name, samples) = (first_name.clone(), kind(first));
    // Which part holds each run: a run in two parts is an error.
    let mut owner: BTreeMap<i64, String> = BTreeMap::new();
    let mut whole: Option<Table> = None;
    for (name, table) in tables {
        if kind(&table) != samples {
            return Err(format!(
                "{first_name} and {name} are not the same kind of table (runs and samples)"
            ));
        }
        for run in table
            .runs()
            .into_iter()
            .collect::<std::collections::BTreeSet<_>>()
        {
            if let Some(other) = owner.insert(run, name.clone()) {
                return Err(format!(
                    "run {run} is in {other} and in {name}: the same shard given twice?"
                ));
            }
        }
        match &mut whole {
            None => whole = Some(table),
            Some(whole) => whole
                .append(table)
                .map_err(|why| format!("{name} cannot join {first_name}: {why}"))?,
        }
    }
    let whole = whole.unwrap_or(Table {
        columns: Vec::new(),
    });
    if !samples {
        if let Some(missing) = (0..owner.len() as i64).find(|r| !owner.contains_key(r)) {
            return Err(format!(
                "run {missing} is in no part: a shard is missing (or has not finished)"
            ));
        }
    }
    let runs = whole.runs();
    let mut order: Vec<usize> = (0..runs.len()).collect();
    // Stable: within a run, its samples keep their order.
    order.sort_by_key(|&i| runs[i]);
    Ok(Gathered {
        table: whole.reordered(&order),
        samples,
    })
}

fn in_file(path: &Path, why: &str) -> String {
    format!("`{}`: {why}", path.display())
}
