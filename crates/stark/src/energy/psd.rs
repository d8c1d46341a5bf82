//! Projection of element Hessians to positive semi-definite (projected Newton).
//!
//! Each element Hessian is projected before assembly so that the global matrix (plus the
//! positive inertia term) is positive definite and the Newton direction is a descent direction.
//! A cheap Cholesky attempt detects the common already-definite case; otherwise a cyclic Jacobi
//! eigen-decomposition clamps negative eigenvalues to zero (Teran et al. 2005; IPC, Li et al. 2020).

/// Largest supported element size (8 blocks of 3).
pub const MAX_DIM: usize = 24;

/// Is the symmetric row-major `n×n` matrix positive definite (Cholesky succeeds with pivots above
/// a small relative threshold)?
pub fn is_positive_definite(h: &[f64], n: usize) -> bool {
    debug_assert!(n <= MAX_DIM);
    let scale = (0..n).map(|i| h[i * n + i].abs()).fold(0.0f64, f64::max);
    if scale == 0.0 {
        return false;
    }
    let threshold = scale * 1e-12;
    let mut l = [0.0f64; MAX_DIM * MAX_DIM];
    for j in 0..n {
        let mut d = h[j * n + j];
        for k in 0..j {
            d -= l[j * MAX_DIM + k] * l[j * MAX_DIM + k];
        }
        if d <= threshold || !d.is_finite() {
            return false;
        }
        let d = d.sqrt();
        l[j * MAX_DIM + j] = d;
        for i in j + 1..n {
            let mut s = h[i * n + j];
            for k in 0..j {
                s -= l[i * MAX_DIM + k] * l[j * MAX_DIM + k];
            }
            l[i * MAX_DIM + j] = s / d;
        }
    }
    true
}

/// Eigen-decomposition of a symmetric row-major `n×n` matrix by cyclic Jacobi rotations.
/// Returns eigenvalues in `w` and eigenvectors as the columns of `v` (row-major, stride `n`).
pub fn symmetric_eigen(h: &[f64], n: usize, w: &mut [f64], v: &mut [f64]) {
    let mut a = [0.0f64; MAX_DIM * MAX_DIM];
    a[..n * n].copy_from_slice(&h[..n * n]);
    for i in 0..n {
        for j in 0..n {
            v[i * n + j] = if i == j { 1.0 } else { 0.0 };
        }
    }
    let frob: f64 = a[..n * n].iter().map(|x| x * x).sum::<f64>().sqrt();
    for _sweep in 0..64 {
        let mut off = 0.0;
        for i in 0..n {
            for j in i + 1..n {
                off += a[i * n + j] * a[i * n + j];
            }
        }
        if off.sqrt() <= 1e-15 * frob || off == 0.0 {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[p * n + q];
                if apq.abs() <= 1e-300 {
                    continue;
                }
                let app = a[p * n + p];
                let aqq = a[q * n + q];
                // Rotation angle that zeroes a[p][q] (Golub & Van Loan, Alg. 8.4.1).
                let tau = (aqq - app) / (2.0 * apq);
                let t = tau.signum() / (tau.abs() + (1.0 + tau * tau).sqrt());
                let t = if tau == 0.0 { 1.0 } else { t };
                let c = 1.0 / (1.0 + t * t).sqrt();
                let s = t * c;
                for k in 0..n {
                    let akp = a[k * n + p];
                    let akq = a[k * n + q];
                    a[k * n + p] = c * akp - s * akq;
                    a[k * n + q] = s * akp + c * akq;
                }
                for k in 0..n {
                    let apk = a[p * n + k];
                    let aqk = a[q * n + k];
                    a[p * n + k] = c * apk - s * aqk;
                    a[q * n + k] = s * apk + c * aqk;
                }
                for k in 0..n {
                    let vkp = v[k * n + p];
                    let vkq = v[k * n + q];
                    v[k * n + p] = c * vkp - s * vkq;
                    v[k * n + q] = s * vkp + c * vkq;
                }
            }
        }
    }
    for i in 0..n {
        w[i] = a[i * n + i];
    }
}

/// Project the symmetric row-major `n×n` matrix `h` in place to the nearest positive
/// semi-definite matrix (negative eigenvalues set to zero). Returns whether it changed.
pub fn project_psd(h: &mut [f64], n: usize) -> bool {
    if is_positive_definite(h, n) {
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
        assert!(!is_positive_definite(&h, n));
        assert!(project_psd(&mut h, n));
        let mut w = [0.0; 3];
        let mut v = [0.0; 9];
        symmetric_eigen(&h, 3, &mut w, &mut v);
        let mut ws = w.to_vec();
        ws.sort_by(|a, b| a.partial_cmp(b).unwrap());
        assert!(ws[0].abs() < 1e-12 && (ws[1] - 0.5).abs() < 1e-12 && (ws[2] - 2.0).abs() < 1e-12);
        // A definite matrix is left untouched.
        let mut spd = vec![2.0, 0.1, 0.0, 0.1, 1.0, 0.0, 0.0, 0.0, 3.0];
        let copy = spd.clone();
        assert!(!project_psd(&mut spd, 3));
        assert_eq!(spd, copy);
    }
}
