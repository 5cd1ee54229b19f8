//! The library's entry points, in the order a program goes through them:
//!
//! 1. [`Program::from_file`] or [`Program::from_text`]: LSD text (or a URDF file) loaded with its
//!    imports, checked and elaborated; its [`diagnostics`](Program::diagnostics) and, when it has
//!    no errors, its [`Mechanism`].
//! 2. [`Program::prepare`]: values for the unknowns, the dynamic model, the initial state and the
//!    settings, as `lsdc simulate` prepares them: a [`Prepared`] simulation.
//!    [`Program::output_frames`] adds the state of named frames to its outputs.
//! 3. [`run`]: the integration, every sample handed to a sink as it is computed, and the
//!    [`Simulation`] with its report (its warnings by [`Report::warnings`]); [`run_with`] with
//!    options. [`evaluate`] gives the dynamics at chosen states instead.
//! 4. [`Simulator`]: the same run owned by its caller and advanced step by step, with efforts
//!    applied from Rust between steps (see below).
//! 5. The studies a binding to another language needs (the Python package, `python/`):
//!    [`StateBatch`], RNEA, CRBA, ABA and the bodies' Jacobians at states given as rows of flat
//!    arrays; [`Program::linearize`], the linear model about an operating point (`lsdc
//!    linearize`); [`Program::sweep`], the runs of a sweep's design or of one of its shards
//!    (`lsdc sweep`), and [`gather`], the shards' tables merged into the whole sweep's.
//!
//! Every failure is an [`Error`]; errors in the program are [`Diagnostic`]s, which
//! [`Program::render`] shows as the command line does.
//!
//! ```
//! use lsdc::api::{run, Program, SettingsChanges};
//!
//! let program = Program::from_file("examples/pendulum.lsd", &Default::default())?;
//! let changes = SettingsChanges { duration: Some(0.5), ..Default::default() };
//! let prepared = program.prepare(&[], &changes)?;
//! let mut times = Vec::new();
//! let simulation = run(&prepared, &mut |sample| times.push(sample.time));
//! assert!(simulation.report.failure.is_none());
//! assert_eq!(times.last(), Some(&0.5));
//! # Ok::<(), lsdc::api::Error>(())
//! ```
//!
//! # Stepping a simulation from Rust
//!
//! A [`Simulator`] holds one run: [`step`](Simulator::step) takes one step of the integrator
//! the settings name, [`advance_to`](Simulator::advance_to) steps to a time and lands on it;
//! between steps the caller reads the state ([`time`](Simulator::time),
//! [`coordinates`](Simulator::coordinates), [`sample`](Simulator::sample)) and sets efforts
//! along the velocities it named as inputs: held values ([`set_inputs`](Simulator::set_inputs),
//! a zero-order hold, as a sampled controller applies its commands) and a law of the time and
//! the declared coordinates and rates ([`set_law`](Simulator::set_law)), which every evaluation
//! of the equations of motion evaluates, at every stage of every step, as it evaluates the
//! program's own efforts. Closed through a law, a loop gives the motion the same law written in
//! LSD gives, to round-off; this one is a PD controller on the bundled pendulum:
//!
//! ```
//! use lsdc::api::{run, Program, SettingsChanges, Simulator};
//!
//! const KP: f64 = 20.0;
//! const KD: f64 = 3.0;
//! const TARGET: f64 = 0.5;
//! let changes = SettingsChanges { duration: Some(2.0), ..Default::default() };
//!
//! // The pendulum, its torque along `swing.q` computed in Rust at every stage.
//! let pendulum = Program::from_file("examples/pendulum.lsd", &Default::default())?;
//! let pendulum = pendulum.prepare(&[], &changes)?;
//! let mut simulator = Simulator::new(&pendulum, &["swing.q"])?;
//! simulator.set_law(|_t, q, v, torque| torque[0] = -KP * (q[0] - TARGET) - KD * v[0]);
//! simulator.advance_to(2.0)?;
//! let (from_rust, report) = simulator.finish();
//! assert!(report.failure.is_none());
//!
//! // The same law written in LSD, as the torque of the pendulum's revolute joint.
//! let text = "
//!     import joints;
//!     let rod = body mass = 1.2, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.001] end;
//!     let pd = link(q) dof = q || [1, 0, 0], torque = [-20 * (q - 0.5) - 3 * q', 0, 0] end;
//!     join earth and rod with pd as swing;
//!     apply force value = [0, 0, -9.81 * rod.mass], body = earth end on rod.iframe;
//!     initial swing.q = pi / 3;
//!     simulate duration = 5, output = 0.05, integrator = dopri5, tolerance = 1e-10 end;";
//! let in_lsd = Program::from_text("pd.lsd", text, None, &Default::default());
//! let in_lsd = run(&in_lsd.prepare(&[], &changes)?, &mut |_| {});
//!
//! assert_eq!(from_rust.len(), in_lsd.samples.len());
//! for (rust, lsd) in from_rust.iter().zip(&in_lsd.samples) {
//!     assert_eq!(rust.time, lsd.time);
//!     assert!((rust.coordinates[0] - lsd.coordinates[0]).abs() <= 1e-12);
//!     assert!((rust.rates[0] - lsd.rates[0]).abs() <= 1e-12);
//! }
//! // The controller holds the rod near its target, which gravity pulls it below.
//! assert!((from_rust.last().unwrap().coordinates[0] - TARGET).abs() < 0.15);
//! # Ok::<(), lsdc::api::Error>(())
//! ```

