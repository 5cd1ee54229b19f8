//! The FMI 2.0 functions (the standard's `fmi2Functions.h`, `fmi2FunctionTypes.h`): those of
//! co-simulation and model exchange implemented on the same instance as FMI 3.0's, the others
//! (saved states, directional derivatives, integer, boolean and string variables,
//! asynchronous steps) present and returning `fmi2Error`.

use std::ffi::{c_char, c_void, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

use crate::fmi3::{refuse, slice, slice_mut, string, with};
use crate::instance::{Instance, Interface, Mode};
use crate::log::{Fmi2Logger, Logger, Status};

type Component = *mut c_void;
type Fmi2Status = i32;
type ValueReference = u32;
type Fmi2Boolean = i32;

/// `fmi2CallbackFunctions` (FMI 2.0 §2.1.5): the logger, the memory functions (unused: the
/// library allocates its own), `stepFinished` (unused: steps are synchronous) and the
/// environment passed back to the logger.
#[repr(C)]
pub struct CallbackFunctions {
    logger: Fmi2Logger,
    allocate_memory: *const c_void,
    free_memory: *const c_void,
    step_finished: *const c_void,
    component_environment: *mut c_void,
}

/// `fmi2ModelExchange` and `fmi2CoSimulation` in `fmi2Type`.
const MODEL_EXCHANGE: i32 = 0;
const CO_SIMULATION: i32 = 1;

/// A file URI's path (RFC 8089: `file:///path` or `file://localhost/path`, percent-encoded).
fn path_of_uri(uri: &str) -> Option<String> {
    let rest = uri.strip_prefix("file://")?;
    let rest = rest.strip_prefix("localhost").unwrap_or(rest);
    let bytes = rest.as_bytes();
    let mut decoded = Vec::with_capacity(bytes.len());
    let mut k = 0;
    while k < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        match (
            bytes[k],
            bytes.get(k + 1).and_then(|&b| hex(b)),
            bytes.get(k + 2).and_then(|&b| hex(b)),
        ) {
            (b'%', Some(high), Some(low)) => {
                decoded.push((high * 16 + low) as u8);
                k += 3;
            }
            (byte, _, _) => {
                decoded.push(byte);
                k += 1;
            }
        }
    }
    String::from_utf8(decoded).ok()
}

#[no_mangle]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

#[no_mangle]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

#[no_mangle]
pub extern "C" fn fmi2SetDebugLogging(
    c: Component,
    logging_on: Fmi2Boolean,
    _n_categories: usize,
    _categories: *const *const c_char,
) -> Fmi2Status {
    with(c, "fmi2SetDebugLogging", |i| {
        i.logging = logging_on != 0;
        Ok(())
    })
}

#[no_mangle]
pub extern "C" fn fmi2Instantiate(
    instance_name: *const c_char,
    fmu_type: i32,
    fmu_guid: *const c_char,
    fmu_resource_location: *const c_char,
    functions: *const CallbackFunctions,
    _visible: Fmi2Boolean,
    logging_on: Fmi2Boolean,
) -> Component {
    // SAFETY: the importer passes C strings and its callback functions (FMI 2.0 §2.1.5).
    let (name, guid, location) = unsafe {
        (
            string(instance_name),
            string(fmu_guid),
            string(fmu_resource_location),
        )
    };
    let (callback, environment) = match unsafe { functions.as_ref() } {
        Some(f) => (f.logger, f.component_environment),
        None => (None, std::ptr::null_mut()),
    };
    let logger = Logger::Fmi2 {
        callback,
        environment,
        instance_name: CString::new(name).unwrap_or_default(),
    };
    let made = catch_unwind(AssertUnwindSafe(|| {
        let interface = match fmu_type {
            CO_SIMULATION => Interface::CoSimulation,
            MODEL_EXCHANGE => Interface::ModelExchange,
            _ => return Err((logger, format!("no FMU type {fmu_type} in FMI 2.0"))),
        };
        let Some(resources) = path_of_uri(&location) else {
            let message = format!("the resource location `{location}` is not a file URI");
            return Err((logger, message));
        };
        Instance::new(
            logger,
            logging_on != 0,
            resources.as_ref(),
            &guid,
            interface,
        )
    }));
    match made {
        Ok(Ok(instance)) => Box::into_raw(Box::new(instance)) as Component,
        Ok(Err((logger, message))) => {
            logger.log(Status::Error, "logStatusError", &message);
            std::ptr::null_mut()
        }
        Err(_) => std::ptr::null_mut(),
    }
}

#[no_mangle]
pub extern "C" fn fmi2FreeInstance(c: Component) {
    crate::fmi3::fmi3FreeInstance(c);
}

#[no_mangle]
pub extern "C" fn fmi2SetupExperiment(
    c: Component,
    tolerance_defined: Fmi2Boolean,
    tolerance: f64,
    start_time: f64,
    stop_time_defined: Fmi2Boolean,
    stop_time: f64,
) -> Fmi2Status {
    with(c, "fmi2SetupExperiment", |i| {
        let tolerance = (tolerance_defined != 0).then_some(tolerance);
        i.setup(
            tolerance,
            start_time,
            (stop_time_defined != 0).then_some(stop_time),
        )
    })
}

