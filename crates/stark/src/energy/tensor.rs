//! Small vectors and matrices over any [`Scalar`], for writing energies generically.
//!
//! nalgebra is used for `f64` linear algebra everywhere else; these types exist because energies
//! must also run on dual and symbolic scalars, which do not implement nalgebra's numeric traits.

use super::scalar::Scalar;
use std::ops::{Add, Index, IndexMut, Mul, Neg, Sub};

/// A 3-vector of scalars.
#[derive(Clone, Copy, Debug)]
pub struct Vec3<S>(pub [S; 3]);

impl<S: Scalar> Vec3<S> {
    /// From components.
    #[inline(always)]
    pub fn new(x: S, y: S, z: S) -> Self {
        Vec3([x, y, z])
    }
    /// Lift an `f64` vector to constants.
    #[inline(always)]
    pub fn constant(v: &nalgebra::Vector3<f64>) -> Self {
        Vec3([S::constant(v.x), S::constant(v.y), S::constant(v.z)])
    }
    /// The zero vector.
    #[inline(always)]
    pub fn zero() -> Self {
        Vec3([S::zero(); 3])
    }
    /// Dot product.
    #[inline(always)]
    pub fn dot(&self, o: &Self) -> S {
        self.0[0] * o.0[0] + self.0[1] * o.0[1] + self.0[2] * o.0[2]
    }
    /// Dot product with a constant vector.
    #[inline(always)]
    pub fn dot_f64(&self, o: &nalgebra::Vector3<f64>) -> S {
        self.0[0] * o.x + self.0[1] * o.y + self.0[2] * o.z
    }
    /// Cross product.
    #[inline(always)]
    pub fn cross(&self, o: &Self) -> Self {
        let [a0, a1, a2] = self.0;
        let [b0, b1, b2] = o.0;
        Vec3([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])
    }
    /// Squared Euclidean norm.
    #[inline(always)]
    pub fn norm_sq(&self) -> S {
        self.dot(self)
    }
    /// Euclidean norm.
    #[inline(always)]
    pub fn norm(&self) -> S {
        self.norm_sq().sqrt()
    }
    /// Unit vector in the same direction.
    #[inline(always)]
    pub fn normalized(&self) -> Self {
        *self * self.norm().recip()
    }
    /// Scale by a constant.
    #[inline(always)]
    pub fn scale(&self, s: f64) -> Self {
        Vec3([self.0[0] * s, self.0[1] * s, self.0[2] * s])
    }
    /// Add a constant vector.
    #[inline(always)]
    pub fn add_f64(&self, o: &nalgebra::Vector3<f64>) -> Self {
        Vec3([self.0[0] + o.x, self.0[1] + o.y, self.0[2] + o.z])
    }
    /// Subtract a constant vector.
    #[inline(always)]
    pub fn sub_f64(&self, o: &nalgebra::Vector3<f64>) -> Self {
        Vec3([self.0[0] - o.x, self.0[1] - o.y, self.0[2] - o.z])
    }
}

impl Vec3<f64> {
    /// Convert to nalgebra.
    pub fn to_na(&self) -> nalgebra::Vector3<f64> {
        nalgebra::Vector3::new(self.0[0], self.0[1], self.0[2])
    }
}

impl<S> Index<usize> for Vec3<S> {
    type Output = S;
    #[inline(always)]
    fn index(&self, i: usize) -> &S {
        &self.0[i]
    }
}
impl<S> IndexMut<usize> for Vec3<S> {
    #[inline(always)]
    fn index_mut(&mut self, i: usize) -> &mut S {
        &mut self.0[i]
    }
}
impl<S: Scalar> Add for Vec3<S> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Vec3([self.0[0] + o.0[0], self.0[1] + o.0[1], self.0[2] + o.0[2]])
    }
}
impl<S: Scalar> Sub for Vec3<S> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Vec3([self.0[0] - o.0[0], self.0[1] - o.0[1], self.0[2] - o.0[2]])
    }
}
impl<S: Scalar> Neg for Vec3<S> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Vec3([-self.0[0], -self.0[1], -self.0[2]])
    }
}
impl<S: Scalar> Mul<S> for Vec3<S> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: S) -> Self {
        Vec3([self.0[0] * s, self.0[1] * s, self.0[2] * s])
    }
}

/// A dense `R×C` matrix of scalars, row-major.
#[derive(Clone, Copy, Debug)]
pub struct Mat<S, const R: usize, const C: usize>(pub [[S; C]; R]);

/// 3×3 matrix.
pub type Mat3<S> = Mat<S, 3, 3>;
/// 2×2 matrix.
pub type Mat2<S> = Mat<S, 2, 2>;
/// 3×2 matrix (a triangle's deformation gradient).
pub type Mat32<S> = Mat<S, 3, 2>;