use std::fmt;
use std::path::Path;

use crate::diag::render;
pub use crate::diag::Diagnostic;
use crate::driver::{self, Compilation};
/// How a run holds a mechanism with loops on its constraints (`lsdc simulate --stabilisation`).
pub use crate::dynamics::loops::Stabilisation;
pub use crate::elab::Mechanism;
/// The flag that stops a [`Simulator`] or a [`run_with`] between two steps (`lsdc simulate`
/// sets it on SIGINT and SIGTERM), so that a caller can name it.
pub use crate::integrate::Interrupt;
pub use crate::kinematics::unknowns::Override;
pub use crate::load::{LoadError, LoadOptions};
use crate::prepare::outputs::Outputs;
pub use crate::prepare::settings::{Integrator, Settings, SettingsChanges, SettingsError};
pub use crate::prepare::Prepared;
/// The equations of a tree without events evaluated at states an outside integrator chooses
/// (FMI model exchange), and why a mechanism's cannot be.
pub use crate::simulate::model_exchange::{refusal as model_exchange_refusal, Equations};
/// The names of a run's outputs (the program's `output`s, then the frames'), of its columns'
/// reactions (with `reactions` in the settings): the names of a [`Simulation`]'s columns.
pub use crate::simulate::run::{
    output_names_of as output_names, reaction_names_of as reaction_names,
};
pub use crate::simulate::run::{
    run_from, Report, RunFailure, RunOptions, Sample, Simulation, Simulator, Start,
};
pub use crate::source::SourceMap;
pub use crate::studies::batch::{parse_states, Evaluation, StateInput, StatesError};
/// What to linearise: the operating point, the inputs, the independent coordinates.
pub use crate::studies::linearize::Request as LinearizeRequest;
pub use crate::studies::linearize::{Linearization, LinearizeError, OperatingPoint};
pub use crate::studies::state_batch::StateBatch;
/// Every combination of the axes, the first varying slowest (`lsdc sweep --grid`).
pub use crate::studies::sweep::design::grid as sweep_grid;
/// The runs of a CSV text (`lsdc sweep --values`).
pub use crate::studies::sweep::design::list as sweep_list;
/// The runs drawn from distributions (`lsdc sweep --vary ... --sample N`).
pub use crate::studies::sweep::design::sample as sweep_sample;
/// A sweep's design: the names it varies and a row of values per run, made by [`sweep_grid`],
/// [`sweep_list`] or [`sweep_sample`].
pub use crate::studies::sweep::design::Design as SweepDesign;
pub use crate::studies::sweep::design::{GridAxis, ListError, Sampling};
pub use crate::studies::sweep::distribution::Distribution;
/// A sweep's table of runs (its columns as `lsdc sweep -o` writes them).
pub use crate::studies::sweep::table::Table as SweepTable;
pub use crate::studies::sweep::table::{Cells, Column, TableFormat};
pub use crate::studies::sweep::Shard;

