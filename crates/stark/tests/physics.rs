//! Physics against analytic and independently computed answers (DESIGN.md §7).
//!
//! One test binary; each claim is one file under `tests/physics/`, named after what it asserts.
//! Run with `cargo test --release -p stark --test physics -- --nocapture` to see the tables.

// `tests/physics.rs` is this binary's root, so a plain `mod physics;` would find both this file
// and `physics/mod.rs`; name the directory module explicitly.
#[path = "physics/mod.rs"]
mod physics;
