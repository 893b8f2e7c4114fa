//! The guard of every entry point: the panic boundary, the per-thread last-error message
//! and the pointer checks, the private helpers every exported function goes through (rustls-ffi's `panic.rs` and
//! `ffi.rs`).

use std::cell::RefCell;
use std::panic::{catch_unwind, AssertUnwindSafe};

use super::status::RveStatus;
use crate::error::Error;
use crate::model::batch::{panic_message, PointError};

thread_local! {
    /// Detailed message of the last failed call on this thread ("" after a success).
    static LAST_ERROR: RefCell<String> = const { RefCell::new(String::new()) };
}

/// Why a C call failed: its status, a readable message and, for solver failures, the
/// suggested step ratio (PNEWDT).
#[derive(Debug, Clone)]
pub(crate) struct Failure {
    pub status: RveStatus,
    pub message: String,
    pub step_ratio: Option<f64>,
}

impl Failure {
    pub fn new(status: RveStatus, message: impl Into<String>) -> Self {
        Failure {
            status,
            message: message.into(),
            step_ratio: None,
        }
    }

    pub fn null(name: &str) -> Self {
        Failure::new(
            RveStatus::NullArgument,
            format!("argument `{name}` is NULL"),
        )
    }
}

impl From<Error> for Failure {
    fn from(e: Error) -> Self {
        let step_ratio = e.suggested_step_ratio();
        Failure {
            status: RveStatus::from(&e),
            message: e.to_string(),
            step_ratio,
        }
    }
}

pub(crate) type FfiResult<T = ()> = Result<T, Failure>;

/// Records the outcome of a call in the thread's last-error slot.
pub(crate) fn record(result: &FfiResult) -> RveStatus {
    LAST_ERROR.with(|m| {
        let mut m = m.borrow_mut();
        m.clear();
        match result {
            Ok(()) => RveStatus::Ok,
            Err(f) => {
                m.push_str(&f.message);
                f.status
            }
        }
    })
}

/// Copies the last-error message into `out` (tests).
pub(crate) fn last_error() -> String {
    LAST_ERROR.with(|m| m.borrow().clone())
}

/// Runs `f` inside the panic boundary and records its outcome. `name` is the exported
/// function's name, for the message after a panic.
pub(crate) fn guard(name: &str, f: impl FnOnce() -> FfiResult) -> RveStatus {
    let result = match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(payload) => {
            let what = panic_message(payload.as_ref());
            Err(Failure::new(
                RveStatus::Panic,
                format!("{name}: internal error (panic: {what}); please report it"),
            ))
        }
    };
    record(&result)
}

/// Checks a pointer to `n` readable values.
///
/// # Safety
/// A non-NULL `p` must point to `n` initialized values valid for `'a`.
pub(crate) unsafe fn slice<'a, T>(p: *const T, n: usize, name: &str) -> FfiResult<&'a [T]> {
    if p.is_null() {
        Err(Failure::null(name))
    } else {
        Ok(std::slice::from_raw_parts(p, n))
    }
}

/// Checks a pointer to `n` writable values.
///
/// # Safety
/// A non-NULL `p` must point to `n` values writable for `'a` and not aliased.
pub(crate) unsafe fn slice_mut<'a, T>(p: *mut T, n: usize, name: &str) -> FfiResult<&'a mut [T]> {
    if p.is_null() {
        Err(Failure::null(name))
    } else {
        Ok(std::slice::from_raw_parts_mut(p, n))
    }
}

/// Checks a pointer to one writable value.
///
/// # Safety
/// A non-NULL `p` must point to one value writable for `'a` and not aliased.
pub(crate) unsafe fn out<'a, T>(p: *mut T, name: &str) -> FfiResult<&'a mut T> {
    p.as_mut().ok_or_else(|| Failure::null(name))
}

/// Copies a message into a caller buffer of `len` bytes, truncated and NUL-terminated
/// (nothing is written when `len` is 0). Returns the full message length without NUL.
///
/// # Safety
/// A non-NULL `buf` must point to `len` writable bytes.
pub(crate) unsafe fn copy_message(message: &str, buf: *mut u8, len: usize) -> usize {
    if !buf.is_null() && len > 0 {
        let n = message.len().min(len - 1);
        std::ptr::copy_nonoverlapping(message.as_ptr(), buf, n);
        *buf.add(n) = 0;
    }
    message.len()
}

/// Copies the detailed message of the last failed `rve_*` call on the calling thread
/// into `buf` (at most `len` bytes, always NUL-terminated when `len > 0`, truncated if
/// needed), and returns the full message length in bytes without the NUL. Pass
/// `buf = NULL, len = 0` to query the length. The message is "" after a successful call.
/// Every `rve_*` function except this one, `rve_version*` and `rve_status_message`
/// overwrites it. Never fails.
///
/// # Safety
/// Each non-NULL pointer must point to valid memory of the documented size (strings:
/// NUL-terminated) for the duration of the call.
#[no_mangle]
pub unsafe extern "C" fn rve_last_error(buf: *mut std::ffi::c_char, len: usize) -> usize {
    catch_unwind(AssertUnwindSafe(|| {
        LAST_ERROR.with(|m| copy_message(&m.borrow(), buf.cast(), len))
    }))
    .unwrap_or(0)
}

impl PointError for Failure {
    fn suggested_step_ratio(&self) -> Option<f64> {
        self.step_ratio
    }
}
