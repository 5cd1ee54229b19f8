//! The FMI 3.0 functions (the standard's `fmi3Functions.h`, `fmi3FunctionTypes.h`): those of
//! co-simulation and model exchange implemented, the others (scheduled execution, saved
//! states, directional derivatives, clocks, types other than Float64) present and returning
//! `fmi3Error`.

use std::ffi::{c_char, c_void, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;

use crate::instance::{Instance, Interface, Mode};
use crate::log::{Fmi3Logger, Logger, Status};

type Fmi3Instance = *mut c_void;
type Fmi3Status = i32;
type ValueReference = u32;

/// The instance behind a handle (of either version), `action` run on it with a panic caught (reported as
/// `Fatal`) and a failure logged (`Error`; the instance then accepts only a reset).
pub(crate) fn with(
    instance: Fmi3Instance,
    name: &str,
    action: impl FnOnce(&mut Instance) -> Result<(), String>,
) -> Fmi3Status {
    if instance.is_null() {
        return Status::Error as i32;
    }
    // SAFETY: a non-null handle is one `fmi3InstantiateCoSimulation` returned and
    // `fmi3FreeInstance` has not freed (the standard's contract with the importer).
    let instance = unsafe { &mut *(instance as *mut Instance) };
    if instance.mode == Mode::Failed && !name.ends_with("Reset") && !name.ends_with("Terminate") {
        instance.log(
            Status::Error,
            &format!("{name}: the instance failed; reset it or free it"),
        );
        return Status::Error as i32;
    }
    match catch_unwind(AssertUnwindSafe(|| action(instance))) {
        Ok(Ok(())) => Status::Ok as i32,
        Ok(Err(message)) => {
            instance.log(Status::Error, &format!("{name}: {message}"));
            instance.mode = Mode::Failed;
            Status::Error as i32
        }
        Err(_) => {
            instance.log(Status::Fatal, &format!("{name}: lsdc panicked"));
            instance.mode = Mode::Failed;
            Status::Fatal as i32
        }
    }
}

/// The answer of a function the unit does not provide: logged, `fmi3Error`, the instance's
/// mode unchanged.
pub(crate) fn refuse(instance: *mut c_void, name: &str) -> i32 {
    if !instance.is_null() {
        // SAFETY: as in `with`.
        let instance = unsafe { &*(instance as *const Instance) };
        instance.log(
            Status::Error,
            &format!("{name}: not provided by this unit (co-simulation and model exchange without events, Float64 variables)"),
        );
    }
    Status::Error as i32
}

/// A slice from a C array and its length (empty where the pointer is null).
pub(crate) unsafe fn slice<'a, T>(pointer: *const T, length: usize) -> &'a [T] {
    if pointer.is_null() || length == 0 {
        &[]
    } else {
        std::slice::from_raw_parts(pointer, length)
    }
}

pub(crate) unsafe fn slice_mut<'a, T>(pointer: *mut T, length: usize) -> &'a mut [T] {
    if pointer.is_null() || length == 0 {
        &mut []
    } else {
        std::slice::from_raw_parts_mut(pointer, length)
    }
}

pub(crate) unsafe fn string(pointer: *const c_char) -> String {
    if pointer.is_null() {
        String::new()
    } else {
        CStr::from_ptr(pointer).to_string_lossy().into_owned()
    }
}

#[no_mangle]
pub extern "C" fn fmi3GetVersion() -> *const c_char {
    c"3.0".as_ptr()
}

#[no_mangle]
pub extern "C" fn fmi3SetDebugLogging(
    instance: Fmi3Instance,
    logging_on: bool,
    _n_categories: usize,
    _categories: *const *const c_char,
) -> Fmi3Status {
    with(instance, "fmi3SetDebugLogging", |i| {
        i.logging = logging_on;
        Ok(())
    })
}

#[no_mangle]
pub extern "C" fn fmi3InstantiateModelExchange(
    _instance_name: *const c_char,
    instantiation_token: *const c_char,
    resource_path: *const c_char,
    _visible: bool,
    logging_on: bool,
    instance_environment: *mut c_void,
    log_message: Fmi3Logger,
) -> Fmi3Instance {
    let logger = Logger::Fmi3 {
        callback: log_message,
        environment: instance_environment,
    };
    // SAFETY: the importer passes C strings or null (FMI 3.0 §3.2.1).
    let (token, resources) = unsafe { (string(instantiation_token), string(resource_path)) };
    instantiate(
        logger,
        logging_on,
        &resources,
        &token,
        Interface::ModelExchange,
    )
}

/// An instance for `interface` from the unit's resources, or null with the reason logged.
fn instantiate(
    logger: Logger,
    logging_on: bool,
    resources: &str,
    token: &str,
    interface: Interface,
) -> Fmi3Instance {
    let made = catch_unwind(AssertUnwindSafe(|| {
        if resources.is_empty() {
            return Err((
                logger,
                "no resource path: the unit's program is in its resources".to_string(),
            ));
        }
        Instance::new(
            logger,
            logging_on,
            &PathBuf::from(resources),
            token,
            interface,
        )
    }));
    match made {
        Ok(Ok(instance)) => Box::into_raw(Box::new(instance)) as Fmi3Instance,
        Ok(Err((logger, message))) => {
            logger.log(Status::Error, "logStatusError", &message);
            std::ptr::null_mut()
        }
        Err(_) => std::ptr::null_mut(),
    }
}

#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub extern "C" fn fmi3InstantiateCoSimulation(
    _instance_name: *const c_char,
    instantiation_token: *const c_char,
    resource_path: *const c_char,
    _visible: bool,
    logging_on: bool,
    event_mode_used: bool,
    _early_return_allowed: bool,
    _required_intermediate_variables: *const ValueReference,
    _n_required_intermediate_variables: usize,
    instance_environment: *mut c_void,
    log_message: Fmi3Logger,
    _intermediate_update: *const c_void,
) -> Fmi3Instance {
    let logger = Logger::Fmi3 {
        callback: log_message,
        environment: instance_environment,
    };
    if event_mode_used {
        let message = "event mode is not supported (eventModeUsed must be false)";
        logger.log(Status::Error, "logStatusError", message);
        return std::ptr::null_mut();
    }
    // SAFETY: the importer passes C strings or null (FMI 3.0 §4.2.1).
    let (token, resources) = unsafe { (string(instantiation_token), string(resource_path)) };
    instantiate(
        logger,
        logging_on,
        &resources,
        &token,
        Interface::CoSimulation,
    )
}

