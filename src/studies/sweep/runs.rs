//! The runs of a sweep: each name of the design is an initial value (`swing.q`, its rate
//! `swing.q'`) or a value of the program (an unknown or a `given` value, as `--set` names it).
//! Where only initial values of a mechanism without loops or drives vary, one prepared
//! mechanism serves every run (each starts from its own state, `run_from_with`); where values
//! of the program vary, or initial values of a mechanism whose loops must be assembled, each
//! run prepares the shared elaborated mechanism with its values, as `lsdc simulate --set`
//! would. Either way a run owns its scratch, and its record depends on nothing but its values:
//! the same whatever the thread that runs it.

use std::collections::HashMap;
use std::panic::{self, AssertUnwindSafe};
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::diag::Diagnostic;
use crate::elab::mechanism::{InitialValue, Mechanism};
use crate::elab::value::{num, JoinId};
use crate::integrate::Interrupt;
use crate::kinematics::unknowns::{unknown_values, Override};
use crate::prepare::settings::SettingsChanges;
use crate::prepare::{prepare, Prepared, Settings};
use crate::simulate::run::{output_names_of, run_from_with, RunOptions, Sample, Start};
use crate::topology::{self, notation};

use super::design::Design;
use super::record::{RunRecord, Status};

/// What a varied name sets (a sensitivity's parameter names the same).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// The initial value of a declared coordinate (`order` 0) or of its rate (1).
    Initial {
        join: JoinId,
        coordinate: usize,
        order: u32,
    },
    /// A value of the program, given to `prepare` as `--set NAME=VALUE` would.
    Value,
}

/// Why a run's values cannot be prepared: errors in the program (a loop that cannot be
/// assembled with them, say), or settings that cannot be used.
#[derive(Debug)]
pub enum PrepareError {
    Program(Vec<Diagnostic>),
    Settings(String),
}

impl PrepareError {
    /// On one line: each error's code and message.
    fn summary(&self) -> String {
        match self {
            PrepareError::Program(diagnostics) => (diagnostics.iter().filter(|d| d.is_error()))
                .map(|d| format!("{}: {}", d.code, d.message))
                .collect::<Vec<_>>()
                .join("; "),
            PrepareError::Settings(why) => why.clone(),
        }
    }
}

impl From<Vec<Diagnostic>> for PrepareError {
    fn from(diagnostics: Vec<Diagnostic>) -> PrepareError {
        PrepareError::Program(diagnostics)
    }
}

/// A sweep ready to run: the mechanism, the values and settings every run shares, the design.
pub struct Sweep<'m> {
    mechanism: &'m Mechanism,
    overrides: Vec<Override>,
    changes: SettingsChanges,
    pub design: Design,
    targets: Vec<Target>,
    /// The one prepared mechanism every run starts from, where no run needs its own.
    shared: Option<Prepared>,
    /// The columns each sample contributes (`quantity_names`).
    pub quantity_names: Vec<String>,
    /// Whether a record keeps every sample of its run (`--samples`).
    pub keep_samples: bool,
    /// Turns the prepared mechanism a run uses (shared or its own) into what the command asks
    /// for (`--planar`, say) before it runs.
    adjust: fn(&mut Prepared),
}

/// The columns of a sample in a sweep's results, as `lsdc simulate`'s CSV names them: the
/// declared coordinates, their rates (`name'`), the energies, then the program's outputs.
pub fn quantity_names(prepared: &Prepared) -> Vec<String> {
    let coordinates = prepared.coordinate_names.iter().cloned();
    let rates = prepared.coordinate_names.iter().map(|n| format!("{n}'"));
    let energies = ["kinetic_energy", "potential_energy"].map(String::from);
    (coordinates.chain(rates).chain(energies))
        .chain(output_names_of(prepared))
        .collect()
}

/// A sample's values in the order of [`quantity_names`] (the potential energy NaN where it
/// is unknown).
fn quantities(sample: &Sample) -> impl Iterator<Item = f64> + '_ {
    (sample.coordinates.iter().chain(&sample.rates).copied())
        .chain([
            sample.kinetic_energy,
            sample.potential_energy.unwrap_or(f64::NAN),
        ])
        .chain(sample.outputs.iter().copied())
}

