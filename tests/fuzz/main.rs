//! Seeded, bounded fuzzing on stable Rust (`cargo test --release --test fuzz`): mutated
//! scene text, mutated Gmsh files, random sequences of C calls, corrupted state bytes.
//! See `driver.rs` for the bounds and the environment variables, and
//! `docs/reliability.md` for the figures.

mod call_sequences;
mod driver;
mod gmsh_files;
mod scene_text;
mod state_bytes;
