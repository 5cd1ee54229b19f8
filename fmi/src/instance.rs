//! One instance of the unit: the program loaded at instantiation, the parameters and inputs the
//! importer sets, and the run, started at the end of initialisation and advanced one
//! communication step at a time with the inputs held over the step (a zero-order hold, as
//! `Simulator::set_inputs` applies them).

use std::mem::ManuallyDrop;
use std::path::Path;

use lsdc::api::{LoadOptions, Override, Prepared, Program, Sample, SettingsChanges, Simulator};

use crate::log::{Logger, Status};
use crate::unit::{Role, Unit};

/// Where the instance is in the standard's state machine (FMI 3.0 §3.2 / §4.2; FMI 2.0 §4.2.4),
/// as far as co-simulation goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    Instantiated,
    Initialization,
    Stepping,
    Terminated,
    /// A call failed with `Error`: only `Reset` and `FreeInstance` are allowed.
    Failed,
}

/// A prepared program and the run that borrows it, owned together: the prepared program lives
/// on the heap at a fixed address until the run is dropped, first (see `Drop`).
struct Run {
    simulator: ManuallyDrop<Simulator<'static>>,
    prepared: *mut Prepared,
    /// The state's sample, computed when first read after a step.
    sample: Option<Sample>,
}

impl Run {
    fn start(prepared: Prepared, inputs: &[String]) -> Result<Run, String> {
        let prepared = Box::into_raw(Box::new(prepared));
        // SAFETY: `prepared` is not freed nor moved before the simulator that borrows it is
        // dropped (`Drop for Run`), and nothing else reaches it.
        let borrowed: &'static Prepared = unsafe { &*prepared };
        let names: Vec<&str> = inputs.iter().map(String::as_str).collect();
        match Simulator::new(borrowed, &names) {
            Ok(simulator) => Ok(Run {
                simulator: ManuallyDrop::new(simulator),
                prepared,
                sample: None,
            }),
            Err(failure) => {
                // SAFETY: no simulator was made; the box is ours again.
                drop(unsafe { Box::from_raw(prepared) });
                Err(failure.message)
            }
        }
    }

    fn sample(&mut self) -> Result<&Sample, String> {
        if self.sample.is_none() {
            let sample = self.simulator.sample().map_err(|f| f.message)?;
            self.sample = Some(sample);
        }
        Ok(self.sample.as_ref().expect("set above"))
    }
}

impl Drop for Run {
    fn drop(&mut self) {
        // SAFETY: the simulator first, then the prepared program it borrowed (`Run::start`).
        unsafe {
            ManuallyDrop::drop(&mut self.simulator);
            drop(Box::from_raw(self.prepared));
        }
    }
}

pub struct Instance {
    pub logger: Logger,
    pub logging: bool,
    pub mode: Mode,
    unit: Unit,
    program: Program,
    parameters: Vec<f64>,
    inputs: Vec<f64>,
    tolerance: Option<f64>,
    stop_time: Option<f64>,
    run: Option<Run>,
}

/// An error for the importer: its message (logged by the caller).
pub type Failure = String;

impl Instance {
    /// Loads the unit's program from its resources folder; `token` must be the model
    /// description's (FMI 3.0 `instantiationToken`, FMI 2.0 `guid`).
    pub fn new(
        logger: Logger,
        logging: bool,
        resources: &Path,
        token: &str,
    ) -> Result<Instance, (Logger, Failure)> {
        let unit = match Unit::read(resources) {
            Ok(unit) => unit,
            Err(message) => return Err((logger, message)),
        };
        if unit.token != token {
            let message = format!(
                "the instantiation token {token} is not this unit's {} (a model description of another unit?)",
                unit.token
            );
            return Err((logger, message));
        }
        let folder = Unit::program_folder(resources);
        let options = LoadOptions {
            library_dirs: unit.library_dirs.iter().map(|d| folder.join(d)).collect(),
            use_environment: false,
            scene: unit.scene.clone(),
        };
        let program = match Program::from_file(folder.join(&unit.program), &options) {
            Ok(program) if !program.has_errors() => program,
            Ok(program) => return Err((logger, program.render())),
            Err(error) => return Err((logger, error.to_string())),
        };
        let start = |role| {
            let variables = unit.variables.iter().filter(|v| v.role == role);
            variables.map(|v| v.start.unwrap_or(0.0)).collect()
        };
        let (parameters, inputs) = (start(Role::Parameter), start(Role::Input));
        Ok(Instance {
            logger,
            logging,
            mode: Mode::Instantiated,
            unit,
            program,
            parameters,
            inputs,
            tolerance: None,
            stop_time: None,
            run: None,
        })
    }

    pub fn log(&self, status: Status, message: &str) {
        let category = match status {
            Status::Ok => "logAll",
            Status::Warning => "logStatusWarning",
            Status::Error => "logStatusError",
            Status::Fatal => "logStatusFatal",
        };
        if self.logging || status >= Status::Warning {
            self.logger.log(status, category, message);
        }
    }

    /// The experiment's settings (FMI 3.0 `fmi3EnterInitializationMode`, FMI 2.0
    /// `fmi2SetupExperiment`). The program's time starts at 0, as its laws of time read it.
    pub fn setup(
        &mut self,
        tolerance: Option<f64>,
        start_time: f64,
        stop_time: Option<f64>,
    ) -> Result<(), Failure> {
        if start_time != 0.0 {
            return Err(format!(
                "the start time must be 0 (the program's time starts at 0), not {start_time}"
            ));
        }
        self.tolerance = tolerance.filter(|t| *t > 0.0);
        self.stop_time = stop_time.filter(|t| *t > 0.0);
        self.run = None;
        Ok(())
    }

