//! One instance of the unit: the program loaded at instantiation, the parameters and inputs the
//! importer sets, and the run, started at the end of initialisation. In co-simulation the run is
//! advanced one communication step at a time with the inputs held over the step (a zero-order
//! hold, as `Simulator::set_inputs` applies them); in model exchange the importer's integrator
//! sets the time and the continuous states (the declared coordinates and their rates) and reads
//! their derivatives from the program's equations (`Equations`).

use std::path::Path;

use lsdc::api::{
    Equations, LoadOptions, Override, Prepared, Program, Sample, SettingsChanges, Simulator,
};

use crate::log::{Logger, Status};
use crate::unit::{Role, Unit};

/// Where the instance is in the standard's state machine (FMI 3.0 §3.2 / §4.2; FMI 2.0 §3.2.3,
/// §4.2.4), as far as the unit goes: model exchange's event and continuous-time modes are one
/// (the unit has no event).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    Instantiated,
    Initialization,
    Stepping,
    Terminated,
    /// A call failed with `Error`: only `Reset` and `FreeInstance` are allowed.
    Failed,
}

/// The interface the importer instantiated the unit for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interface {
    CoSimulation,
    ModelExchange,
}

/// A prepared program and what borrows it, owned together: the prepared program lives on the
/// heap at a fixed address until its borrowers are dropped, first (see `Drop`).
struct Run {
    /// The run of co-simulation.
    simulator: Option<Simulator<'static>>,
    /// The equations of model exchange (and of the accelerations read in co-simulation).
    equations: Option<Equations<'static>>,
    prepared: *mut Prepared,
    /// Model exchange: the time and the continuous states the importer set.
    time: f64,
    states: Vec<f64>,
    /// The state's sample, computed when first read after a step.
    sample: Option<Sample>,
}

impl Run {
    fn start(prepared: Prepared, inputs: &[String], interface: Interface) -> Result<Run, String> {
        let prepared = Box::into_raw(Box::new(prepared));
        let mut run = Run {
            simulator: None,
            equations: None,
            prepared,
            time: 0.0,
            states: Vec::new(),
            sample: None,
        };
        let names: Vec<&str> = inputs.iter().map(String::as_str).collect();
        match interface {
            Interface::CoSimulation => {
                let simulator = Simulator::new(run.prepared(), &names);
                run.simulator = Some(simulator.map_err(|f| f.message)?);
            }
            Interface::ModelExchange => {
                let equations = Equations::new(run.prepared(), &names)?;
                run.states = equations.start().to_vec();
                run.equations = Some(equations);
            }
        }
        Ok(run)
    }

    fn prepared(&self) -> &'static Prepared {
        // SAFETY: `prepared` is not freed nor moved before the simulator and the equations
        // that borrow it are dropped (`Drop for Run`), and nothing else reaches it.
        unsafe { &*self.prepared }
    }

    /// The equations, made when first needed (in co-simulation, for the accelerations).
    fn equations(&mut self, inputs: &[String]) -> Result<&mut Equations<'static>, String> {
        if self.equations.is_none() {
            let names: Vec<&str> = inputs.iter().map(String::as_str).collect();
            self.equations = Some(Equations::new(self.prepared(), &names)?);
        }
        Ok(self.equations.as_mut().expect("made above"))
    }

    fn sample(&mut self) -> Result<&Sample, String> {
        if self.sample.is_none() {
            let sample = match (&mut self.simulator, &mut self.equations) {
                (Some(simulator), _) => simulator.sample().map_err(|f| f.message)?,
                (None, Some(equations)) => equations.sample(self.time, &self.states)?,
                (None, None) => return Err("the run has not started".to_string()),
            };
            self.sample = Some(sample);
        }
        Ok(self.sample.as_ref().expect("set above"))
    }

    fn time(&self) -> f64 {
        self.simulator.as_ref().map_or(self.time, Simulator::time)
    }

    /// The derivatives of the continuous states at the current state: the rates, then the
    /// accelerations.
    fn derivatives(&mut self, inputs: &[String], efforts: &[f64]) -> Result<Vec<f64>, String> {
        let (time, states) = match &self.simulator {
            Some(simulator) => {
                let (q, v) = simulator.coordinates().map_err(|f| f.message)?;
                (simulator.time(), [q, v].concat())
            }
            None => (self.time, self.states.clone()),
        };
        let equations = self.equations(inputs)?;
        equations.set_inputs(efforts)?;
        let mut derivatives = vec![0.0; states.len()];
        equations.derivatives(time, &states, &mut derivatives)?;
        Ok(derivatives)
    }
}

impl Drop for Run {
    fn drop(&mut self) {
        // The borrowers first, then the prepared program they borrowed (`Run::start`).
        self.simulator = None;
        self.equations = None;
        // SAFETY: the box is ours again, borrowed by nothing now.
        drop(unsafe { Box::from_raw(self.prepared) });
    }
}

