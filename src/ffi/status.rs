//! Stable status codes returned by every C entry point.

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
}
