//! Stable status codes returned by every C entry point, and the one mapping from
//! [`crate::Error`].

use std::ffi::c_char;

use crate::error::Error;

/// Status code of a C call. Numbers are stable and never reused; a retired code stays
/// here as a comment. `rve_status_message` gives a static description of each code;
/// `rve_last_error` gives the detailed message of the last failed call on this thread.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RveStatus {
    /// Success.
    Ok = 0,
    /// A required pointer argument was NULL.
    NullArgument = 1,
    /// The scene could not be read, parsed or validated.
    BadScene = 2,
    /// The microstructure could not be placed, meshed or imported.
    MeshFailed = 3,
    /// The handle is 0 where an instance is required, was freed, or never came from
    /// `rve_init_*` in this process.
    BadHandle = 4,
    /// A strain component is NaN or infinite.
    NonFiniteStrain = 5,
    /// A strain component exceeds the model's bound (`|eps| > 0.1`: not a small strain).
    AbsurdStrain = 6,
    /// The RVE solver failed even after sub-stepping. The committed state is unchanged;
    /// retry with a smaller increment (`RveInfo::suggested_step_ratio`).
    SolverFailed = 7,
    /// `rve_commit` without a successful `rve_update` since the last commit/revert/reset.
    NoTrial = 8,
    /// The instance is in use by another thread right now (one instance, one thread at a
    /// time). Nothing was done; the instance is intact.
    InstanceBusy = 9,
    /// An argument has a bad value (unknown tangent request, length overflow, ...).
    InvalidArgument = 10,
    /// The output buffer is too small; the required size was written where documented.
    BufferTooSmall = 11,
    /// State bytes are not a mesorve state (bad magic, truncated or undecodable) or were
    /// corrupted (their checksum does not match: any flipped bit).
    BadState = 12,
    /// State bytes were written in a state format this library does not read.
    StateVersion = 13,
    /// State bytes belong to a model of another size (another scene).
    StateMismatch = 14,
    /// At least one item of `rve_update_batch` failed; see its `statuses` array.
    BatchFailed = 15,
    /// An output file could not be written (`rve_write_vtk`: missing directory, no
    /// permission, disk full); `rve_last_error` names the path and the system's reason.
    WriteFailed = 16,
    /// The sparse linear algebra failed outside a solve: the symbolic analysis of the
    /// RVE's matrix pattern (`rve_init_*`). A failed factorization within a solve is
    /// `SOLVER_FAILED`.
    LinearAlgebraFailed = 17,
    /// An internal invariant was violated (a bug: please report it).
    Internal = 98,
    /// A Rust panic was caught at the C boundary (a bug: please report it).
    Panic = 99,
}

/// Every status, for tests and documentation.
pub const ALL_STATUSES: [RveStatus; 20] = [
    RveStatus::Ok,
    RveStatus::NullArgument,
    RveStatus::BadScene,
    RveStatus::MeshFailed,
    RveStatus::BadHandle,
    RveStatus::NonFiniteStrain,
    RveStatus::AbsurdStrain,
    RveStatus::SolverFailed,
    RveStatus::NoTrial,
    RveStatus::InstanceBusy,
    RveStatus::InvalidArgument,
    RveStatus::BufferTooSmall,
    RveStatus::BadState,
    RveStatus::StateVersion,
    RveStatus::StateMismatch,
    RveStatus::BatchFailed,
    RveStatus::WriteFailed,
    RveStatus::LinearAlgebraFailed,
    RveStatus::Internal,
    RveStatus::Panic,
];

impl RveStatus {
    /// Converts a raw number received from C; unknown numbers map to `None` so that a bad
    /// value never becomes an invalid enum.
    pub fn from_u32(code: u32) -> Option<Self> {
        ALL_STATUSES.iter().copied().find(|s| *s as u32 == code)
    }

    /// A static NUL-terminated description.
    fn message(self) -> &'static str {
        match self {
            RveStatus::Ok => "ok\0",
            RveStatus::NullArgument => "a required pointer argument was NULL\0",
            RveStatus::BadScene => "the scene could not be read, parsed or validated\0",
            RveStatus::MeshFailed => "meshing or mesh import failed\0",
            RveStatus::BadHandle => "bad handle: 0, freed, or not from rve_init\0",
            RveStatus::NonFiniteStrain => "a strain component is NaN or infinite\0",
            RveStatus::AbsurdStrain => "a strain component exceeds the small-strain bound\0",
            RveStatus::SolverFailed => {
                "the RVE solver failed; committed state unchanged, retry with a smaller step\0"
            }
            RveStatus::NoTrial => "no trial to commit: call rve_update first\0",
            RveStatus::InstanceBusy => "the instance is in use by another thread\0",
            RveStatus::InvalidArgument => "an argument has an invalid value\0",
            RveStatus::BufferTooSmall => "the output buffer is too small\0",
            RveStatus::BadState => "the bytes are not a valid mesorve state\0",
            RveStatus::StateVersion => "the state was saved in an unsupported format version\0",
            RveStatus::StateMismatch => "the state belongs to a model of another scene\0",
            RveStatus::BatchFailed => "at least one item of the batch failed\0",
            RveStatus::WriteFailed => "an output file could not be written\0",
            RveStatus::LinearAlgebraFailed => {
                "the sparse linear algebra failed (symbolic analysis of the RVE matrix)\0"
            }
            RveStatus::Internal => "internal error (a bug: please report it)\0",
            RveStatus::Panic => "internal error (panic caught at the C boundary)\0",
        }
    }

    /// The description without the NUL.
    pub fn text(self) -> &'static str {
        let m = self.message();
        &m[..m.len() - 1]
    }
}