#[no_mangle]
pub extern "C" fn fmi2EnterInitializationMode(c: Component) -> Fmi2Status {
    with(c, "fmi2EnterInitializationMode", |i| {
        i.mode = Mode::Initialization;
        Ok(())
    })
}

#[no_mangle]
pub extern "C" fn fmi2ExitInitializationMode(c: Component) -> Fmi2Status {
    with(
        c,
        "fmi2ExitInitializationMode",
        Instance::exit_initialization,
    )
}

#[no_mangle]
pub extern "C" fn fmi2Terminate(c: Component) -> Fmi2Status {
    with(c, "fmi2Terminate", |i| {
        i.mode = Mode::Terminated;
        Ok(())
    })
}

#[no_mangle]
pub extern "C" fn fmi2Reset(c: Component) -> Fmi2Status {
    with(c, "fmi2Reset", |i| {
        i.reset();
        Ok(())
    })
}

#[no_mangle]
pub extern "C" fn fmi2GetReal(
    c: Component,
    vr: *const ValueReference,
    nvr: usize,
    value: *mut f64,
) -> Fmi2Status {
    with(c, "fmi2GetReal", |i| {
        // SAFETY: arrays of `nvr` elements (FMI 2.0 §2.1.7).
        let (references, values) = unsafe { (slice(vr, nvr), slice_mut(value, nvr)) };
        i.get(references, values)
    })
}

#[no_mangle]
pub extern "C" fn fmi2SetReal(
    c: Component,
    vr: *const ValueReference,
    nvr: usize,
    value: *const f64,
) -> Fmi2Status {
    with(c, "fmi2SetReal", |i| {
        // SAFETY: arrays of `nvr` elements (FMI 2.0 §2.1.7).
        let (references, values) = unsafe { (slice(vr, nvr), slice(value, nvr)) };
        i.set(references, values)
    })
}

#[no_mangle]
pub extern "C" fn fmi2DoStep(
    c: Component,
    current_communication_point: f64,
    communication_step_size: f64,
    _no_set_fmu_state_prior_to_current_point: Fmi2Boolean,
) -> Fmi2Status {
    with(c, "fmi2DoStep", |i| {
        i.do_step(current_communication_point, communication_step_size)
    })
}

/// `fmi2StatusKind`: `fmi2LastSuccessfulTime` and `fmi2Terminated` are answered, as the
/// steps are synchronous.
const LAST_SUCCESSFUL_TIME: i32 = 2;
const TERMINATED: i32 = 3;

#[no_mangle]
pub extern "C" fn fmi2GetRealStatus(c: Component, kind: i32, value: *mut f64) -> Fmi2Status {
    if kind != LAST_SUCCESSFUL_TIME || value.is_null() {
        return refuse(c, "fmi2GetRealStatus");
    }
    with(c, "fmi2GetRealStatus", |i| {
        // SAFETY: the importer's variable, not null.
        unsafe { *value = i.time() };
        Ok(())
    })
}

#[no_mangle]
pub extern "C" fn fmi2GetBooleanStatus(
    c: Component,
    kind: i32,
    value: *mut Fmi2Boolean,
) -> Fmi2Status {
    if kind != TERMINATED || value.is_null() {
        return refuse(c, "fmi2GetBooleanStatus");
    }
    with(c, "fmi2GetBooleanStatus", |_| {
        // SAFETY: the importer's variable, not null.
        unsafe { *value = 0 };
        Ok(())
    })
}

/// `fmi2EventInfo` (FMI 2.0 §3.2.2).
#[repr(C)]
pub struct EventInfo {
    new_discrete_states_needed: Fmi2Boolean,
    terminate_simulation: Fmi2Boolean,
    nominals_of_continuous_states_changed: Fmi2Boolean,
    values_of_continuous_states_changed: Fmi2Boolean,
    next_event_time_defined: Fmi2Boolean,
    next_event_time: f64,
}

/// Model exchange: the unit has no event, so event mode only passes (FMI 2.0 §3.2.2).
fn exchanging(c: Component, name: &str) -> Fmi2Status {
    with(c, name, |i| {
        if i.interface != Interface::ModelExchange {
            return Err("the unit was instantiated for co-simulation".to_string());
        }
        Ok(())
    })
}

#[no_mangle]
pub extern "C" fn fmi2EnterEventMode(c: Component) -> Fmi2Status {
    exchanging(c, "fmi2EnterEventMode")
}

#[no_mangle]
pub extern "C" fn fmi2NewDiscreteStates(c: Component, event_info: *mut EventInfo) -> Fmi2Status {
    // SAFETY: the importer's structure or null.
    if let Some(info) = unsafe { event_info.as_mut() } {
        *info = EventInfo {
            new_discrete_states_needed: 0,
            terminate_simulation: 0,
            nominals_of_continuous_states_changed: 0,
            values_of_continuous_states_changed: 0,
            next_event_time_defined: 0,
            next_event_time: 0.0,
        };
    }
    exchanging(c, "fmi2NewDiscreteStates")
}

