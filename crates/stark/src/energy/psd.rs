//! Projection of element Hessians to positive semi-definite (projected Newton).
//!
//! Each element Hessian is projected before assembly so that the global matrix (plus the
//! positive inertia term) is positive definite and the Newton direction is a descent direction.
//! A cheap Cholesky attempt detects the common already-definite case; otherwise a cyclic Jacobi
//! eigen-decomposition clamps negative eigenvalues to zero (Teran et al. 2005; IPC, Li et al. 2020).

/// Largest supported element size (8 blocks of 3).
pub const MAX_DIM: usize = 24;

/// Is the symmetric row-major `n×n` matrix positive semi-definite? An `LDLᵀ` factorisation
/// with symmetric elimination: a pivot below `−tol` fails, a pivot within `±tol` must have a
/// (numerically) zero column and is skipped, so singular PSD matrices (rank-deficient bending or
/// barrier Hessians) pass without an eigen-decomposition. `tol` is relative to the largest
/// diagonal entry.
pub fn is_positive_semidefinite(h: &[f64], n: usize) -> bool {
    debug_assert!(n <= MAX_DIM);
    let scale = (0..n).map(|i| h[i * n + i].abs()).fold(0.0f64, f64::max);
    if scale == 0.0 {
        return h[..n * n].iter().all(|&x| x == 0.0);
    }
    if !scale.is_finite() {
        return false;
    }
    let tol = scale * 1e-10;
    let mut a = [0.0f64; MAX_DIM * MAX_DIM];
    a[..n * n].copy_from_slice(&h[..n * n]);
    for k in 0..n {
        let d = a[k * n + k];
        if d < -tol {
            return false;
        }
        if d <= tol {
            if (k + 1..n).any(|i| a[i * n + k].abs() > tol) {
                return false;
            }
            continue;
        }
        for i in k + 1..n {
            let f = a[i * n + k] / d;
            if f == 0.0 {
                continue;
            }
            for j in k + 1..=i {
                a[i * n + j] -= f * a[j * n + k];
            }
        }
        for i in k + 1..n {
            for j in k + 1..i {
                a[j * n + i] = a[i * n + j];
            }
        }
    }
    true
}

/// Eigen-decomposition of a symmetric row-major `n×n` matrix (nalgebra's Householder
/// tridiagonalisation and implicit QR; 3–5× faster than cyclic Jacobi at these sizes).
/// Returns eigenvalues in `w` and eigenvectors as the columns of `v` (row-major, stride `n`).
pub fn symmetric_eigen(h: &[f64], n: usize, w: &mut [f64], v: &mut [f64]) {
    let m = nalgebra::DMatrix::from_row_slice(n, n, &h[..n * n]);
    let e = m.symmetric_eigen();
    for i in 0..n {
        w[i] = e.eigenvalues[i];
        for j in 0..n {
            v[i * n + j] = e.eigenvectors[(i, j)];
        }
    }
}

/// Project the symmetric row-major `n×n` matrix `h` in place to the nearest positive
/// semi-definite matrix (negative eigenvalues set to zero). Returns whether it changed.
pub fn project_psd(h: &mut [f64], n: usize) -> bool {
    if is_positive_semidefinite(h, n) {
        return false;
    }
    let mut w = [0.0f64; MAX_DIM];
    let mut v = [0.0f64; MAX_DIM * MAX_DIM];
    symmetric_eigen(h, n, &mut w, &mut v[..n * n]);
    if w[..n].iter().all(|&x| x >= 0.0) {
        return false;
    }
    for i in 0..n {
        for j in 0..n {
            let mut s = 0.0;
            for k in 0..n {
                if w[k] > 0.0 {
                    s += v[i * n + k] * w[k] * v[j * n + k];
                }
            }
            h[i * n + j] = s;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn eigen_decomposition_reconstructs_matrix() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(0);
        for n in [3, 6, 12, 24] {
            let mut h = vec![0.0; n * n];
            for i in 0..n {
                for j in i..n {
                    let x: f64 = rng.random_range(-1.0..1.0);
                    h[i * n + j] = x;
                    h[j * n + i] = x;
                }
            }
            let mut w = vec![0.0; n];
            let mut v = vec![0.0; n * n];
            symmetric_eigen(&h, n, &mut w, &mut v);
            for i in 0..n {
                for j in 0..n {
                    let r: f64 = (0..n).map(|k| v[i * n + k] * w[k] * v[j * n + k]).sum();
                    assert!((r - h[i * n + j]).abs() < 1e-12 * n as f64, "n={n}");
                }
            }
        }
    }

    #[test]
    fn projection_clamps_negative_eigenvalues_only() {
        // diag(2, −1, 0.5) rotated.
        let n = 3;
        let (c, s) = (0.6f64, 0.8f64);
        let q = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]];
        let d = [2.0, -1.0, 0.5];
        let mut h = vec![0.0; 9];
        for i in 0..3 {
            for j in 0..3 {
                h[i * 3 + j] = (0..3).map(|k| q[i][k] * d[k] * q[j][k]).sum();
            }
        }
        assert!(!is_positive_semidefinite(&h, n));
        assert!(project_psd(&mut h, n));
        let mut w = [0.0; 3];
        let mut v = [0.0; 9];
        symmetric_eigen(&h, 3, &mut w, &mut v);
        let mut ws = w.to_vec();
        ws.sort_by(|a, b| a.partial_cmp(b).unwrap());
        assert!(ws[0].abs() < 1e-12 && (ws[1] - 0.5).abs() < 1e-12 && (ws[2] - 2.0).abs() < 1e-12);
        // A singular PSD matrix (rank one) passes the check.
        let k = [1.0, -2.0, 0.5];
        let rank_one: Vec<f64> = (0..9).map(|i| k[i / 3] * k[i % 3]).collect();
        assert!(is_positive_semidefinite(&rank_one, 3));
        // A definite matrix is left untouched.
        let mut spd = vec![2.0, 0.1, 0.0, 0.1, 1.0, 0.0, 0.0, 0.0, 3.0];
        let copy = spd.clone();
        assert!(!project_psd(&mut spd, 3));
        assert_eq!(spd, copy);
    }
}
