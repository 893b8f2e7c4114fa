//! Stable status codes returned by every C entry point.

use std::ffi::c_char;

/// Status code of a C call. Numbers are stable and never reused; a retired code stays
/// here as a comment.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RveStatus {
    /// Success.
    Ok = 0,
    /// A required pointer argument was NULL.
    NullArgument = 1,
    /// The scene could not be read, parsed or validated.
    BadScene = 2,
    /// Meshing or mesh import failed.
    MeshFailed = 3,
    /// A Rust panic was caught at the C boundary (a bug: please report it).
    Panic = 99,
}

impl RveStatus {
    /// Converts a raw number received from C; unknown numbers map to `None` so that a bad
    /// value never becomes an invalid enum.
    pub fn from_u32(code: u32) -> Option<Self> {
        Some(match code {
            0 => RveStatus::Ok,
            1 => RveStatus::NullArgument,
            2 => RveStatus::BadScene,
            3 => RveStatus::MeshFailed,
            99 => RveStatus::Panic,
            _ => return None,
        })
    }

    /// A static NUL-terminated description.
    fn message(self) -> &'static str {
        match self {
            RveStatus::Ok => "ok\0",
            RveStatus::NullArgument => "a required pointer argument was NULL\0",
            RveStatus::BadScene => "the scene could not be read, parsed or validated\0",
            RveStatus::MeshFailed => "meshing or mesh import failed\0",
            RveStatus::Panic => "internal error (panic caught at the C boundary)\0",
        }
    }
}

/// Returns a static NUL-terminated description of a status code (`RveStatus` value);
/// unknown codes give "unknown status code". Never NULL; the caller must not free it.
#[no_mangle]
pub extern "C" fn rve_status_message(code: u32) -> *const c_char {
    RveStatus::from_u32(code)
        .map(RveStatus::message)
        .unwrap_or("unknown status code\0")
        .as_ptr()
        .cast()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_round_trip_and_messages_are_terminated() {
        for code in [0, 1, 2, 3, 99] {
            let status = RveStatus::from_u32(code).unwrap();
            assert_eq!(status as u32, code);
            assert!(status.message().ends_with('\0'));
        }
        assert_eq!(RveStatus::from_u32(4), None);
        let unknown = unsafe { std::ffi::CStr::from_ptr(rve_status_message(12345)) };
        assert_eq!(unknown.to_str().unwrap(), "unknown status code");
    }
}