impl<'m> Sweep<'m> {
    /// Checks the design's names against the mechanism and prepares what the runs share.
    /// `overrides` are the values every run takes (`--set`), `changes` the settings' changes.
    pub fn new(
        mechanism: &'m Mechanism,
        overrides: Vec<Override>,
        changes: SettingsChanges,
        design: Design,
        keep_samples: bool,
        adjust: fn(&mut Prepared),
    ) -> Result<Sweep<'m>, PrepareError> {
        let coordinates = coordinate_targets(mechanism);
        let targets: Vec<Target> = (design.names.iter())
            .map(|name| coordinates.get(name).copied().unwrap_or(Target::Value))
            .collect();
        // A name that is neither a coordinate nor a value of the program is an error now,
        // with the suggestions `--set` gives, not a failure of every run.
        let topology = topology::build(mechanism)?;
        let generated = notation::unknown_names(mechanism, &topology);
        let named: Vec<Override> = (design.names.iter().zip(&targets))
            .filter(|(_, target)| **target == Target::Value)
            .map(|(name, _)| Override {
                name: name.clone(),
                value: 0.0,
            })
            .collect();
        unknown_values(mechanism, &generated, &named)?;
        let mut sweep = Sweep {
            mechanism,
            overrides,
            changes,
            design,
            targets,
            shared: None,
            quantity_names: Vec::new(),
            keep_samples,
            adjust,
        };
        // The columns come from the first run that prepares; where none does, the first
        // one's diagnostics say why.
        let mut first_error = None;
        for index in 0..sweep.design.runs.len() {
            match sweep.prepare_run(index) {
                Ok(prepared) => {
                    sweep.quantity_names = quantity_names(&prepared);
                    if sweep.shares_one_preparation(&prepared) {
                        sweep.shared = Some(prepared);
                    }
                    return Ok(sweep);
                }
                Err(error) => {
                    let settings = matches!(error, PrepareError::Settings(_));
                    first_error.get_or_insert(error);
                    // Runs with values of their own may prepare where this one cannot.
                    if settings || sweep.targets.is_empty() {
                        break;
                    }
                }
            }
        }
        match first_error {
            Some(error) => Err(error),
            None => Ok(sweep),
        }
    }

    /// Whether every run can start from one prepared mechanism: no value of the program
    /// varies, and no varied initial value needs the loops assembled or the drives applied.
    fn shares_one_preparation(&self, prepared: &Prepared) -> bool {
        let model = &prepared.model;
        let assembled = model.has_loops() || !model.drives.is_empty();
        let assembled = assembled || !model.position_drives.is_empty();
        !self.targets.contains(&Target::Value) && (self.targets.is_empty() || !assembled)
    }

    /// Whether the runs share one prepared mechanism.
    pub fn is_shared(&self) -> bool {
        self.shared.is_some()
    }

    /// The prepared mechanism every run starts from, where they share one.
    pub fn shared(&self) -> Option<&Prepared> {
        self.shared.as_ref()
    }

    /// Lets the runs evaluate their equations of motion as native code (`sweep --compiled`):
    /// compiled once, for the one prepared mechanism they share, with the warnings of
    /// `simulate --compiled`. Runs that each prepare the mechanism with values of their own
    /// would each need their own native code (the values are constants in it): W0904 says so,
    /// and they run without it.
    pub fn attach_native(&mut self) -> Vec<Diagnostic> {
        match &mut self.shared {
            Some(shared) => crate::simulate::compiled::attach_with_warnings(shared, self.mechanism),
            None => vec![Diagnostic::warning(
                "W0904",
                "--compiled: the runs do not share one prepared mechanism (a value of the program varies, or initial values of a mechanism that must be assembled), and native code is made for one; the runs evaluate the equations without it",
            )
            .help("vary only initial values of a tree for native code in every run")],
        }
    }

    /// The number of runs of the design.
    pub fn run_count(&self) -> usize {
        self.design.runs.len()
    }

    /// The run's own preparation: the mechanism with its initial values, prepared with its
    /// values of the program.
    fn prepare_run(&self, index: usize) -> Result<Prepared, PrepareError> {
        let values = &self.design.runs[index];
        let mut overrides = self.overrides.clone();
        let mut initial = Vec::new();
        for ((name, target), &value) in self.design.names.iter().zip(&self.targets).zip(values) {
            match *target {
                Target::Value => overrides.push(Override {
                    name: name.clone(),
                    value,
                }),
                Target::Initial {
                    join,
                    coordinate,
                    order,
                } => initial.push((join, coordinate, order, value)),
            }
        }
        let mut prepared = match initial.is_empty() {
            true => prepare(self.mechanism, &overrides, &Settings::default()),
            false => {
                let mechanism = with_initial_values(self.mechanism, &initial);
                prepare(&mechanism, &overrides, &Settings::default())
            }
        }?;
        let changed = prepared.settings.apply(&self.changes);
        changed.map_err(|e| PrepareError::Settings(e.to_string()))?;
        (self.adjust)(&mut prepared);
        Ok(prepared)
    }

    /// Runs the `index`-th run to its end, a failure or `interrupt`; a panic inside the run is
    /// its failure, not the sweep's.
    pub fn run(&self, index: usize, interrupt: Option<&Interrupt>) -> RunRecord {
        let outcome =
            panic::catch_unwind(AssertUnwindSafe(|| self.run_unguarded(index, interrupt)));
        outcome.unwrap_or_else(|payload| {
            let why = (payload.downcast_ref::<&str>().map(|s| s.to_string()))
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            RunRecord::failed_to_prepare(
                index,
                &self.design.runs[index],
                format!("internal error (please report it): {why}"),
            )
        })
    }

    fn run_unguarded(&self, index: usize, interrupt: Option<&Interrupt>) -> RunRecord {
        let values = &self.design.runs[index];
        let own;
        let (prepared, start) = match &self.shared {
            Some(shared) => {
                let (mut coordinates, mut rates) =
                    (shared.coordinates.clone(), shared.rates.clone());
                for (target, &value) in self.targets.iter().zip(values) {
                    if let Target::Initial {
                        join,
                        coordinate,
                        order,
                    } = *target
                    {
                        let Some(offset) = shared.model.declared_offset(join) else {
                            continue;
                        };
                        match order {
                            0 => coordinates[offset + coordinate] = value,
                            _ => rates[offset + coordinate] = value,
                        }
                    }
                }
                (shared, (coordinates, rates))
            }
            None => match self.prepare_run(index) {
                Ok(prepared) => {
                    own = prepared;
                    let start = (own.coordinates.clone(), own.rates.clone());
                    (&own, start)
                }
                Err(error) => return RunRecord::failed_to_prepare(index, values, error.summary()),
            },
        };
        let mut summary = Summary::new(self.quantity_names.len(), self.keep_samples);
        let options = RunOptions {
            keep_samples: false,
            interrupt: interrupt.cloned(),
        };
        let start = Start {
            coordinates: &start.0,
            rates: &start.1,
        };
        let simulation = run_from_with(prepared, &start, &options, &mut |sample| {
            summary.add(sample)
        });
        let report = &simulation.report;
        let status = match (&report.interrupted, &report.failure) {
            (Some(_), _) => Status::Interrupted,
            (None, Some(_)) => Status::Failed,
            (None, None) => Status::Ok,
        };
        RunRecord {
            run: index,
            values: values.clone(),
            status,
            failure_time: report.failure.as_ref().map(|f| f.time),
            failure: report.failure.as_ref().map(|f| f.message.clone()),
            steps: Some(report.steps as u64),
            end_time: summary.end_time,
            end: summary.end,
            min: summary.min,
            max: summary.max,
            samples: summary.samples,
        }
    }
}