impl TryFrom<u32> for RveStatus {
    type Error = u32;
    fn try_from(code: u32) -> Result<Self, u32> {
        RveStatus::from_u32(code).ok_or(code)
    }
}

impl From<&Error> for RveStatus {
    /// The one mapping from the core error type to a status code.
    fn from(e: &Error) -> Self {
        match e {
            Error::Scene { .. }
            | Error::SceneParse(_)
            | Error::Io { .. }
            | Error::SceneNotFound { .. } => RveStatus::BadScene,
            Error::Placement(_) | Error::Gmsh { .. } | Error::Mesh(_) => RveStatus::MeshFailed,
            Error::BadStrain { strain, .. } => {
                if strain.iter().all(|e| e.is_finite()) {
                    RveStatus::AbsurdStrain
                } else {
                    RveStatus::NonFiniteStrain
                }
            }
            Error::Solve { .. } => RveStatus::SolverFailed,
            Error::LinearAlgebra(_) => RveStatus::LinearAlgebraFailed,
            Error::WorkspaceMismatch | Error::StateEncoding { .. } => RveStatus::Internal,
            Error::NoTrial => RveStatus::NoTrial,
            Error::BadState { .. } => RveStatus::BadState,
            Error::StateVersion { .. } => RveStatus::StateVersion,
            Error::StateMismatch { .. } | Error::StateOwner { .. } => RveStatus::StateMismatch,
            Error::StateStrain { .. } | Error::StateTime { .. } | Error::StateLost { .. } => {
                RveStatus::BadState
            }
            Error::HostConvention(_) => RveStatus::InvalidArgument,
            Error::Panic(_) => RveStatus::Panic,
            Error::Threads(_) => RveStatus::Internal,
        }
    }
}

/// Returns a static NUL-terminated description of a status code (`RveStatus` value);
/// unknown codes give "unknown status code". Never NULL; the caller must not free it.
/// For the detailed message of the last failure on this thread see `rve_last_error`.
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
        let mut seen = std::collections::HashSet::new();
        for status in ALL_STATUSES {
            let code = status as u32;
            assert!(seen.insert(code), "duplicate code {code}");
            assert_eq!(RveStatus::try_from(code), Ok(status));
            assert!(status.message().ends_with('\0'));
            assert!(!status.text().contains('\0'));
        }
        assert_eq!(RveStatus::from_u32(18), None);
        assert_eq!(RveStatus::try_from(97), Err(97));
        let unknown = unsafe { std::ffi::CStr::from_ptr(rve_status_message(12345)) };
        assert_eq!(unknown.to_str().unwrap(), "unknown status code");
    }

    #[test]
    fn errors_map_to_distinct_codes() {
        let nan = Error::BadStrain {
            strain: [f64::NAN, 0.0, 0.0],
            reason: String::new(),
        };
        let big = Error::BadStrain {
            strain: [1.0, 0.0, 0.0],
            reason: String::new(),
        };
        assert_eq!(RveStatus::from(&nan), RveStatus::NonFiniteStrain);
        assert_eq!(RveStatus::from(&big), RveStatus::AbsurdStrain);
        assert_eq!(
            RveStatus::from(&Error::SceneParse(String::new())),
            RveStatus::BadScene
        );
        assert_eq!(
            RveStatus::from(&Error::Mesh(String::new())),
            RveStatus::MeshFailed
        );
        assert_eq!(RveStatus::from(&Error::NoTrial), RveStatus::NoTrial);
        let analysis = crate::error::LinearAlgebraError::Analysis {
            factorization: "LU",
            reason: String::new(),
        };
        assert_eq!(
            RveStatus::from(&Error::from(analysis)),
            RveStatus::LinearAlgebraFailed
        );
        let bad = Error::BadState {
            reason: String::new(),
        };
        let version = Error::StateVersion {
            found: 9,
            older: &[1],
            current: 2,
        };
        let mismatch = Error::StateMismatch {
            saved_unknowns: 1,
            saved_history: 2,
            unknowns: 3,
            history: 4,
        };
        let encoding = Error::StateEncoding {
            reason: String::new(),
        };
        assert_eq!(RveStatus::from(&bad), RveStatus::BadState);
        assert_eq!(RveStatus::from(&version), RveStatus::StateVersion);
        assert_eq!(RveStatus::from(&mismatch), RveStatus::StateMismatch);
        assert_eq!(RveStatus::from(&encoding), RveStatus::Internal);
    }
}
