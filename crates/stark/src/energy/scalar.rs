//! The scalar type energies are written in.
//!
//! Every energy is one generic function `fn energy<S: Scalar>(..) -> S`. It is evaluated with
//! - `f64` for plain values (line search),
//! - [`HyperDual`](super::dual::HyperDual) for exact gradients and Hessians (forward mode; the test
//!   oracle and the path for user energies),
//! - [`Sym`](super::symbolic::Sym) to trace an expression graph that is differentiated and emitted as
//!   Rust code (the fast path for the built-in energies, see `stark-codegen`).
//!
//! Because the symbolic scalar has no value, an energy must not branch on values with `if`; it uses
//! [`Scalar::select_gt`] instead, which the symbolic scalar records as a conditional node.

use std::fmt::Debug;
use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// Arithmetic needed by energies. Implemented by `f64`, `HyperDual<N>` and `Sym`.
///
/// Mixed operations with `f64` constants are available with the constant on the right
/// (`s * 2.0`, `s - 1.0`).
pub trait Scalar:
    Copy
    + Debug
    + Send
    + Sync
    + 'static
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + Add<f64, Output = Self>
    + Sub<f64, Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
{
    /// A constant (zero derivatives).
    fn constant(value: f64) -> Self;
    /// Zero.
    fn zero() -> Self {
        Self::constant(0.0)
    }
    /// Square root.
    fn sqrt(self) -> Self;
    /// Natural logarithm.
    fn ln(self) -> Self;
    /// Exponential.
    fn exp(self) -> Self;
    /// Sine.
    fn sin(self) -> Self;
    /// Cosine.
    fn cos(self) -> Self;
    /// Arc cosine.
    fn acos(self) -> Self;
    /// Four-quadrant arc tangent of `self / x`.
    fn atan2(self, x: Self) -> Self;
    /// Integer power.
    fn powi(self, n: i32) -> Self;
    /// Reciprocal `1/self`.
    fn recip(self) -> Self {
        Self::constant(1.0) / self
    }
    /// Square.
    fn sq(self) -> Self {
        self * self
    }
    /// `if a > b { then() } else { otherwise() }`, differentiable and traceable.
    ///
    /// Numeric scalars evaluate only the branch taken; the symbolic scalar records both and a
    /// conditional node. Both branches must therefore be safe to *trace*; the one not taken may be
    /// non-finite at the evaluation point (it is discarded).
    fn select_gt(a: Self, b: Self, then: impl FnOnce() -> Self, otherwise: impl FnOnce() -> Self) -> Self;
    /// `max(a, 0)` written with [`Scalar::select_gt`].
    fn positive_part(self) -> Self {
        Self::select_gt(self, Self::zero(), || self, Self::zero)
    }
}

impl Scalar for f64 {
    #[inline(always)]
    fn constant(value: f64) -> Self {
        value
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn ln(self) -> Self {
        f64::ln(self)
    }
    #[inline(always)]
    fn exp(self) -> Self {
        f64::exp(self)
    }
    #[inline(always)]
    fn sin(self) -> Self {
        f64::sin(self)
    }
    #[inline(always)]
    fn cos(self) -> Self {
        f64::cos(self)
    }
    #[inline(always)]
    fn acos(self) -> Self {
        f64::acos(self)
    }
    #[inline(always)]
    fn atan2(self, x: Self) -> Self {
        f64::atan2(self, x)
    }
    #[inline(always)]
    fn powi(self, n: i32) -> Self {
        f64::powi(self, n)
    }
    #[inline(always)]
    fn recip(self) -> Self {
        f64::recip(self)
    }
    #[inline(always)]
    fn select_gt(a: Self, b: Self, then: impl FnOnce() -> Self, otherwise: impl FnOnce() -> Self) -> Self {
        if a > b {
            then()
        } else {
            otherwise()
        }
    }
}