/// Why a step of the library's pipeline failed.
#[derive(Debug)]
pub enum Error {
    /// A root file cannot be read.
    Load(LoadError),
    /// The program has errors, or cannot be prepared for simulation (a value is missing, a loop
    /// cannot be assembled, …): the diagnostics say where and why.
    Program(Vec<Diagnostic>),
    /// The settings asked for cannot be used.
    Settings(SettingsError),
    /// The states to evaluate cannot be read, or one of them cannot be evaluated.
    States(StatesError),
    /// A frame asked for by name cannot be found, or followed by the outputs.
    Frame(String),
    /// A [`Simulator`] cannot start, or its run stopped: when and why.
    Run(RunFailure),
    /// A study cannot be done as asked (a linearisation's inputs, a sweep's settings, shards
    /// that do not make a sweep): why.
    Study(String),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Load(error) => error.fmt(f),
            Error::Settings(error) => error.fmt(f),
            Error::States(error) => error.fmt(f),
            Error::Frame(message) | Error::Study(message) => f.write_str(message),
            Error::Run(failure) => write!(f, "at t = {}: {}", failure.time, failure.message),
            Error::Program(diagnostics) => {
                let errors: Vec<String> = diagnostics
                    .iter()
                    .filter(|d| d.is_error())
                    .map(Diagnostic::to_string)
                    .collect();
                write!(f, "{}", errors.join("; "))
            }
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Load(error) => Some(error),
            Error::Settings(error) => Some(error),
            Error::States(error) => Some(error),
            Error::Program(_) | Error::Frame(_) | Error::Run(_) | Error::Study(_) => None,
        }
    }
}

impl From<LoadError> for Error {
    fn from(error: LoadError) -> Error {
        Error::Load(error)
    }
}

impl From<SettingsError> for Error {
    fn from(error: SettingsError) -> Error {
        Error::Settings(error)
    }
}

impl From<StatesError> for Error {
    fn from(error: StatesError) -> Error {
        Error::States(error)
    }
}

impl From<RunFailure> for Error {
    fn from(failure: RunFailure) -> Error {
        Error::Run(failure)
    }
}

impl From<Vec<Diagnostic>> for Error {
    fn from(diagnostics: Vec<Diagnostic>) -> Error {
        Error::Program(diagnostics)
    }
}

/// A program loaded, checked and elaborated, with everything its phases reported.
pub struct Program {
    compilation: Compilation,
}

impl Program {
    /// Loads a `.lsd` (or `.urdf`) file and what it imports, then checks and elaborates it.
    /// Only a file that cannot be read is an error here; errors in the program are in
    /// [`diagnostics`](Program::diagnostics).
    ///
    /// ```
    /// let program = lsdc::api::Program::from_file("examples/four_bar.lsd", &Default::default())?;
    /// assert!(!program.has_errors());
    /// assert!(program.mechanism()?.joins.len() >= 4);
    /// # Ok::<(), lsdc::api::Error>(())
    /// ```
    pub fn from_file(path: impl AsRef<Path>, options: &LoadOptions) -> Result<Program, Error> {
        // Nothing here reads the syntax tree again: it is freed as the mechanism is elaborated.
        let compilation = driver::compile_files_lean(&[path.as_ref().to_path_buf()], options)?;
        Ok(Program { compilation })
    }

    /// Checks and elaborates a program given as text; `name` is how diagnostics name it, and
    /// its relative imports are looked up in `dir` (then the library path).
    ///
    /// ```
    /// use lsdc::api::Program;
    ///
    /// let program = Program::from_text("typo.lsd", "let b = body mass = 1 end; join earth and c with 1;", None, &Default::default());
    /// assert!(program.has_errors());
    /// let text = program.render();
    /// assert!(text.contains("unknown name `c`") && text.contains("typo.lsd:1:"));
    /// ```
    pub fn from_text(name: &str, text: &str, dir: Option<&Path>, options: &LoadOptions) -> Program {
        Program {
            compilation: driver::compile_text(name, text, dir, options),
        }
    }