/// The initial values `J.c` and `J.c'` of every declared coordinate, by name.
pub fn coordinate_targets(mechanism: &Mechanism) -> HashMap<String, Target> {
    let mut targets = HashMap::new();
    for (index, join) in mechanism.joins.iter().enumerate() {
        let id = JoinId(index as u32);
        let name = mechanism.join_name(id);
        let link = mechanism.link(join.link);
        for (coordinate, parameter) in link.coordinates.iter().enumerate() {
            for (order, prime) in [(0, ""), (1, "'")] {
                let target = Target::Initial {
                    join: id,
                    coordinate,
                    order,
                };
                targets.insert(format!("{name}.{}{prime}", &**parameter), target);
            }
        }
    }
    targets
}

/// A copy of `mechanism` whose `initial` declarations give these values (join, coordinate,
/// order, value): a declared one keeps its `fixed` and `guess`, a new one is as `initial`
/// writes it.
pub fn with_initial_values(
    mechanism: &Mechanism,
    values: &[(JoinId, usize, u32, f64)],
) -> Mechanism {
    let mut mechanism = mechanism.clone();
    for &(join, coordinate, order, value) in values {
        let declared = (mechanism.initial.iter_mut())
            .find(|i| i.join == join && i.coordinate == coordinate && i.order == order);
        match declared {
            Some(initial) => initial.value = num(value),
            None => {
                let span = mechanism.join(join).span;
                mechanism.initial.push(InitialValue {
                    join,
                    coordinate,
                    order,
                    value: num(value),
                    fixed: false,
                    guess: false,
                    span,
                });
            }
        }
    }
    mechanism
}