#[no_mangle]
pub extern "C" fn fmi2EnterContinuousTimeMode(c: Component) -> Fmi2Status {
    exchanging(c, "fmi2EnterContinuousTimeMode")
}

#[no_mangle]
pub extern "C" fn fmi2CompletedIntegratorStep(
    c: Component,
    _no_set_state_prior: Fmi2Boolean,
    enter_event_mode: *mut Fmi2Boolean,
    terminate_simulation: *mut Fmi2Boolean,
) -> Fmi2Status {
    // SAFETY: the importer's variables or null.
    unsafe {
        for flag in [enter_event_mode, terminate_simulation] {
            if !flag.is_null() {
                *flag = 0;
            }
        }
    }
    exchanging(c, "fmi2CompletedIntegratorStep")
}

#[no_mangle]
pub extern "C" fn fmi2SetTime(c: Component, time: f64) -> Fmi2Status {
    with(c, "fmi2SetTime", |i| i.set_time(time))
}

#[no_mangle]
pub extern "C" fn fmi2SetContinuousStates(c: Component, x: *const f64, nx: usize) -> Fmi2Status {
    // SAFETY: an array of `nx` values (FMI 2.0 §3.2.1).
    with(c, "fmi2SetContinuousStates", |i| {
        i.set_states(unsafe { slice(x, nx) })
    })
}

#[no_mangle]
pub extern "C" fn fmi2GetContinuousStates(c: Component, x: *mut f64, nx: usize) -> Fmi2Status {
    // SAFETY: an array of `nx` values (FMI 2.0 §3.2.2).
    with(c, "fmi2GetContinuousStates", |i| {
        i.get_states(unsafe { slice_mut(x, nx) })
    })
}

#[no_mangle]
pub extern "C" fn fmi2GetDerivatives(c: Component, derivatives: *mut f64, nx: usize) -> Fmi2Status {
    // SAFETY: an array of `nx` values (FMI 2.0 §3.2.2).
    with(c, "fmi2GetDerivatives", |i| {
        i.get_derivatives(unsafe { slice_mut(derivatives, nx) })
    })
}

#[no_mangle]
pub extern "C" fn fmi2GetNominalsOfContinuousStates(
    c: Component,
    x_nominal: *mut f64,
    nx: usize,
) -> Fmi2Status {
    // SAFETY: an array of `nx` values (FMI 2.0 §3.2.2).
    with(c, "fmi2GetNominalsOfContinuousStates", |i| {
        i.get_nominals(unsafe { slice_mut(x_nominal, nx) })
    })
}

#[no_mangle]
pub extern "C" fn fmi2GetEventIndicators(
    c: Component,
    _indicators: *mut f64,
    ni: usize,
) -> Fmi2Status {
    with(c, "fmi2GetEventIndicators", |_| match ni {
        0 => Ok(()),
        _ => Err(format!(
            "{ni} event indicators asked for; the unit has none"
        )),
    })
}

/// Functions the unit does not provide: each logs why and returns `fmi2Error`, its
/// arguments those of the standard's declaration.
macro_rules! not_provided {
    ($($name:ident($($argument:ident: $type:ty),*);)*) => {
        $(
            #[no_mangle]
            pub extern "C" fn $name(c: Component, $($argument: $type),*) -> Fmi2Status {
                $(let _ = $argument;)*
                refuse(c, stringify!($name))
            }
        )*
    };
}

type Refs = *const ValueReference;

not_provided! {
    fmi2GetInteger(vr: Refs, nvr: usize, value: *mut i32);
    fmi2GetBoolean(vr: Refs, nvr: usize, value: *mut Fmi2Boolean);
    fmi2GetString(vr: Refs, nvr: usize, value: *mut *const c_char);
    fmi2SetInteger(vr: Refs, nvr: usize, value: *const i32);
    fmi2SetBoolean(vr: Refs, nvr: usize, value: *const Fmi2Boolean);
    fmi2SetString(vr: Refs, nvr: usize, value: *const *const c_char);
    fmi2GetFMUstate(state: *mut *mut c_void);
    fmi2SetFMUstate(state: *mut c_void);
    fmi2FreeFMUstate(state: *mut *mut c_void);
    fmi2SerializedFMUstateSize(state: *mut c_void, size: *mut usize);
    fmi2SerializeFMUstate(state: *mut c_void, bytes: *mut c_char, size: usize);
    fmi2DeSerializeFMUstate(bytes: *const c_char, size: usize, state: *mut *mut c_void);
    fmi2GetDirectionalDerivative(unknowns: Refs, n_unknowns: usize, knowns: Refs, n_knowns: usize, dv_known: *const f64, dv_unknown: *mut f64);
    fmi2SetRealInputDerivatives(vr: Refs, nvr: usize, order: *const i32, value: *const f64);
    fmi2GetRealOutputDerivatives(vr: Refs, nvr: usize, order: *const i32, value: *mut f64);
    fmi2CancelStep();
    fmi2GetStatus(kind: i32, value: *mut i32);
    fmi2GetIntegerStatus(kind: i32, value: *mut i32);
    fmi2GetStringStatus(kind: i32, value: *mut *const c_char);
}
