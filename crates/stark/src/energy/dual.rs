//! Forward-mode hyper-dual numbers: value, gradient and Hessian with respect to the `3N`
//! coordinates of an `N`-node stencil.
//!
//! Exact (no truncation error) and needing no code generation, so they serve as the permanent
//! oracle for every energy and as the derivative path for user energies. They cost `O((3N)²)` per
//! operation; the built-in hot energies use generated code instead (see `generated/`).
//!
//! Only the upper triangle of the Hessian is propagated; [`HyperDual::hessian_full`] mirrors it.

use super::scalar::Scalar;
use super::tensor::Vec3;
use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// Value, gradient and (upper-triangular) Hessian with respect to `3N` variables.
#[derive(Clone, Copy, Debug)]
pub struct HyperDual<const N: usize> {
    /// Value.
    pub value: f64,
    /// Gradient, `[node][coordinate]`.
    pub grad: [[f64; 3]; N],
    /// Hessian, `[node_a][coord_i][node_b][coord_j]`; only entries with flat index row ≤ column
    /// are maintained.
    pub hess: [[[[f64; 3]; N]; 3]; N],
}

impl<const N: usize> HyperDual<N> {
    const D: usize = 3 * N;

    /// The variable `x[node][coord]` with the given value (unit gradient).
    pub fn variable(value: f64, node: usize, coord: usize) -> Self {
        let mut d = Self::constant(value);
        d.grad[node][coord] = 1.0;
        d
    }

    /// The stencil positions as variables.
    pub fn variables(x: &[nalgebra::Vector3<f64>; N]) -> [Vec3<Self>; N] {
        std::array::from_fn(|a| Vec3(std::array::from_fn(|i| Self::variable(x[a][i], a, i))))
    }

    #[inline(always)]
    fn g(&self) -> &[f64] {
        self.grad.as_flattened()
    }
    #[inline(always)]
    fn g_mut(&mut self) -> &mut [f64] {
        self.grad.as_flattened_mut()
    }
    #[inline(always)]
    fn h(&self) -> &[f64] {
        self.hess.as_flattened().as_flattened().as_flattened()
    }
    #[inline(always)]
    fn h_mut(&mut self) -> &mut [f64] {
        self.hess.as_flattened_mut().as_flattened_mut().as_flattened_mut()
    }

    /// Gradient as a flat slice of length `3N`.
    pub fn gradient_flat(&self) -> &[f64] {
        self.g()
    }

    /// The full symmetric Hessian, row-major `3N × 3N`.
    pub fn hessian_full(&self) -> Vec<f64> {
        let d = Self::D;
        let mut h = self.h().to_vec();
        for i in 0..d {
            for j in 0..i {
                h[i * d + j] = h[j * d + i];
            }
        }
        h
    }

    /// `f(self)` given `f`, `f'` and `f''` at the value.
    #[inline]
    fn chain(&self, f: f64, df: f64, ddf: f64) -> Self {
        let d = Self::D;
        let mut out = Self::constant(f);
        {
            let g = self.g();
            let og = out.g_mut();
            for i in 0..d {
                og[i] = df * g[i];
            }
        }
        let g = self.g();
        let h = self.h();
        let oh = out.h_mut();
        for i in 0..d {
            let gi = ddf * g[i];
            for j in i..d {
                oh[i * d + j] = df * h[i * d + j] + gi * g[j];
            }
        }
        out
    }

    /// `f(self, o)` given the value and first and second partial derivatives.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn chain2(&self, o: &Self, f: f64, fa: f64, fb: f64, faa: f64, fab: f64, fbb: f64) -> Self {
        let d = Self::D;
        let mut out = Self::constant(f);
        let (ga, gb) = (self.g(), o.g());
        {
            let og = out.g_mut();
            for i in 0..d {
                og[i] = fa * ga[i] + fb * gb[i];
            }
        }
        let (ha, hb) = (self.h(), o.h());
        let oh = out.h_mut();
        for i in 0..d {
            for j in i..d {
                oh[i * d + j] = fa * ha[i * d + j]
                    + fb * hb[i * d + j]
                    + faa * ga[i] * ga[j]
                    + fab * (ga[i] * gb[j] + gb[i] * ga[j])
                    + fbb * gb[i] * gb[j];
            }
        }
        out
    }
}