impl<S: Scalar, const R: usize, const C: usize> Mat<S, R, C> {
    /// The zero matrix.
    pub fn zero() -> Self {
        Mat([[S::zero(); C]; R])
    }
    /// Lift a constant matrix given row-major.
    pub fn constant(m: &[[f64; C]; R]) -> Self {
        Mat(m.map(|row| row.map(S::constant)))
    }
    /// Transpose.
    pub fn transpose(&self) -> Mat<S, C, R> {
        let mut t = Mat::<S, C, R>::zero();
        for i in 0..R {
            for j in 0..C {
                t.0[j][i] = self.0[i][j];
            }
        }
        t
    }
    /// Matrix product.
    pub fn mul_mat<const K: usize>(&self, o: &Mat<S, C, K>) -> Mat<S, R, K> {
        let mut out = Mat::<S, R, K>::zero();
        for i in 0..R {
            for k in 0..K {
                let mut acc = self.0[i][0] * o.0[0][k];
                for j in 1..C {
                    acc += self.0[i][j] * o.0[j][k];
                }
                out.0[i][k] = acc;
            }
        }
        out
    }
    /// Product with a constant matrix (`self · o`). Skips exact zeros of `o`, which matters for
    /// traced code.
    pub fn mul_f64<const K: usize>(&self, o: &[[f64; K]; C]) -> Mat<S, R, K> {
        let mut out = Mat::<S, R, K>::zero();
        for i in 0..R {
            for k in 0..K {
                let mut acc: Option<S> = None;
                for j in 0..C {
                    if o[j][k] != 0.0 {
                        let term = self.0[i][j] * o[j][k];
                        acc = Some(match acc {
                            Some(a) => a + term,
                            None => term,
                        });
                    }
                }
                out.0[i][k] = acc.unwrap_or_else(S::zero);
            }
        }
        out
    }
    /// Squared Frobenius norm.
    pub fn frobenius_norm_sq(&self) -> S {
        let mut acc = S::zero();
        for i in 0..R {
            for j in 0..C {
                acc += self.0[i][j] * self.0[i][j];
            }
        }
        acc
    }
    /// Entry-wise scaling.
    pub fn scale(&self, s: S) -> Self {
        Mat(self.0.map(|row| row.map(|x| x * s)))
    }
    /// Entry-wise sum.
    pub fn add(&self, o: &Self) -> Self {
        let mut out = *self;
        for i in 0..R {
            for j in 0..C {
                out.0[i][j] = self.0[i][j] + o.0[i][j];
            }
        }
        out
    }
    /// Entry-wise difference.
    pub fn sub(&self, o: &Self) -> Self {
        let mut out = *self;
        for i in 0..R {
            for j in 0..C {
                out.0[i][j] = self.0[i][j] - o.0[i][j];
            }
        }
        out
    }
    /// Matrix built from column vectors of length 3 (only for `R == 3`).
    pub fn from_columns3(cols: [Vec3<S>; C]) -> Self {
        assert_eq!(R, 3);
        let mut m = Self::zero();
        for (j, c) in cols.iter().enumerate() {
            for i in 0..3 {
                m.0[i][j] = c.0[i];
            }
        }
        m
    }
}

impl<S: Scalar, const N: usize> Mat<S, N, N> {
    /// Trace.
    pub fn trace(&self) -> S {
        let mut acc = self.0[0][0];
        for i in 1..N {
            acc += self.0[i][i];
        }
        acc
    }
    /// `self - s·I`.
    pub fn sub_identity(&self, s: f64) -> Self {
        let mut out = *self;
        for i in 0..N {
            out.0[i][i] = out.0[i][i] - s;
        }
        out
    }
}

impl<S: Scalar> Mat3<S> {
    /// Determinant.
    pub fn det(&self) -> S {
        let m = &self.0;
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    }
}

impl<S: Scalar> Mat2<S> {
    /// Determinant.
    pub fn det(&self) -> S {
        self.0[0][0] * self.0[1][1] - self.0[0][1] * self.0[1][0]
    }
    /// Eigenvalues of a symmetric 2×2 matrix, largest first:
    /// `½(a + b ± √((a − b)² + 4c²))`.
    pub fn symmetric_eigenvalues(&self) -> [S; 2] {
        let a = self.0[0][0];
        let b = self.0[1][1];
        let c = self.0[0][1];
        let delta = ((a - b).sq() + c.sq() * 4.0).sqrt();
        [(a + b + delta) * 0.5, (a + b - delta) * 0.5]
    }
}

/// View a flat coordinate slice `[x0, y0, z0, x1, …]` as `N` points (used by traced kernels).
pub fn points_from_flat<S: Scalar, const N: usize>(x: &[S]) -> [Vec3<S>; N] {
    std::array::from_fn(|a| Vec3([x[3 * a], x[3 * a + 1], x[3 * a + 2]]))
}

/// Flatten `N` points to `[x0, y0, z0, x1, …]`.
pub fn flat_from_points<const N: usize>(x: &[nalgebra::Vector3<f64>; N], out: &mut [f64]) {
    for (a, p) in x.iter().enumerate() {
        out[3 * a..3 * a + 3].copy_from_slice(p.as_slice());
    }
}