    /// The names of the scenes the program declares (`scene NAME = ... end`), in order.
    pub fn scene_names(&self) -> &[String] {
        &self.compilation.workspace.scenes.names
    }

    /// The scene the program was compiled for: the one its options name, else its first.
    pub fn scene(&self) -> Option<&str> {
        self.compilation.workspace.scenes.selected.as_deref()
    }

    /// Errors and warnings of every phase, in the order found.
    pub fn diagnostics(&self) -> &[Diagnostic] {
        &self.compilation.diagnostics
    }

    /// Whether a phase reported an error (warnings alone leave a usable mechanism).
    pub fn has_errors(&self) -> bool {
        self.compilation.has_errors()
    }

    /// The program's diagnostics as the command line prints them: file, line, column, the
    /// source lines and the help.
    pub fn render(&self) -> String {
        self.render_diagnostics(self.diagnostics())
    }

    /// Other diagnostics about this program (from [`prepare`](Program::prepare), say) rendered
    /// against its sources, with the import that brought a library in.
    pub fn render_diagnostics(&self, diagnostics: &[Diagnostic]) -> String {
        render::to_text(self.sources(), &self.in_context(diagnostics))
    }

    /// Diagnostics about this program with the import that brought a library in, to render
    /// against its [`sources`](Program::sources) (as text or JSON, `diag::render`).
    pub fn in_context(&self, diagnostics: &[Diagnostic]) -> Vec<Diagnostic> {
        let mut diagnostics = diagnostics.to_vec();
        for diagnostic in &mut diagnostics {
            self.compilation.workspace.add_import_context(diagnostic);
        }
        diagnostics
    }

    /// The program's source files, which its diagnostics point into.
    pub fn sources(&self) -> &SourceMap {
        &self.compilation.workspace.sources
    }

    /// The mechanism the program describes, when it has no errors.
    pub fn mechanism(&self) -> Result<&Mechanism, Error> {
        self.compilation
            .mechanism
            .as_ref()
            .ok_or_else(|| Error::Program(self.compilation.diagnostics.clone()))
    }

    /// Prepares the simulation as `lsdc simulate` does: `values` give unknowns their values by
    /// name (as `--set NAME=VALUE`), `changes` change the settings of the program's `simulate`
    /// declaration. A value the motion needs and nobody gave is an error that names it.
    ///
    /// ```
    /// use lsdc::api::{Error, Override, Program, SettingsChanges};
    ///
    /// let text = "import joints; let k = ?s; let b = body mass = 1, iframe = 0, inertia = [1, 1, 1] end;
    ///             join earth and b with prismatic([1, 0, 0]) as slide;
    ///             apply force value = [-k * slide.q, 0, 0], body = earth end on b;
    ///             initial slide.q = 0.1;";
    /// let program = Program::from_text("spring.lsd", text, None, &Default::default());
    /// let missing = program.prepare(&[], &Default::default());
    /// assert!(matches!(missing, Err(Error::Program(ref d)) if d[0].message.contains("no value for `k`")));
    /// let k = Override { name: "k".to_string(), value: 4.0 };
    /// let prepared = program.prepare(&[k], &SettingsChanges { duration: Some(2.0), ..Default::default() })?;
    /// assert_eq!(prepared.settings.duration, 2.0);
    /// # Ok::<(), Error>(())
    /// ```
    pub fn prepare(
        &self,
        values: &[Override],
        changes: &SettingsChanges,
    ) -> Result<Prepared, Error> {
        let mut prepared =
            crate::prepare::prepare(self.mechanism()?, values, &Settings::default())?;
        prepared.settings.apply(changes)?;
        Ok(prepared)
    }