/// What a run keeps of its samples: the last, the extremes of each quantity, and all of them
/// when asked.
struct Summary {
    end_time: Option<f64>,
    end: Vec<Option<f64>>,
    min: Vec<Option<f64>>,
    max: Vec<Option<f64>>,
    samples: Vec<Vec<f64>>,
    keep_samples: bool,
}

impl Summary {
    fn new(quantities: usize, keep_samples: bool) -> Summary {
        Summary {
            end_time: None,
            end: vec![None; quantities],
            min: vec![None; quantities],
            max: vec![None; quantities],
            samples: Vec::new(),
            keep_samples,
        }
    }

    fn add(&mut self, sample: &Sample) {
        self.end_time = Some(sample.time);
        for (k, x) in quantities(sample).enumerate().take(self.end.len()) {
            self.end[k] = Some(x);
            // NaN (an unknown potential energy) is no extreme.
            if !x.is_nan() {
                self.min[k] = Some(self.min[k].map_or(x, |m| m.min(x)));
                self.max[k] = Some(self.max[k].map_or(x, |m| m.max(x)));
            }
        }
        if self.keep_samples {
            self.samples.push(
                std::iter::once(sample.time)
                    .chain(quantities(sample))
                    .collect(),
            );
        }
    }
}

/// What stops a sweep between runs: a signal (the flag a run also reads between its steps) or
/// a limit on the runs this process starts.
pub struct Stop {
    pub interrupt: Option<Interrupt>,
    pub most_runs: Option<usize>,
    started: AtomicUsize,
}

impl Stop {
    pub fn new(interrupt: Option<Interrupt>, most_runs: Option<usize>) -> Stop {
        Stop {
            interrupt,
            most_runs,
            started: AtomicUsize::new(0),
        }
    }

    /// Whether another run may start (and counts it).
    fn may_start(&self) -> bool {
        let signalled = (self.interrupt.as_ref()).is_some_and(|i| i.requested().is_some());
        let started = self.started.fetch_add(1, Ordering::Relaxed);
        !signalled && self.most_runs.is_none_or(|most| started < most)
    }

    /// The signal that stopped the sweep, if any.
    pub fn signal(&self) -> Option<usize> {
        self.interrupt.as_ref().and_then(Interrupt::requested)
    }
}

/// Runs `runs` (indices of the design) on `threads` threads (every core with `None`), handing
/// each finished run's record to `on_record` on the calling thread as it comes. A run a signal
/// interrupts is not handed over: it was not finished.
pub fn run_all(
    sweep: &Sweep<'_>,
    runs: &[usize],
    threads: Option<usize>,
    stop: &Stop,
    on_record: &mut dyn FnMut(RunRecord),
) -> Result<(), String> {
    use rayon::prelude::*;
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(threads) = threads {
        builder = builder.num_threads(threads);
    }
    let pool = builder
        .build()
        .map_err(|e| format!("cannot start the threads: {e}"))?;
    let (sender, receiver) = std::sync::mpsc::channel();
    std::thread::scope(|scope| {
        scope.spawn(move || {
            pool.install(|| {
                // One run at a time per task: runs take very different times.
                runs.par_iter()
                    .with_max_len(1)
                    .for_each_with(sender, |sender, &index| {
                        if !stop.may_start() {
                            return;
                        }
                        let record = sweep.run(index, stop.interrupt.as_ref());
                        if record.status != Status::Interrupted {
                            let _ = sender.send(record);
                        }
                    });
            });
        });
        for record in receiver {
            on_record(record);
        }
    });
    Ok(())
}