#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub extern "C" fn fmi3InstantiateScheduledExecution(
    _instance_name: *const c_char,
    _instantiation_token: *const c_char,
    _resource_path: *const c_char,
    _visible: bool,
    _logging_on: bool,
    instance_environment: *mut c_void,
    log_message: Fmi3Logger,
    _clock_update: *const c_void,
    _lock_preemption: *const c_void,
    _unlock_preemption: *const c_void,
) -> Fmi3Instance {
    let logger = Logger::Fmi3 {
        callback: log_message,
        environment: instance_environment,
    };
    logger.log(
        Status::Error,
        "logStatusError",
        "this unit provides co-simulation (fmi3InstantiateCoSimulation) and, for trees without events, model exchange (fmi3InstantiateModelExchange), not scheduled execution",
    );
    std::ptr::null_mut()
}

#[no_mangle]
pub extern "C" fn fmi3FreeInstance(instance: Fmi3Instance) {
    if !instance.is_null() {
        // SAFETY: the handle came from `Box::into_raw` and is freed once (FMI 3.0 §3.2.1).
        drop(unsafe { Box::from_raw(instance as *mut Instance) });
    }
}

#[no_mangle]
pub extern "C" fn fmi3EnterInitializationMode(
    instance: Fmi3Instance,
    tolerance_defined: bool,
    tolerance: f64,
    start_time: f64,
    stop_time_defined: bool,
    stop_time: f64,
) -> Fmi3Status {
    with(instance, "fmi3EnterInitializationMode", |i| {
        let tolerance = tolerance_defined.then_some(tolerance);
        i.setup(
            tolerance,
            start_time,
            stop_time_defined.then_some(stop_time),
        )?;
        i.mode = Mode::Initialization;
        Ok(())
    })
}

#[no_mangle]
pub extern "C" fn fmi3ExitInitializationMode(instance: Fmi3Instance) -> Fmi3Status {
    with(
        instance,
        "fmi3ExitInitializationMode",
        Instance::exit_initialization,
    )
}

#[no_mangle]
pub extern "C" fn fmi3EnterStepMode(instance: Fmi3Instance) -> Fmi3Status {
    with(instance, "fmi3EnterStepMode", |i| {
        i.mode = Mode::Stepping;
        Ok(())
    })
}

#[no_mangle]
pub extern "C" fn fmi3Terminate(instance: Fmi3Instance) -> Fmi3Status {
    with(instance, "fmi3Terminate", |i| {
        i.mode = Mode::Terminated;
        Ok(())
    })
}