    /// Prepares a run (`lsdc simulate`): as [`Program::prepare`], except that a scene that asks
    /// only for kinematics (every coordinate driven or closed by the loops, nothing read that
    /// needs a mass or an effort, no reactions asked for) is prepared without its dynamics and
    /// runs by assembly at each output (`prepare::kinematic_scene`; `prepared.kinematics_only`,
    /// and the scene's model says so in the report).
    pub fn prepare_run(
        &self,
        values: &[Override],
        changes: &SettingsChanges,
    ) -> Result<Prepared, Error> {
        let mechanism = self.mechanism()?;
        if !changes.reactions {
            let defaults = Settings::default();
            let kinematic = crate::prepare::kinematic_scene::prepare(mechanism, values, &defaults);
            if let Some(mut prepared) = kinematic {
                prepared.settings.apply(changes)?;
                return Ok(prepared);
            }
        }
        self.prepare(values, changes)
    }

    /// Prepares what a study of kinematics alone reads (`lsdc kinematics`, `lsdc workspace`):
    /// the mechanism's joints, loops, stops and drives without the dynamics
    /// (`prepare::prepare_kinematics`), so that no mass or effort needs a value;
    /// `prepared.model.dynamics` is false.
    pub fn prepare_kinematics(&self, values: &[Override]) -> Result<Prepared, Error> {
        Ok(crate::prepare::prepare_kinematics(
            self.mechanism()?,
            values,
        )?)
    }

    /// Adds the state of each named frame to the outputs of `prepared`, after the program's
    /// own: a frame the program names, a body's name or `earth`, 13 columns `NAME.x`, `NAME.y`,
    /// `NAME.z`, `NAME.qw` … `NAME.qz` (unit quaternion, w ≥ 0), `NAME.vx` … `NAME.wz` in the
    /// fixed frame, as `output NAME = NAME;` would (and `lsdc simulate --output-frame`).
    ///
    /// ```
    /// use lsdc::api::{run, Program, SettingsChanges};
    ///
    /// let program = Program::from_file("examples/pendulum.lsd", &Default::default())?;
    /// let mut prepared = program.prepare(&[], &SettingsChanges { duration: Some(0.5), ..Default::default() })?;
    /// program.output_frames(&mut prepared, &["rod".to_string()])?;
    /// let simulation = run(&prepared, &mut |_| {});
    /// assert_eq!(simulation.output_names[0], "rod.x");
    /// assert_eq!(simulation.samples[0].outputs.len(), 13);
    /// assert!(program.output_frames(&mut prepared, &["rdo".to_string()]).is_err());
    /// # Ok::<(), lsdc::api::Error>(())
    /// ```
    pub fn output_frames(&self, prepared: &mut Prepared, names: &[String]) -> Result<(), Error> {
        let (mechanism, model) = (self.mechanism()?, &prepared.model);
        prepared.outputs = Outputs::with_frames(mechanism, model, &prepared.kinematics, names)
            .map_err(Error::Frame)?;
        Ok(())
    }

    /// Lets `prepared` evaluate its equations of motion as native code (the generated C forward
    /// dynamics, compiled by the C compiler and cached): warnings say why where it cannot, and
    /// the runs then go on without it.
    pub fn attach_native(&self, prepared: &mut Prepared) -> Result<Vec<Diagnostic>, Error> {
        let mechanism = self.mechanism()?;
        Ok(crate::simulate::compiled::attach_with_warnings(
            prepared, mechanism,
        ))
    }
}

/// Where a diagnostic points: the file as the program names it, the line and the column (in
/// characters) of the start of its primary label, both from 1.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    pub file: String,
    pub line: usize,
    pub column: usize,
}

impl Program {
    /// Where `diagnostic` (one of this program's) points in its sources; `None` for a
    /// diagnostic about no place (a value missing from the command line, say).
    pub fn location(&self, diagnostic: &Diagnostic) -> Option<Location> {
        let span = diagnostic.primary_span()?;
        let file = self.sources().file(span.file());
        let (line, column) = file.line_column(span.start() as usize);
        Some(Location {
            file: file.name.clone(),
            line,
            column,
        })
    }

