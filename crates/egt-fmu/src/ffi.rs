//! The FMI 2.0 Co-Simulation C ABI: the `fmi2*` functions an importer loads
//! from the shared library, over [`Instance`]. This is the crate's only
//! `unsafe`: turning the importer's pointers into references and slices,
//! and calling its logger. Each instance is a `Box` the importer holds as
//! `fmi2Component` (no global state), and every call runs inside
//! `catch_unwind`, so a panic becomes `fmi2Error` with a message, never an
//! unwind into the importing process.
//!
//! The C types are declared here from the FMI 2.0.4 headers
//! (`fmi2TypesPlatform.h`, `fmi2FunctionTypes.h`): a handful of aliases and
//! one struct. The `fmi-sys` crate would bring them through bindgen (libclang
//! at build time) for an importer's needs; the exporter needs only these.

#![allow(non_camel_case_types, non_snake_case, clippy::missing_safety_doc)]

use std::ffi::{CStr, CString, c_char, c_int, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};

use crate::description::guid;
use crate::instance::Instance;

type fmi2Component = *mut c_void;
type fmi2ComponentEnvironment = *mut c_void;
type fmi2FMUstate = *mut c_void;
type fmi2ValueReference = u32;
type fmi2Real = f64;
type fmi2Integer = c_int;
type fmi2Boolean = c_int;
type fmi2String = *const c_char;
type fmi2Status = c_int;
type fmi2Type = c_int;
type fmi2StatusKind = c_int;
type fmi2Byte = c_char;

const OK: fmi2Status = 0;
const ERROR: fmi2Status = 3;
const CO_SIMULATION: fmi2Type = 1;

/// `fmi2CallbackLogger`: C-variadic, called with the format `"%s"` and the
/// message, so that a `%` in a message is never read as a conversion.
type Logger = unsafe extern "C" fn(
    fmi2ComponentEnvironment,
    fmi2String,
    fmi2Status,
    fmi2String,
    fmi2String,
    ...
);

#[repr(C)]
pub struct fmi2CallbackFunctions {
    logger: Option<Logger>,
    allocateMemory: Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>,
    freeMemory: Option<unsafe extern "C" fn(*mut c_void)>,
    stepFinished: Option<unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2Status)>,
    componentEnvironment: fmi2ComponentEnvironment,
}

/// What the importer holds: the instance and how to log to it.
struct Component {
    name: CString,
    logger: Option<Logger>,
    environment: fmi2ComponentEnvironment,
    instance: Instance,
}

/// Sends `message` to `logger` with `status` (the category names it).
fn log(
    logger: Option<Logger>,
    environment: fmi2ComponentEnvironment,
    name: &CStr,
    status: fmi2Status,
    message: &str,
) {
    let Some(logger) = logger else { return };
    let text = CString::new(message.replace('\0', " ")).unwrap_or_default();
    let category = if status == OK {
        c"logAll"
    } else {
        c"logStatusError"
    };
    // SAFETY: the importer gave this logger for this instance; every pointer
    // is a NUL-terminated string that lives across the call.
    unsafe {
        logger(
            environment,
            name.as_ptr(),
            status,
            category.as_ptr(),
            c"%s".as_ptr(),
            text.as_ptr(),
        );
    }
}

/// Runs `f` on the instance behind `c`: `fmi2OK`, or `fmi2Error` with the
/// refusal (or the panic) logged.
fn with(
    c: fmi2Component,
    call: &str,
    f: impl FnOnce(&mut Instance) -> Result<(), String>,
) -> c_int {
    if c.is_null() {
        return ERROR;
    }
    // SAFETY: a non-null component is one `fmi2Instantiate` returned and
    // `fmi2FreeInstance` has not freed (the importer's contract); calls on
    // one instance are not concurrent (FMI 2.0, section 2.1.5).
    let component = unsafe { &mut *c.cast::<Component>() };
    let outcome = catch_unwind(AssertUnwindSafe(|| f(&mut component.instance)));
    let message = match outcome {
        Ok(Ok(())) => return OK,
        Ok(Err(message)) => message,
        Err(panic) => {
            let what = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| (*s).to_string()))
                .unwrap_or_default();
            format!("internal error (a bug in egt): {what}")
        }
    };
    log(
        component.logger,
        component.environment,
        &component.name,
        ERROR,
        &format!("{call}: {message}"),
    );
    ERROR
}