#[no_mangle]
pub extern "C" fn fmi3Reset(instance: Fmi3Instance) -> Fmi3Status {
    with(instance, "fmi3Reset", |i| {
        i.reset();
        Ok(())
    })
}

#[no_mangle]
pub extern "C" fn fmi3GetFloat64(
    instance: Fmi3Instance,
    value_references: *const ValueReference,
    n_value_references: usize,
    values: *mut f64,
    n_values: usize,
) -> Fmi3Status {
    with(instance, "fmi3GetFloat64", |i| {
        if n_values != n_value_references {
            return Err(format!(
                "{n_values} values for {n_value_references} scalar variables"
            ));
        }
        // SAFETY: arrays of the lengths given (FMI 3.0 §2.2.6.1).
        let (references, values) = unsafe {
            (
                slice(value_references, n_value_references),
                slice_mut(values, n_values),
            )
        };
        i.get(references, values)
    })
}

#[no_mangle]
pub extern "C" fn fmi3SetFloat64(
    instance: Fmi3Instance,
    value_references: *const ValueReference,
    n_value_references: usize,
    values: *const f64,
    n_values: usize,
) -> Fmi3Status {
    with(instance, "fmi3SetFloat64", |i| {
        if n_values != n_value_references {
            return Err(format!(
                "{n_values} values for {n_value_references} scalar variables"
            ));
        }
        // SAFETY: arrays of the lengths given (FMI 3.0 §2.2.6.2).
        let (references, values) = unsafe {
            (
                slice(value_references, n_value_references),
                slice(values, n_values),
            )
        };
        i.set(references, values)
    })
}

#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub extern "C" fn fmi3DoStep(
    instance: Fmi3Instance,
    current_communication_point: f64,
    communication_step_size: f64,
    _no_set_fmu_state_prior_to_current_point: bool,
    event_handling_needed: *mut bool,
    terminate_simulation: *mut bool,
    early_return: *mut bool,
    last_successful_time: *mut f64,
) -> Fmi3Status {
    let status = with(instance, "fmi3DoStep", |i| {
        i.do_step(current_communication_point, communication_step_size)
    });
    // SAFETY: the out-arguments are the importer's variables or null.
    unsafe {
        for flag in [event_handling_needed, terminate_simulation, early_return] {
            if !flag.is_null() {
                *flag = false;
            }
        }
        if !last_successful_time.is_null() && !instance.is_null() {
            *last_successful_time = (*(instance as *mut Instance)).time();
        }
    }
    status
}

/// Model exchange: the unit has no event, so event mode only passes (FMI 3.0 §3.2.2).
fn exchanging(instance: Fmi3Instance, name: &str) -> Fmi3Status {
    with(instance, name, |i| {
        if i.interface != Interface::ModelExchange {
            return Err("the unit was instantiated for co-simulation".to_string());
        }
        i.mode = Mode::Stepping;
        Ok(())
    })
}

#[no_mangle]
pub extern "C" fn fmi3EnterEventMode(instance: Fmi3Instance) -> Fmi3Status {
    exchanging(instance, "fmi3EnterEventMode")
}

#[no_mangle]
pub extern "C" fn fmi3EnterContinuousTimeMode(instance: Fmi3Instance) -> Fmi3Status {
    exchanging(instance, "fmi3EnterContinuousTimeMode")
}

/// Writes `value` where `pointer` points, unless it is null.
unsafe fn put<T>(pointer: *mut T, value: T) {
    if !pointer.is_null() {
        *pointer = value;
    }
}

#[no_mangle]
pub extern "C" fn fmi3UpdateDiscreteStates(
    instance: Fmi3Instance,
    discrete_states_need_update: *mut bool,
    terminate_simulation: *mut bool,
    nominals_changed: *mut bool,
    values_changed: *mut bool,
    next_event_time_defined: *mut bool,
    next_event_time: *mut f64,
) -> Fmi3Status {
    // SAFETY: the importer's variables or null (FMI 3.0 §3.2.2).
    unsafe {
        for flag in [
            discrete_states_need_update,
            terminate_simulation,
            nominals_changed,
            values_changed,
            next_event_time_defined,
        ] {
            put(flag, false);
        }
        put(next_event_time, 0.0);
    }
    exchanging(instance, "fmi3UpdateDiscreteStates")
}

#[no_mangle]
pub extern "C" fn fmi3EvaluateDiscreteStates(instance: Fmi3Instance) -> Fmi3Status {
    with(instance, "fmi3EvaluateDiscreteStates", |_| Ok(()))
}