    /// Prepares the program with the parameters' values and starts the run (at the end of
    /// initialisation, or when an output is read during it).
    fn started(&mut self) -> Result<&mut Run, Failure> {
        if self.run.is_none() {
            let overrides: Vec<Override> = (self.unit.variables.iter())
                .filter(|v| v.role == Role::Parameter)
                .map(|v| Override {
                    name: v.name.clone(),
                    value: self.parameters[v.index],
                })
                .collect();
            let program_settings = self
                .program
                .prepare(&overrides, &SettingsChanges::default())
                .map_err(|e| self.describe(e))?
                .settings;
            // The run ends at the stop time, or never; its own samples are not used (one
            // output interval: the duration), so none accumulate over a long run.
            let duration = self.stop_time.unwrap_or(1e12);
            let changes = SettingsChanges {
                duration: Some(duration),
                output: Some(duration),
                // The importer's tolerance where it differs from the program's (FMPy passes
                // the default experiment's, the program's relative tolerance).
                tolerance: self.tolerance.filter(|t| *t != program_settings.rtol),
                max_steps: Some(usize::MAX),
                ..SettingsChanges::default()
            };
            let prepared =
                (self.program.prepare(&overrides, &changes)).map_err(|e| self.describe(e))?;
            let mut run = Run::start(prepared, &self.unit.inputs)?;
            run.simulator
                .set_inputs(&self.inputs)
                .map_err(|f| f.message)?;
            self.run = Some(run);
        }
        Ok(self.run.as_mut().expect("started above"))
    }

    /// An error of the library, with the program's diagnostics rendered against its sources.
    fn describe(&self, error: lsdc::api::Error) -> Failure {
        match error {
            lsdc::api::Error::Program(diagnostics) => self.program.render_diagnostics(&diagnostics),
            other => other.to_string(),
        }
    }

    pub fn exit_initialization(&mut self) -> Result<(), Failure> {
        self.started()?;
        self.mode = Mode::Stepping;
        Ok(())
    }

    /// Drops the run and the values set: as just instantiated.
    pub fn reset(&mut self) {
        self.run = None;
        for variable in &self.unit.variables {
            let start = variable.start.unwrap_or(0.0);
            match variable.role {
                Role::Parameter => self.parameters[variable.index] = start,
                Role::Input => self.inputs[variable.index] = start,
                _ => {}
            }
        }
        (self.tolerance, self.stop_time) = (None, None);
        self.mode = Mode::Instantiated;
    }

    /// The values of `references`.
    pub fn get(&mut self, references: &[u32], values: &mut [f64]) -> Result<(), Failure> {
        for (reference, value) in references.iter().zip(values) {
            let variable = (self.unit.variable(*reference).cloned())
                .ok_or_else(|| format!("no variable has value reference {reference}"))?;
            *value = match variable.role {
                Role::Parameter => self.parameters[variable.index],
                Role::Input => self.inputs[variable.index],
                Role::Time => self.run.as_ref().map_or(0.0, |r| r.simulator.time()),
                role => {
                    let sample = self.started()?.sample()?;
                    match role {
                        Role::Coordinate => sample.coordinates[variable.index],
                        Role::Rate => sample.rates[variable.index],
                        Role::KineticEnergy => sample.kinetic_energy,
                        Role::PotentialEnergy => sample.potential_energy.unwrap_or(f64::NAN),
                        _ => sample.outputs[variable.index],
                    }
                }
            };
        }
        Ok(())
    }

    /// Sets the values of `references`: parameters before the end of initialisation, inputs
    /// at any time.
    pub fn set(&mut self, references: &[u32], values: &[f64]) -> Result<(), Failure> {
        for (reference, value) in references.iter().zip(values) {
            let variable = (self.unit.variable(*reference).cloned())
                .ok_or_else(|| format!("no variable has value reference {reference}"))?;
            match variable.role {
                Role::Parameter
                    if matches!(self.mode, Mode::Instantiated | Mode::Initialization) =>
                {
                    self.parameters[variable.index] = *value;
                    // Prepared again with the new value when next needed.
                    self.run = None;
                }
                Role::Parameter => {
                    return Err(format!(
                        "`{}` is a fixed parameter: set it before the end of initialisation",
                        variable.name
                    ))
                }
                Role::Input => {
                    self.inputs[variable.index] = *value;
                    if let Some(run) = &mut self.run {
                        run.simulator
                            .set_inputs(&self.inputs)
                            .map_err(|f| f.message)?;
                        run.sample = None;
                    }
                }
                _ => {
                    return Err(format!(
                        "`{}` is an output of the unit: it cannot be set",
                        variable.name
                    ))
                }
            }
        }
        Ok(())
    }

    /// Advances the run from `current` by `step`, the inputs held.
    pub fn do_step(&mut self, current: f64, step: f64) -> Result<(), Failure> {
        let run = self.started()?;
        let now = run.simulator.time();
        // The importer's communication points are sums of steps; the run's time lands on
        // them exactly, so a difference is the importer's rounding or a step skipped.
        if (current - now).abs() > 1e-9 * now.abs().max(1.0) {
            return Err(format!(
                "the step starts at t = {current}, but the unit is at t = {now}"
            ));
        }
        if step < 0.0 {
            return Err(format!("a step of {step} s goes back in time"));
        }
        run.sample = None;
        let target = current + step;
        let advanced = run.simulator.advance_to(target);
        drop(run.simulator.take_samples());
        advanced.map_err(|f| format!("the run stopped at t = {}: {}", f.time, f.message))
    }

    /// The run's time (0 before it starts).
    pub fn time(&self) -> f64 {
        self.run.as_ref().map_or(0.0, |r| r.simulator.time())
    }
}