    /// As [`prepare`](Program::prepare), with `initial` values of declared coordinates by
    /// name, `JOIN.COORD` for a coordinate and `JOIN.COORD'` for its rate, as if the program's
    /// `initial` declarations said them (a declared one keeps its `fixed` or `guess`): as
    /// `lsdc sweep` varies initial values. A name that is no declared coordinate is an error
    /// that names the closest one.
    pub fn prepare_with_initial(
        &self,
        values: &[Override],
        initial: &[Override],
        changes: &SettingsChanges,
    ) -> Result<Prepared, Error> {
        use crate::studies::sweep::runs::{coordinate_targets, with_initial_values, Target};
        let mechanism = self.mechanism()?;
        let targets = coordinate_targets(mechanism);
        let mut chosen = Vec::with_capacity(initial.len());
        for value in initial {
            match targets.get(&value.name) {
                Some(&Target::Initial {
                    join,
                    coordinate,
                    order,
                }) => chosen.push((join, coordinate, order, value.value)),
                _ => {
                    let names = targets.keys().map(String::as_str);
                    let closest = crate::diag::suggest::did_you_mean(&value.name, names);
                    let hint = closest.map_or(String::new(), |c| format!(": did you mean `{c}`?"));
                    return Err(Error::Study(format!(
                        "`{}` is not a declared coordinate (`JOIN.COORD`) or its rate (`JOIN.COORD'`){hint}",
                        value.name
                    )));
                }
            }
        }
        let mechanism = with_initial_values(mechanism, &chosen);
        let mut prepared = crate::prepare::prepare(&mechanism, values, &Settings::default())?;
        prepared.settings.apply(changes)?;
        Ok(prepared)
    }

    /// The linear model of `prepared` (prepared from this program) about the operating point
    /// `request` names, as `lsdc linearize` computes it. An error in the program (a motion
    /// imposed in time, say) is located in it.
    pub fn linearize(
        &self,
        prepared: &Prepared,
        request: &LinearizeRequest,
    ) -> Result<Linearization, Error> {
        crate::studies::linearize::linearize(prepared, request).map_err(|error| {
            match self.mechanism().ok().and_then(|m| error.diagnostic(m)) {
                Some(diagnostic) => Error::Program(vec![diagnostic]),
                None => Error::Study(error.to_string()),
            }
        })
    }

    /// Runs the part `shard` of the sweep of `design` over this program, as `lsdc sweep
    /// --shard K/N` does, on `threads` threads (every core with `None`): its table of runs,
    /// the rows `lsdc sweep -o` writes for those runs (every run: [`Shard::WHOLE`]). `values`
    /// are the values every run takes (`--set`), `changes` the settings' changes.
    pub fn sweep(
        &self,
        values: &[Override],
        changes: &SettingsChanges,
        design: SweepDesign,
        shard: Shard,
        threads: Option<usize>,
    ) -> Result<SweepTable, Error> {
        use crate::studies::sweep::{self, record, runs};
        fn spatial(_: &mut Prepared) {}
        let mechanism = self.mechanism()?;
        let sweep = runs::Sweep::new(
            mechanism,
            values.to_vec(),
            changes.clone(),
            design,
            false,
            spatial,
        )
        .map_err(|error| match error {
            runs::PrepareError::Program(diagnostics) => Error::Program(diagnostics),
            runs::PrepareError::Settings(why) => Error::Study(why),
        })?;
        let stop = runs::Stop::new(None, None);
        let execution = sweep::Execution {
            shard,
            journal: None,
            resume: false,
            threads,
            stop: &stop,
            context: String::new(),
        };
        let outcome = sweep::execute(&sweep, &execution, &mut |_, _| {}).map_err(Error::Study)?;
        let names = (&sweep.design.names, &sweep.quantity_names);
        Ok(record::runs_table(names.0, names.1, &outcome.records))
    }
}

/// Merges the tables of a sweep's shards (in any order) into the whole sweep's table, as
/// `lsdc sweep gather` merges their files: the rows in the order of the runs, identical to the
/// table of the sweep run whole. An error when their columns differ, a run is in two parts or
/// in none.
pub fn gather(parts: Vec<SweepTable>) -> Result<SweepTable, Error> {
    let labelled = (parts.into_iter().enumerate())
        .map(|(k, table)| (format!("part {k}"), table))
        .collect();
    crate::studies::sweep::gather_tables(labelled)
        .map(|gathered| gathered.table)
        .map_err(Error::Study)
}

