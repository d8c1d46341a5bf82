//! Generated value/gradient/Hessian kernels of the built-in energies (DESIGN §2, "derivatives are
//! automatic", path 2).
//!
//! `kernels.rs` is written by `cargo run -p stark-codegen`, which traces each energy's generic
//! function with the symbolic scalar, differentiates it and emits straight-line Rust. Do not edit
//! it by hand: change the energy, then regenerate. A test in stark-codegen fails when the file is
//! stale, and every energy's tests compare its kernel with the hyper-dual derivatives. The list
//! of kernel specs lives in stark-codegen too: the models import this module, not the reverse.

#[rustfmt::skip]
#[allow(clippy::all, clippy::pedantic, unused_variables, unused_parens, missing_docs)]
mod kernels;
pub use kernels::*;