impl<const N: usize> Add for HyperDual<N> {
    type Output = Self;
    #[inline]
    fn add(mut self, o: Self) -> Self {
        self += o;
        self
    }
}
impl<const N: usize> AddAssign for HyperDual<N> {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        self.value += o.value;
        for (a, b) in self.g_mut().iter_mut().zip(o.g()) {
            *a += b;
        }
        for (a, b) in self.h_mut().iter_mut().zip(o.h()) {
            *a += b;
        }
    }
}
impl<const N: usize> Sub for HyperDual<N> {
    type Output = Self;
    #[inline]
    fn sub(mut self, o: Self) -> Self {
        self -= o;
        self
    }
}
impl<const N: usize> SubAssign for HyperDual<N> {
    #[inline]
    fn sub_assign(&mut self, o: Self) {
        self.value -= o.value;
        for (a, b) in self.g_mut().iter_mut().zip(o.g()) {
            *a -= b;
        }
        for (a, b) in self.h_mut().iter_mut().zip(o.h()) {
            *a -= b;
        }
    }
}
impl<const N: usize> Neg for HyperDual<N> {
    type Output = Self;
    #[inline]
    fn neg(mut self) -> Self {
        self.value = -self.value;
        self.g_mut().iter_mut().for_each(|a| *a = -*a);
        self.h_mut().iter_mut().for_each(|a| *a = -*a);
        self
    }
}
impl<const N: usize> Mul for HyperDual<N> {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        self.chain2(&o, self.value * o.value, o.value, self.value, 0.0, 1.0, 0.0)
    }
}
impl<const N: usize> MulAssign for HyperDual<N> {
    #[inline]
    fn mul_assign(&mut self, o: Self) {
        *self = *self * o;
    }
}
// a/b = a·(1/b): the reciprocal carries the derivatives of the division.
#[allow(clippy::suspicious_arithmetic_impl)]
impl<const N: usize> Div for HyperDual<N> {
    type Output = Self;
    #[inline]
    fn div(self, o: Self) -> Self {
        self * o.recip()
    }
}
impl<const N: usize> Add<f64> for HyperDual<N> {
    type Output = Self;
    #[inline]
    fn add(mut self, c: f64) -> Self {
        self.value += c;
        self
    }
}
impl<const N: usize> Sub<f64> for HyperDual<N> {
    type Output = Self;
    #[inline]
    fn sub(mut self, c: f64) -> Self {
        self.value -= c;
        self
    }
}
impl<const N: usize> Mul<f64> for HyperDual<N> {
    type Output = Self;
    #[inline]
    fn mul(mut self, c: f64) -> Self {
        self.value *= c;
        self.g_mut().iter_mut().for_each(|a| *a *= c);
        self.h_mut().iter_mut().for_each(|a| *a *= c);
        self
    }
}
impl<const N: usize> Div<f64> for HyperDual<N> {
    type Output = Self;
    #[inline]
    fn div(self, c: f64) -> Self {
        self * (1.0 / c)
    }
}

impl<const N: usize> Scalar for HyperDual<N> {
    fn constant(value: f64) -> Self {
        HyperDual {
            value,
            grad: [[0.0; 3]; N],
            hess: [[[[0.0; 3]; N]; 3]; N],
        }
    }
    fn sqrt(self) -> Self {
        let s = self.value.sqrt();
        self.chain(s, 0.5 / s, -0.25 / (s * self.value))
    }
    fn ln(self) -> Self {
        let x = self.value;
        self.chain(x.ln(), 1.0 / x, -1.0 / (x * x))
    }
    fn exp(self) -> Self {
        let e = self.value.exp();
        self.chain(e, e, e)
    }
    fn sin(self) -> Self {
        let (s, c) = self.value.sin_cos();
        self.chain(s, c, -s)
    }
    fn cos(self) -> Self {
        let (s, c) = self.value.sin_cos();
        self.chain(c, -s, -c)
    }
    fn acos(self) -> Self {
        let x = self.value;
        let r = 1.0 - x * x;
        let d = -1.0 / r.sqrt();
        self.chain(x.acos(), d, d * x / r)
    }
    fn atan2(self, x: Self) -> Self {
        let (a, b) = (self.value, x.value);
        let r2 = a * a + b * b;
        let r4 = r2 * r2;
        // f = atan2(a, b): f_a = b/r², f_b = −a/r², f_aa = −2ab/r⁴, f_ab = (a² − b²)/r⁴, f_bb = 2ab/r⁴
        self.chain2(
            &x,
            a.atan2(b),
            b / r2,
            -a / r2,
            -2.0 * a * b / r4,
            (a * a - b * b) / r4,
            2.0 * a * b / r4,
        )
    }
    fn powi(self, n: i32) -> Self {
        let x = self.value;
        let nf = n as f64;
        let d = if n == 0 { 0.0 } else { nf * x.powi(n - 1) };
        let dd = if n == 0 || n == 1 {
            0.0
        } else {
            nf * (nf - 1.0) * x.powi(n - 2)
        };
        self.chain(x.powi(n), d, dd)
    }
    fn recip(self) -> Self {
        let r = 1.0 / self.value;
        self.chain(r, -r * r, 2.0 * r * r * r)
    }
    fn select_gt(a: Self, b: Self, then: impl FnOnce() -> Self, otherwise: impl FnOnce() -> Self) -> Self {
        if a.value > b.value {
            then()
        } else {
            otherwise()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// f(x, y, z) = x² y + sin(z) · ln(y) / x + atan2(y, z) + sqrt(x·z)
    fn f<S: Scalar>(x: S, y: S, z: S) -> S {
        x * x * y + z.sin() * y.ln() / x + y.atan2(z) + (x * z).sqrt() + x.powi(3).acos().exp() * 0.1
    }

    #[test]
    fn gradient_and_hessian_match_finite_differences() {
        let p = [0.3, 1.7, 0.9];
        let d = |i| HyperDual::<1>::variable(p[i], 0, i);
        let r = f(d(0), d(1), d(2));
        assert!((r.value - f(p[0], p[1], p[2])).abs() < 1e-14);
        let h = 1e-5;
        let fe = |q: [f64; 3]| f(q[0], q[1], q[2]);
        let hess = r.hessian_full();
        for i in 0..3 {
            let mut a = p;
            let mut b = p;
            a[i] += h;
            b[i] -= h;
            let fd = (fe(a) - fe(b)) / (2.0 * h);
            assert!((fd - r.grad[0][i]).abs() < 1e-8 * (1.0 + fd.abs()), "grad {i}");
            for j in 0..3 {
                let fd2 = {
                    let g = |q: [f64; 3]| {
                        let dq = |k| HyperDual::<1>::variable(q[k], 0, k);
                        f(dq(0), dq(1), dq(2)).grad[0][j]
                    };
                    (g(a) - g(b)) / (2.0 * h)
                };
                assert!((fd2 - hess[i * 3 + j]).abs() < 1e-6 * (1.0 + fd2.abs()), "hess {i}{j}");
            }
        }
    }
}
