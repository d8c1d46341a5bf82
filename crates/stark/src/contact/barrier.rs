//! Contact barriers as functions of the (unsquared) distance `d` and the activation distance `d̂`.
//!
//! - Log barrier (IPC, Li et al. 2020, written in `d` as in DESIGN §4):
//!   `b(d) = −(d − d̂)² ln(d/d̂)` for `0 < d < d̂`, 0 beyond, `+∞` at contact. Because it is
//!   infinite at `d = 0`, a state with finite energy has no touching pair: this is what makes
//!   "never penetrates" a guarantee together with CCD in the line search.
//!   `b'(d) = −2(d − d̂) ln(d/d̂) − (d − d̂)²/d`,
//!   `b''(d) = −2 ln(d/d̂) − 4(d − d̂)/d + (d − d̂)²/d²`.
//! - Cubic penalty (the original Stark's default): `b(d) = (d̂ − d)³/3`, finite at contact, for
//!   comparison with Stark.
//!
//! Both are C² at `d̂`, positive and decreasing on `(0, d̂)`; the energy of a pair is `κ·b(d)`.

use crate::energy::Scalar;
use serde::{Deserialize, Serialize};

/// Which barrier function contact uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, strum::VariantNames)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
pub enum BarrierKind {
    /// IPC log barrier, infinite at contact (default).
    Log,
    /// Cubic penalty `(d̂ − d)³/3` (the original Stark's), finite at contact.
    Cubic,
}

/// `(b, b', b'')` at `d` for activation distance `dhat` (zeros for `d ≥ d̂`; for the log barrier
/// `+∞` at `d ≤ 0`).
pub fn barrier(kind: BarrierKind, d: f64, dhat: f64) -> (f64, f64, f64) {
    if d >= dhat {
        return (0.0, 0.0, 0.0);
    }
    match kind {
        BarrierKind::Log => {
            if d <= 0.0 {
                return (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY);
            }
            let r = d - dhat;
            let l = (d / dhat).ln();
            (
                -r * r * l,
                -2.0 * r * l - r * r / d,
                -2.0 * l - 4.0 * r / d + r * r / (d * d),
            )
        }
        BarrierKind::Cubic => {
            let r = dhat - d;
            (r * r * r / 3.0, -r * r, 2.0 * r)
        }
    }
}

/// The barrier written generically (for the hyper-dual oracle and traced energies).
pub fn barrier_generic<S: Scalar>(kind: BarrierKind, d: S, dhat: f64) -> S {
    S::select_gt(d, S::constant(dhat), S::zero, || match kind {
        BarrierKind::Log => -(d - dhat).sq() * (d * (1.0 / dhat)).ln(),
        BarrierKind::Cubic => (-d + dhat).powi(3) * (1.0 / 3.0),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::HyperDual;

    #[test]
    fn derivatives_match_the_generic_form() {
        for kind in [BarrierKind::Log, BarrierKind::Cubic] {
            for d in [1e-6, 1e-3, 0.3e-2, 0.7e-2, 0.999e-2] {
                let dhat = 1e-2;
                let (b, db, ddb) = barrier(kind, d, dhat);
                let x = HyperDual::<1>::variable(d, 0, 0);
                let g = barrier_generic(kind, x, dhat);
                assert!((g.value - b).abs() <= 1e-12 * b.abs().max(1e-30));
                assert!((g.grad[0][0] - db).abs() <= 1e-10 * db.abs().max(1e-20), "{kind:?} {d}");
                assert!(
                    (g.hess[0][0][0][0] - ddb).abs() <= 1e-9 * ddb.abs().max(1e-20),
                    "{kind:?} {d}"
                );
                // Repulsive: positive, decreasing, convex.
                assert!(b > 0.0 && db < 0.0 && ddb > 0.0);
            }
            assert_eq!(barrier(kind, 0.02, 0.01), (0.0, 0.0, 0.0));
        }
        assert!(barrier(BarrierKind::Log, 0.0, 0.01).0.is_infinite());
    }
}
