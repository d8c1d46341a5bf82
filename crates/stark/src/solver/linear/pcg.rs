//! Block-Jacobi preconditioned conjugate gradients (the default linear solver, as in Stark's
//! BDPCG): the preconditioner inverts the 3×3 diagonal blocks.

use super::block_sparse::{dot, BlockSparseMatrix};
use nalgebra::Matrix3;
use rayon::prelude::*;

/// Outcome of a CG solve.
#[derive(Clone, Copy, Debug, Default)]
pub struct CgInfo {
    /// Iterations performed.
    pub iterations: usize,
    /// Final preconditioner-free residual norm `‖b − A x‖₂`.
    pub residual_norm: f64,
    /// The tolerance was reached.
    pub converged: bool,
    /// A direction of non-positive curvature was met (the matrix is not positive definite); the
    /// iterate before it is returned.
    pub indefinite: bool,
}

/// Inverse diagonal blocks of `a`. A singular block (a DOF with no stiffness and no mass) is
/// replaced by the identity, so the preconditioner stays well defined.
pub fn block_jacobi(a: &BlockSparseMatrix) -> Vec<[f64; 9]> {
    (0..a.n_blocks)
        .into_par_iter()
        .map(|r| {
            let b = &a.values[a.diagonal[r]];
            let m = Matrix3::from_row_slice(b);
            match m.try_inverse() {
                Some(inv) if inv.iter().all(|x| x.is_finite()) => {
                    let mut out = [0.0; 9];
                    for i in 0..3 {
                        for j in 0..3 {
                            out[3 * i + j] = inv[(i, j)];
                        }
                    }
                    out
                }
                _ => [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
            }
        })
        .collect()
}

fn apply_preconditioner(inv_diag: &[[f64; 9]], r: &[f64], z: &mut [f64]) {
    z.par_chunks_mut(3)
        .zip(r.par_chunks(3))
        .zip(inv_diag.par_iter())
        .for_each(|((z, r), m)| {
            z[0] = m[0] * r[0] + m[1] * r[1] + m[2] * r[2];
            z[1] = m[3] * r[0] + m[4] * r[1] + m[5] * r[2];
            z[2] = m[6] * r[0] + m[7] * r[1] + m[8] * r[2];
        });
}

/// Solve `A x = b` to `‖b − A x‖₂ ≤ tolerance`, starting from `x = 0`, block-Jacobi
/// preconditioned.
pub fn solve(a: &BlockSparseMatrix, b: &[f64], x: &mut [f64], tolerance: f64, max_iterations: usize) -> CgInfo {
    let inv_diag = block_jacobi(a);
    solve_preconditioned(a, b, x, tolerance, max_iterations, &mut |r, z| {
        apply_preconditioner(&inv_diag, r, z)
    })
}

/// [`solve`] with the preconditioner `precondition(r, z)`: `z ≈ A⁻¹ r` (symmetric positive
/// definite).
pub fn solve_preconditioned(
    a: &BlockSparseMatrix,
    b: &[f64],
    x: &mut [f64],
    tolerance: f64,
    max_iterations: usize,
    precondition: &mut dyn FnMut(&[f64], &mut [f64]),
) -> CgInfo {
    let n = b.len();
    x.iter_mut().for_each(|v| *v = 0.0);
    let mut r = b.to_vec();
    let mut z = vec![0.0; n];
    let mut ap = vec![0.0; n];
    precondition(&r, &mut z);
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut info = CgInfo {
        residual_norm: dot(&r, &r).sqrt(),
        ..Default::default()
    };
    if info.residual_norm <= tolerance {
        info.converged = true;
        return info;
    }
    while info.iterations < max_iterations {
        let pap = a.mul_vec_dot(&p, &mut ap);
        if pap <= 0.0 || !pap.is_finite() {
            info.indefinite = true;
            break;
        }
        let alpha = rz / pap;
        x.par_iter_mut().zip(p.par_iter()).for_each(|(x, p)| *x += alpha * p);
        r.par_iter_mut().zip(ap.par_iter()).for_each(|(r, ap)| *r -= alpha * ap);
        info.iterations += 1;
        info.residual_norm = dot(&r, &r).sqrt();
        if info.residual_norm <= tolerance {
            info.converged = true;
            break;
        }
        precondition(&r, &mut z);
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        p.par_iter_mut().zip(z.par_iter()).for_each(|(p, z)| *p = z + beta * *p);
    }
    info
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 1D chain of 3×3 blocks: tridiagonal SPD (Laplacian plus mass).
    fn chain(n: usize) -> BlockSparseMatrix {
        let mut pairs = vec![];
        for i in 0..n as u32 {
            if i > 0 {
                pairs.push((i, i - 1));
            }
            pairs.push((i, i));
            if (i as usize) < n - 1 {
                pairs.push((i, i + 1));
            }
        }
        let mut a = BlockSparseMatrix::from_sorted_pairs(n, &pairs);
        for r in 0..n {
            for idx in a.row_start[r]..a.row_start[r + 1] {
                let c = a.cols[idx] as usize;
                let v = if c == r { 2.1 } else { -1.0 };
                a.values[idx] = [
                    v,
                    0.0,
                    0.0,
                    0.0,
                    v * 1.5,
                    0.1 * (c == r) as i32 as f64,
                    0.0,
                    0.1 * (c == r) as i32 as f64,
                    v,
                ];
            }
        }
        a
    }

    #[test]
    fn solves_spd_chain() {
        for n in [5, 50, 400] {
            let a = chain(n);
            let b: Vec<f64> = (0..3 * n).map(|i| ((i * 7) % 11) as f64 - 5.0).collect();
            let mut x = vec![0.0; 3 * n];
            let info = solve(&a, &b, &mut x, 1e-12, 10_000);
            assert!(info.converged, "{info:?}");
            let mut ax = vec![0.0; 3 * n];
            a.mul_vec(&x, &mut ax);
            let err = ax.iter().zip(&b).map(|(p, q)| (p - q).abs()).fold(0.0, f64::max);
            assert!(err < 1e-10 * n as f64, "n = {n}: {err}");
        }
    }
}