#[no_mangle]
pub extern "C" fn fmi3CompletedIntegratorStep(
    instance: Fmi3Instance,
    _no_set_state_prior: bool,
    enter_event_mode: *mut bool,
    terminate_simulation: *mut bool,
) -> Fmi3Status {
    // SAFETY: the importer's variables or null (FMI 3.0 §3.2.3).
    unsafe {
        put(enter_event_mode, false);
        put(terminate_simulation, false);
    }
    exchanging(instance, "fmi3CompletedIntegratorStep")
}

#[no_mangle]
pub extern "C" fn fmi3SetTime(instance: Fmi3Instance, time: f64) -> Fmi3Status {
    with(instance, "fmi3SetTime", |i| i.set_time(time))
}

#[no_mangle]
pub extern "C" fn fmi3SetContinuousStates(
    instance: Fmi3Instance,
    states: *const f64,
    n: usize,
) -> Fmi3Status {
    // SAFETY: an array of `n` values (FMI 3.0 §3.2.3).
    with(instance, "fmi3SetContinuousStates", |i| {
        i.set_states(unsafe { slice(states, n) })
    })
}

#[no_mangle]
pub extern "C" fn fmi3GetContinuousStates(
    instance: Fmi3Instance,
    states: *mut f64,
    n: usize,
) -> Fmi3Status {
    // SAFETY: an array of `n` values (FMI 3.0 §3.2.3).
    with(instance, "fmi3GetContinuousStates", |i| {
        i.get_states(unsafe { slice_mut(states, n) })
    })
}

#[no_mangle]
pub extern "C" fn fmi3GetContinuousStateDerivatives(
    instance: Fmi3Instance,
    derivatives: *mut f64,
    n: usize,
) -> Fmi3Status {
    // SAFETY: an array of `n` values (FMI 3.0 §3.2.3).
    with(instance, "fmi3GetContinuousStateDerivatives", |i| {
        i.get_derivatives(unsafe { slice_mut(derivatives, n) })
    })
}

#[no_mangle]
pub extern "C" fn fmi3GetNominalsOfContinuousStates(
    instance: Fmi3Instance,
    nominals: *mut f64,
    n: usize,
) -> Fmi3Status {
    // SAFETY: an array of `n` values (FMI 3.0 §3.2.3).
    with(instance, "fmi3GetNominalsOfContinuousStates", |i| {
        i.get_nominals(unsafe { slice_mut(nominals, n) })
    })
}

#[no_mangle]
pub extern "C" fn fmi3GetEventIndicators(
    instance: Fmi3Instance,
    _indicators: *mut f64,
    n: usize,
) -> Fmi3Status {
    with(instance, "fmi3GetEventIndicators", |_| match n {
        0 => Ok(()),
        _ => Err(format!("{n} event indicators asked for; the unit has none")),
    })
}

#[no_mangle]
pub extern "C" fn fmi3GetNumberOfEventIndicators(
    instance: Fmi3Instance,
    n: *mut usize,
) -> Fmi3Status {
    // SAFETY: the importer's variable or null.
    with(instance, "fmi3GetNumberOfEventIndicators", |_| {
        unsafe { put(n, 0) };
        Ok(())
    })
}

#[no_mangle]
pub extern "C" fn fmi3GetNumberOfContinuousStates(
    instance: Fmi3Instance,
    n: *mut usize,
) -> Fmi3Status {
    // SAFETY: the importer's variable or null.
    with(instance, "fmi3GetNumberOfContinuousStates", |i| {
        unsafe { put(n, i.state_count()) };
        Ok(())
    })
}

/// Functions the unit does not provide: each logs why and returns `fmi3Error`, its
/// arguments those of the standard's declaration.
macro_rules! not_provided {
    ($($name:ident($($argument:ident: $type:ty),*);)*) => {
        $(
            #[no_mangle]
            #[allow(clippy::too_many_arguments)]
            pub extern "C" fn $name(instance: Fmi3Instance, $($argument: $type),*) -> Fmi3Status {
                $(let _ = $argument;)*
                refuse(instance, stringify!($name))
            }
        )*
    };
}

type Refs = *const ValueReference;