/// `n` elements at `p` (an empty slice for `n = 0`, whatever `p`).
///
/// # Safety
/// `p` points to `n` valid elements that outlive the call.
unsafe fn slice<'a, T>(p: *const T, n: usize) -> Result<&'a [T], String> {
    if n == 0 {
        Ok(&[])
    } else if p.is_null() {
        Err("a null array".into())
    } else {
        // SAFETY: the caller's contract.
        Ok(unsafe { std::slice::from_raw_parts(p, n) })
    }
}

/// As [`slice`], mutable.
///
/// # Safety
/// As [`slice`], and no other reference to the elements.
unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Result<&'a mut [T], String> {
    if n == 0 {
        Ok(&mut [])
    } else if p.is_null() {
        Err("a null array".into())
    } else {
        // SAFETY: the caller's contract.
        Ok(unsafe { std::slice::from_raw_parts_mut(p, n) })
    }
}

/// The directory a `file:` URI names (percent-escapes decoded).
fn uri_path(uri: &str) -> Option<std::path::PathBuf> {
    let rest = uri.strip_prefix("file:")?;
    let rest = rest.strip_prefix("//localhost").unwrap_or(rest);
    let rest = match rest.strip_prefix("//") {
        Some(r) => r,
        None => rest,
    };
    let bytes = rest.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            let hex = std::str::from_utf8(&bytes[i + 1..i + 3]).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    Some(std::path::PathBuf::from(String::from_utf8(out).ok()?))
}

/// The spec in the unit's resources and the instance made from it.
fn instantiate(guid_given: &str, resources: &str) -> Result<Instance, String> {
    let dir = uri_path(resources)
        .ok_or_else(|| format!("the resource location `{resources}` is not a file: URI"))?;
    let spec = ["spec.toml", "spec.json"]
        .iter()
        .find_map(|f| std::fs::read_to_string(dir.join(f)).ok())
        .ok_or_else(|| format!("no spec.toml or spec.json in {}", dir.display()))?;
    let expected = guid(&spec);
    if guid_given != expected {
        return Err(format!(
            "the GUID {guid_given} is not this unit's ({expected}): the model description and the spec in the resources differ"
        ));
    }
    Instance::new(&spec)
}

/// # Safety
/// The FMI 2.0 contract: strings NUL-terminated, `functions` valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Instantiate(
    instanceName: fmi2String,
    fmuType: fmi2Type,
    fmuGUID: fmi2String,
    fmuResourceLocation: fmi2String,
    functions: *const fmi2CallbackFunctions,
    _visible: fmi2Boolean,
    _loggingOn: fmi2Boolean,
) -> fmi2Component {
    let text = |p: fmi2String| {
        if p.is_null() {
            String::new()
        } else {
            // SAFETY: a NUL-terminated string (the contract).
            unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
        }
    };
    // SAFETY: null or a valid struct (the contract); its fields are copied.
    let (logger, environment) = unsafe { functions.as_ref() }
        .map_or((None, std::ptr::null_mut()), |f| {
            (f.logger, f.componentEnvironment)
        });
    let name = CString::new(text(instanceName).replace('\0', " ")).unwrap_or_default();
    let made = catch_unwind(AssertUnwindSafe(|| {
        if fmuType != CO_SIMULATION {
            return Err("this unit is for Co-Simulation only".to_string());
        }
        instantiate(&text(fmuGUID), &text(fmuResourceLocation))
    }));
    match made {
        Ok(Ok(instance)) => Box::into_raw(Box::new(Component {
            name,
            logger,
            environment,
            instance,
        }))
        .cast(),
        Ok(Err(message)) => {
            log(
                logger,
                environment,
                &name,
                ERROR,
                &format!("fmi2Instantiate: {message}"),
            );
            std::ptr::null_mut()
        }
        Err(_) => {
            log(
                logger,
                environment,
                &name,
                ERROR,
                "fmi2Instantiate: internal error (a bug in egt)",
            );
            std::ptr::null_mut()
        }
    }
}

