//! Messages to the importer through the logger it gave at instantiation: FMI 3.0's
//! `fmi3LogMessageCallback`, or FMI 2.0's `fmi2CallbackLogger` (a C variadic function, called
//! with the message as the argument of a `%s` format, so that a `%` in it is not read).

use std::ffi::{c_char, c_void, CString};

/// FMI 3.0 §2.3.1: `void (*)(fmi3InstanceEnvironment, fmi3Status, fmi3String category,
/// fmi3String message)`.
pub type Fmi3Logger = Option<unsafe extern "C" fn(*mut c_void, i32, *const c_char, *const c_char)>;

/// FMI 2.0 §2.1.5: `void (*)(fmi2ComponentEnvironment, fmi2String instanceName, fmi2Status,
/// fmi2String category, fmi2String message, ...)`.
pub type Fmi2Logger = Option<
    unsafe extern "C" fn(*mut c_void, *const c_char, i32, *const c_char, *const c_char, ...),
>;

/// The status of a call and of a message: the same numbers in FMI 3.0 and 2.0 (`Discard`, 2,
/// is not used: a step either lands or fails).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
#[repr(i32)]
pub enum Status {
    Ok = 0,
    Warning = 1,
    Error = 3,
    Fatal = 4,
}

/// Where an instance's messages go.
pub enum Logger {
    Fmi3 {
        callback: Fmi3Logger,
        environment: *mut c_void,
    },
    Fmi2 {
        callback: Fmi2Logger,
        environment: *mut c_void,
        instance_name: CString,
    },
}

/// A message as a C string (an interior NUL, which C cannot carry, as a space).
fn c_string(text: &str) -> CString {
    CString::new(text.replace('\0', " ")).unwrap_or_default()
}

impl Logger {
    /// Sends `message` in `category` (`logStatusError`, `logEvents`…) with `status`.
    pub fn log(&self, status: Status, category: &str, message: &str) {
        let (category, message) = (c_string(category), c_string(message));
        match self {
            Logger::Fmi3 {
                callback: Some(callback),
                environment,
            } => unsafe {
                callback(
                    *environment,
                    status as i32,
                    category.as_ptr(),
                    message.as_ptr(),
                )
            },
            Logger::Fmi2 {
                callback: Some(callback),
                environment,
                instance_name,
            } => unsafe {
                callback(
                    *environment,
                    instance_name.as_ptr(),
                    status as i32,
                    category.as_ptr(),
                    c"%s".as_ptr(),
                    message.as_ptr(),
                )
            },
            _ => {}
        }
    }
}