not_provided! {
    fmi3GetFloat32(vr: Refs, n: usize, values: *mut f32, nv: usize);
    fmi3GetInt8(vr: Refs, n: usize, values: *mut i8, nv: usize);
    fmi3GetUInt8(vr: Refs, n: usize, values: *mut u8, nv: usize);
    fmi3GetInt16(vr: Refs, n: usize, values: *mut i16, nv: usize);
    fmi3GetUInt16(vr: Refs, n: usize, values: *mut u16, nv: usize);
    fmi3GetInt32(vr: Refs, n: usize, values: *mut i32, nv: usize);
    fmi3GetUInt32(vr: Refs, n: usize, values: *mut u32, nv: usize);
    fmi3GetInt64(vr: Refs, n: usize, values: *mut i64, nv: usize);
    fmi3GetUInt64(vr: Refs, n: usize, values: *mut u64, nv: usize);
    fmi3GetBoolean(vr: Refs, n: usize, values: *mut bool, nv: usize);
    fmi3GetString(vr: Refs, n: usize, values: *mut *const c_char, nv: usize);
    fmi3GetBinary(vr: Refs, n: usize, sizes: *mut usize, values: *mut *const u8, nv: usize);
    fmi3GetClock(vr: Refs, n: usize, values: *mut bool);
    fmi3SetFloat32(vr: Refs, n: usize, values: *const f32, nv: usize);
    fmi3SetInt8(vr: Refs, n: usize, values: *const i8, nv: usize);
    fmi3SetUInt8(vr: Refs, n: usize, values: *const u8, nv: usize);
    fmi3SetInt16(vr: Refs, n: usize, values: *const i16, nv: usize);
    fmi3SetUInt16(vr: Refs, n: usize, values: *const u16, nv: usize);
    fmi3SetInt32(vr: Refs, n: usize, values: *const i32, nv: usize);
    fmi3SetUInt32(vr: Refs, n: usize, values: *const u32, nv: usize);
    fmi3SetInt64(vr: Refs, n: usize, values: *const i64, nv: usize);
    fmi3SetUInt64(vr: Refs, n: usize, values: *const u64, nv: usize);
    fmi3SetBoolean(vr: Refs, n: usize, values: *const bool, nv: usize);
    fmi3SetString(vr: Refs, n: usize, values: *const *const c_char, nv: usize);
    fmi3SetBinary(vr: Refs, n: usize, sizes: *const usize, values: *const *const u8, nv: usize);
    fmi3SetClock(vr: Refs, n: usize, values: *const bool);
    fmi3GetNumberOfVariableDependencies(vr: ValueReference, n: *mut usize);
    fmi3GetVariableDependencies(dependent: ValueReference, element_indices_of_dependent: *mut usize, independents: *mut ValueReference, element_indices_of_independents: *mut usize, dependency_kinds: *mut i32, n: usize);
    fmi3GetFMUState(state: *mut *mut c_void);
    fmi3SetFMUState(state: *mut c_void);
    fmi3FreeFMUState(state: *mut *mut c_void);
    fmi3SerializedFMUStateSize(state: *mut c_void, size: *mut usize);
    fmi3SerializeFMUState(state: *mut c_void, bytes: *mut u8, size: usize);
    fmi3DeserializeFMUState(bytes: *const u8, size: usize, state: *mut *mut c_void);
    fmi3GetDirectionalDerivative(unknowns: Refs, n_unknowns: usize, knowns: Refs, n_knowns: usize, seed: *const f64, n_seed: usize, sensitivity: *mut f64, n_sensitivity: usize);
    fmi3GetAdjointDerivative(unknowns: Refs, n_unknowns: usize, knowns: Refs, n_knowns: usize, seed: *const f64, n_seed: usize, sensitivity: *mut f64, n_sensitivity: usize);
    fmi3EnterConfigurationMode();
    fmi3ExitConfigurationMode();
    fmi3GetIntervalDecimal(vr: Refs, n: usize, intervals: *mut f64, qualifiers: *mut i32);
    fmi3GetIntervalFraction(vr: Refs, n: usize, counters: *mut u64, resolutions: *mut u64, qualifiers: *mut i32);
    fmi3GetShiftDecimal(vr: Refs, n: usize, shifts: *mut f64);
    fmi3GetShiftFraction(vr: Refs, n: usize, counters: *mut u64, resolutions: *mut u64);
    fmi3SetIntervalDecimal(vr: Refs, n: usize, intervals: *const f64);
    fmi3SetIntervalFraction(vr: Refs, n: usize, counters: *const u64, resolutions: *const u64);
    fmi3SetShiftDecimal(vr: Refs, n: usize, shifts: *const f64);
    fmi3SetShiftFraction(vr: Refs, n: usize, counters: *const u64, resolutions: *const u64);
    fmi3GetOutputDerivatives(vr: Refs, n: usize, orders: *const i32, values: *mut f64, nv: usize);
    fmi3ActivateModelPartition(clock_reference: ValueReference, activation_time: f64);
}