/// Reads a sweep's table of runs from the CSV text `lsdc sweep -o runs.csv` writes (each
/// column's type by its name): the table that wrote it.
pub fn sweep_table_from_csv(text: &str) -> Result<SweepTable, String> {
    SweepTable::from_csv(text, crate::studies::sweep::record::runs_column_kind)
}

/// Integrates a prepared simulation. `sink` receives every sample as soon as it is computed (to
/// stream it, draw progress or stop caring about memory); the returned [`Simulation`] holds them
/// all with the run report. A run that fails keeps the samples computed before the failure, and
/// its report says when and why.
///
/// ```
/// use lsdc::api::{run, Program, SettingsChanges};
///
/// let program = Program::from_file("examples/double_pendulum.lsd", &Default::default())?;
/// let prepared = program.prepare(&[], &SettingsChanges { duration: Some(1.0), ..Default::default() })?;
/// let mut energies = Vec::new();
/// let simulation = run(&prepared, &mut |sample| energies.push(sample.kinetic_energy));
/// assert_eq!(energies.len(), simulation.samples.len());
/// assert!(simulation.report.energy_drift.unwrap() < 1e-6);
/// # Ok::<(), lsdc::api::Error>(())
/// ```
pub fn run(prepared: &Prepared, sink: &mut dyn FnMut(&Sample)) -> Simulation {
    crate::simulate::run::run(prepared, sink)
}

/// As [`run`], with `options`: whether the simulation keeps its samples, and a flag that stops
/// the run between two steps.
pub fn run_with(
    prepared: &Prepared,
    options: &RunOptions,
    sink: &mut dyn FnMut(&Sample),
) -> Simulation {
    crate::simulate::run::run_with(prepared, options, sink)
}

/// Inverse dynamics, mass matrix, forward dynamics and the bodies' poses at each state, as
/// `lsdc eval` computes them.
///
/// ```
/// use lsdc::api::{evaluate, parse_states, Program};
///
/// let program = Program::from_file("examples/pendulum.lsd", &Default::default())?;
/// let prepared = program.prepare(&[], &Default::default())?;
/// let states = parse_states(r#"[{"q": [0.5], "v": [0.0]}]"#)?;
/// let evaluation = evaluate(&prepared, &states)?;
/// assert_eq!(evaluation.states.len(), 1);
/// # Ok::<(), lsdc::api::Error>(())
/// ```
pub fn evaluate(prepared: &Prepared, states: &[StateInput]) -> Result<Evaluation, Error> {
    crate::studies::batch::evaluate_states(prepared, states).map_err(Error::States)
}

/// As [`evaluate`], with each state's analytical derivatives (`lsdc eval --derivatives`): of
/// the inverse dynamics with respect to q and v, of the forward dynamics with respect to q, v
/// and τ, and of the mass matrix with respect to q (Carpentier & Mansard, RSS 2018).
///
/// ```
/// use lsdc::api::{evaluate_with_derivatives, parse_states, Program};
///
/// let program = Program::from_file("examples/pendulum.lsd", &Default::default())?;
/// let prepared = program.prepare(&[], &Default::default())?;
/// let states = parse_states(r#"[{"q": [0.5], "v": [0.0], "a": [0.0]}]"#)?;
/// let evaluation = evaluate_with_derivatives(&prepared, &states)?;
/// let derivatives = evaluation.states[0].derivatives.as_ref().expect("derivatives");
/// // Holding the rod (1.2 kg, centre 0.5 m below the axis) takes τ = m g l sin q.
/// let dtau_dq = derivatives.rnea.as_ref().expect("a was given").dq[0][0];
/// assert!((dtau_dq - 1.2 * 9.81 * 0.5 * 0.5f64.cos()).abs() < 1e-12);
/// # Ok::<(), lsdc::api::Error>(())
/// ```
pub fn evaluate_with_derivatives(
    prepared: &Prepared,
    states: &[StateInput],
) -> Result<Evaluation, Error> {
    crate::studies::batch::evaluate_states_with(prepared, states, true).map_err(Error::States)
}