/// # Safety
/// `c` is null or a component of `fmi2Instantiate` not yet freed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeInstance(c: fmi2Component) {
    if !c.is_null() {
        // SAFETY: the box `fmi2Instantiate` leaked, freed once (the contract).
        drop(unsafe { Box::from_raw(c.cast::<Component>()) });
    }
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetDebugLogging(
    c: fmi2Component,
    _loggingOn: fmi2Boolean,
    _n: usize,
    _categories: *const fmi2String,
) -> fmi2Status {
    with(c, "fmi2SetDebugLogging", |_| Ok(()))
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetupExperiment(
    c: fmi2Component,
    _toleranceDefined: fmi2Boolean,
    _tolerance: fmi2Real,
    startTime: fmi2Real,
    _stopTimeDefined: fmi2Boolean,
    _stopTime: fmi2Real,
) -> fmi2Status {
    with(c, "fmi2SetupExperiment", |i| i.setup_experiment(startTime))
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status {
    with(
        c,
        "fmi2EnterInitializationMode",
        Instance::enter_initialization,
    )
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
    with(
        c,
        "fmi2ExitInitializationMode",
        Instance::exit_initialization,
    )
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
    with(c, "fmi2Terminate", Instance::terminate)
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
    with(c, "fmi2Reset", |i| {
        i.reset();
        Ok(())
    })
}

/// # Safety
/// `vr` and `value` point to `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Real,
) -> fmi2Status {
    with(c, "fmi2GetReal", |i| {
        // SAFETY: the contract.
        let (vr, value) = unsafe { (slice(vr, nvr)?, slice_mut(value, nvr)?) };
        i.get_real(vr, value)
    })
}

/// # Safety
/// `vr` and `value` point to `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Real,
) -> fmi2Status {
    with(c, "fmi2SetReal", |i| {
        // SAFETY: the contract.
        let (vr, value) = unsafe { (slice(vr, nvr)?, slice(value, nvr)?) };
        i.set_real(vr, value)
    })
}

/// # Safety
/// `vr` and `value` point to `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Integer,
) -> fmi2Status {
    with(c, "fmi2GetInteger", |i| {
        // SAFETY: the contract.
        let (vr, value) = unsafe { (slice(vr, nvr)?, slice_mut(value, nvr)?) };
        i.get_integer(vr, value)
    })
}

/// # Safety
/// `vr` and `value` point to `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Integer,
) -> fmi2Status {
    with(c, "fmi2SetInteger", |i| {
        // SAFETY: the contract.
        let (vr, value) = unsafe { (slice(vr, nvr)?, slice(value, nvr)?) };
        i.set_integer(vr, value)
    })
}

