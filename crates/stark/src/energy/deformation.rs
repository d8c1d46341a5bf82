//! Energies of the deformation gradient: derivatives in `F`-space mapped to node positions.
//!
//! For a linear element the deformation gradient `F = D_s D_m⁻¹` is linear in the node
//! positions: `∂F_ic/∂x_{a,l} = δ_il w_ac` with `w_kc = (D_m⁻¹)_kc` for the nodes `k ≥ 1` and
//! `w_0c = −Σ_k (D_m⁻¹)_kc`. So an energy `Ψ(F)` has `∇ₓΨ = Dᵀ ∇_F Ψ` and `Hₓ = Dᵀ H_F D`.
//! Projecting the small `H_F` (9×9 for tets, 6×6 for membranes) instead of `Hₓ` is cheaper and
//! still gives a positive semi-definite `Hₓ` (Teran et al. 2005, the usual practice for
//! hyperelastic solids).

use super::dual::HyperDual;
use super::psd::project_psd;

/// The weights `w[a][c]` of node `a` in column `c` of `F`, from `D_m⁻¹` (`(N−1) × C`).
pub fn gradient_weights<const N: usize, const C: usize>(dm_inv: &[[f64; C]]) -> [[f64; C]; N] {
    let mut w = [[0.0; C]; N];
    for k in 1..N {
        for c in 0..C {
            w[k][c] = dm_inv[k - 1][c];
            w[0][c] -= dm_inv[k - 1][c];
        }
    }
    w
}

/// `F` (row-major `3 × C`) of node positions `x` given the weights.
pub fn deformation_gradient<const N: usize, const C: usize>(
    w: &[[f64; C]; N],
    x: &[nalgebra::Vector3<f64>; N],
    f: &mut [f64],
) {
    for i in 0..3 {
        for c in 0..C {
            f[i * C + c] = (0..N).map(|a| x[a][i] * w[a][c]).sum();
        }
    }
}

/// Map `F`-space gradient `g_f` (length `3C`) and Hessian `h_f` (`3C × 3C`, row-major) to node
/// space, projecting `h_f` first when `project` is set.
pub fn map_to_nodes<const N: usize, const C: usize>(
    w: &[[f64; C]; N],
    value: f64,
    g_f: &[f64],
    h_f: &mut [f64],
    project: bool,
    out: &mut HyperDual<N>,
) {
    let m = 3 * C;
    if project {
        project_psd(h_f, m);
    }
    out.value = value;
    for a in 0..N {
        for l in 0..3 {
            out.grad[a][l] = (0..C).map(|c| g_f[l * C + c] * w[a][c]).sum();
        }
    }
    // H[(a,l),(b,k)] = Σ_{c,d} w_ac w_bd H_F[(l,c),(k,d)]. First contract the right index:
    // t[(l,c), b, k] = Σ_d H_F[(l,c),(k,d)] w_bd.
    let mut t = [[[0.0f64; 3]; 4]; 9];
    for lc in 0..m {
        for b in 0..N {
            for k in 0..3 {
                t[lc][b][k] = (0..C).map(|d| h_f[lc * m + k * C + d] * w[b][d]).sum();
            }
        }
    }
    for a in 0..N {
        for l in 0..3 {
            for b in 0..N {
                for k in 0..3 {
                    out.hess[a][l][b][k] = (0..C).map(|c| w[a][c] * t[l * C + c][b][k]).sum();
                }
            }
        }
    }
}