pub struct Instance {
    pub logger: Logger,
    pub logging: bool,
    pub mode: Mode,
    pub interface: Interface,
    unit: Unit,
    program: Program,
    parameters: Vec<f64>,
    inputs: Vec<f64>,
    /// The values of the program's value inputs (`input voltage = 0;`), in the order of
    /// their variables.
    value_inputs: Vec<f64>,
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
        interface: Interface,
    ) -> Result<Instance, (Logger, Failure)> {
        let unit = match Unit::read(resources) {
            Ok(unit) => unit,
            Err(message) => return Err((logger, message)),
        };
        if interface == Interface::ModelExchange && !unit.model_exchange {
            let message = "this unit provides co-simulation only: its model description says why (its mechanism's equations need lsdc's own run)".to_string();
            return Err((logger, message));
        }
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
        let value_inputs = start(Role::ValueInput);
        Ok(Instance {
            logger,
            logging,
            mode: Mode::Instantiated,
            interface,
            unit,
            program,
            parameters,
            inputs,
            value_inputs,
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
            let mut run = Run::start(prepared, &self.unit.inputs, self.interface)?;
            if let Some(simulator) = &mut run.simulator {
                simulator.set_inputs(&self.inputs).map_err(|f| f.message)?;
                let values = (self.unit.variables.iter()).filter(|v| v.role == Role::ValueInput);
                for variable in values {
                    let value = self.value_inputs[variable.index];
                    (simulator.set_input(&variable.name, value)).map_err(|f| f.message)?;
                }
            }
            if let Some(equations) = &mut run.equations {
                equations.set_inputs(&self.inputs)?;
            }
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
                Role::ValueInput => self.value_inputs[variable.index] = start,
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
                Role::ValueInput => self.value_inputs[variable.index],
                Role::Time => self.time(),
                Role::Acceleration => {
                    let (inputs, efforts) = (self.unit.inputs.clone(), self.inputs.clone());
                    let derivatives = self.started()?.derivatives(&inputs, &efforts)?;
                    derivatives[derivatives.len() / 2 + variable.index]
                }
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
                        if let Some(simulator) = &mut run.simulator {
                            simulator.set_inputs(&self.inputs).map_err(|f| f.message)?;
                        }
                        if let Some(equations) = &mut run.equations {
                            equations.set_inputs(&self.inputs)?;
                        }
                        run.sample = None;
                    }
                }
                Role::ValueInput => {
                    self.value_inputs[variable.index] = *value;
                    if let Some(run) = &mut self.run {
                        if let Some(simulator) = &mut run.simulator {
                            let set = simulator.set_input(&variable.name, *value);
                            set.map_err(|f| f.message)?;
                        }
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
        let Some(simulator) = &mut run.simulator else {
            return Err("the unit was instantiated for model exchange".to_string());
        };
        let now = simulator.time();
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
        let target = current + step;
        let advanced = simulator.advance_to(target);
        drop(simulator.take_samples());
        run.sample = None;
        advanced.map_err(|f| format!("the run stopped at t = {}: {}", f.time, f.message))
    }

    /// The run's time (0 before it starts).
    pub fn time(&self) -> f64 {
        self.run.as_ref().map_or(0.0, Run::time)
    }

    /// Model exchange: the run, started (its equations prepared) if it was not.
    fn exchanged(&mut self) -> Result<&mut Run, Failure> {
        if self.interface != Interface::ModelExchange {
            return Err("the unit was instantiated for co-simulation".to_string());
        }
        self.started()
    }

    /// Model exchange: the number of continuous states (the declared coordinates, then their
    /// rates).
    pub fn state_count(&self) -> usize {
        self.unit.state_count()
    }

    pub fn set_time(&mut self, time: f64) -> Result<(), Failure> {
        let run = self.exchanged()?;
        run.time = time;
        run.sample = None;
        Ok(())
    }

    pub fn set_states(&mut self, states: &[f64]) -> Result<(), Failure> {
        let run = self.exchanged()?;
        if states.len() != run.states.len() {
            return Err(format!(
                "{} continuous states given for {}",
                states.len(),
                run.states.len()
            ));
        }
        run.states.copy_from_slice(states);
        run.sample = None;
        Ok(())
    }

    pub fn get_states(&mut self, states: &mut [f64]) -> Result<(), Failure> {
        let run = self.exchanged()?;
        if states.len() != run.states.len() {
            return Err(format!(
                "{} continuous states asked for {}",
                states.len(),
                run.states.len()
            ));
        }
        states.copy_from_slice(&run.states);
        Ok(())
    }

    /// The derivatives of the continuous states at the time and states set.
    pub fn get_derivatives(&mut self, derivatives: &mut [f64]) -> Result<(), Failure> {
        let run = self.exchanged()?;
        let Some(equations) = &mut run.equations else {
            return Err("the run has no equations".to_string());
        };
        equations.derivatives(run.time, &run.states, derivatives)
    }

    /// The nominal values of the continuous states: 1 (rad, m, rad/s, m/s), the scale of a
    /// mechanism's coordinates.
    pub fn get_nominals(&mut self, nominals: &mut [f64]) -> Result<(), Failure> {
        if nominals.len() != self.state_count() {
            return Err(format!(
                "{} nominal values asked for {} continuous states",
                nominals.len(),
                self.state_count()
            ));
        }
        nominals.fill(1.0);
        Ok(())
    }
}