/// The unit has no boolean or string variables: only empty calls succeed.
fn none_of(nvr: usize, kind: &str) -> Result<(), String> {
    if nvr == 0 {
        Ok(())
    } else {
        Err(format!("the unit has no {kind} variables"))
    }
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetBoolean(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    nvr: usize,
    _value: *mut fmi2Boolean,
) -> fmi2Status {
    with(c, "fmi2GetBoolean", |_| none_of(nvr, "boolean"))
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetBoolean(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    nvr: usize,
    _value: *const fmi2Boolean,
) -> fmi2Status {
    with(c, "fmi2SetBoolean", |_| none_of(nvr, "boolean"))
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetString(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    nvr: usize,
    _value: *mut fmi2String,
) -> fmi2Status {
    with(c, "fmi2GetString", |_| none_of(nvr, "string"))
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetString(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    nvr: usize,
    _value: *const fmi2String,
) -> fmi2Status {
    with(c, "fmi2SetString", |_| none_of(nvr, "string"))
}

/// # Safety
/// `vr`, `order` and `value` point to `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    order: *const fmi2Integer,
    value: *const fmi2Real,
) -> fmi2Status {
    with(c, "fmi2SetRealInputDerivatives", |i| {
        // SAFETY: the contract.
        let (vr, order, value) =
            unsafe { (slice(vr, nvr)?, slice(order, nvr)?, slice(value, nvr)?) };
        i.set_input_derivatives(vr, order, value)
    })
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2DoStep(
    c: fmi2Component,
    currentCommunicationPoint: fmi2Real,
    communicationStepSize: fmi2Real,
    _noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
) -> fmi2Status {
    with(c, "fmi2DoStep", |i| {
        i.do_step(currentCommunicationPoint, communicationStepSize)
    })
}

/// A call the unit does not support (its capability flags say so): `fmi2Error`.
fn unsupported(c: fmi2Component, call: &str) -> fmi2Status {
    with(c, call, |_| Err("not supported by this unit".into()))
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetRealOutputDerivatives(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    _nvr: usize,
    _order: *const fmi2Integer,
    _value: *mut fmi2Real,
) -> fmi2Status {
    unsupported(c, "fmi2GetRealOutputDerivatives")
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2CancelStep(c: fmi2Component) -> fmi2Status {
    unsupported(c, "fmi2CancelStep")
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetStatus(
    c: fmi2Component,
    _s: fmi2StatusKind,
    _value: *mut fmi2Status,
) -> fmi2Status {
    unsupported(c, "fmi2GetStatus")
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetRealStatus(
    c: fmi2Component,
    _s: fmi2StatusKind,
    _value: *mut fmi2Real,
) -> fmi2Status {
    unsupported(c, "fmi2GetRealStatus")
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetIntegerStatus(
    c: fmi2Component,
    _s: fmi2StatusKind,
    _value: *mut fmi2Integer,
) -> fmi2Status {
    unsupported(c, "fmi2GetIntegerStatus")
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetBooleanStatus(
    c: fmi2Component,
    _s: fmi2StatusKind,
    _value: *mut fmi2Boolean,
) -> fmi2Status {
    unsupported(c, "fmi2GetBooleanStatus")
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetStringStatus(
    c: fmi2Component,
    _s: fmi2StatusKind,
    _value: *mut fmi2String,
) -> fmi2Status {
    unsupported(c, "fmi2GetStringStatus")
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetFMUstate(c: fmi2Component, _state: *mut fmi2FMUstate) -> fmi2Status {
    unsupported(c, "fmi2GetFMUstate")
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetFMUstate(c: fmi2Component, _state: fmi2FMUstate) -> fmi2Status {
    unsupported(c, "fmi2SetFMUstate")
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2FreeFMUstate(c: fmi2Component, _state: *mut fmi2FMUstate) -> fmi2Status {
    unsupported(c, "fmi2FreeFMUstate")
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2SerializedFMUstateSize(
    c: fmi2Component,
    _state: fmi2FMUstate,
    _size: *mut usize,
) -> fmi2Status {
    unsupported(c, "fmi2SerializedFMUstateSize")
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2SerializeFMUstate(
    c: fmi2Component,
    _state: fmi2FMUstate,
    _bytes: *mut fmi2Byte,
    _size: usize,
) -> fmi2Status {
    unsupported(c, "fmi2SerializeFMUstate")
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2DeSerializeFMUstate(
    c: fmi2Component,
    _bytes: *const fmi2Byte,
    _size: usize,
    _state: *mut fmi2FMUstate,
) -> fmi2Status {
    unsupported(c, "fmi2DeSerializeFMUstate")
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetDirectionalDerivative(
    c: fmi2Component,
    _vUnknown: *const fmi2ValueReference,
    _nUnknown: usize,
    _vKnown: *const fmi2ValueReference,
    _nKnown: usize,
    _dvKnown: *const fmi2Real,
    _dvUnknown: *mut fmi2Real,
) -> fmi2Status {
    unsupported(c, "fmi2GetDirectionalDerivative")
}

#[cfg(test)]
mod tests {
    use super::uri_path;

    #[test]
    fn file_uris_become_paths() {
        for (uri, path) in [
            ("file:///tmp/a%20b/resources", "/tmp/a b/resources"),
            ("file:/tmp/x/resources/", "/tmp/x/resources/"),
            ("file://localhost/tmp/y", "/tmp/y"),
        ] {
            assert_eq!(uri_path(uri).unwrap_or_default().to_str(), Some(path));
        }
        assert!(uri_path("http://example.org/x").is_none());
    }
}
