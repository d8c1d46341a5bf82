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
/// space, projecting `h_f` first when `project` is set. `w` are [`gradient_weights`]: node 0's
/// are minus the sum of the others', so node 0's gradient and Hessian blocks are minus the sums
/// of the others' (a rigid translation leaves `F` unchanged), and only the blocks between nodes
/// `1..N` are contracted, each pair once (the Hessian is symmetric).
pub fn map_to_nodes<const N: usize, const C: usize>(
    w: &[[f64; C]; N],
    value: f64,
    g_f: &[f64],
    h_f: &mut [f64],
    project: bool,
    out: &mut HyperDual<N>,
) {
    debug_assert!((0..C).all(|c| {
        let sum: f64 = (0..N).map(|a| w[a][c]).sum();
        sum.abs() <= 1e-9 * (0..N).map(|a| w[a][c].abs()).sum::<f64>()
    }));
    let m = 3 * C;
    if project {
        project_psd(h_f, m);
    }
    out.value = value;
    for l in 0..3 {
        let mut sum = 0.0;
        for a in 1..N {
            let g: f64 = (0..C).map(|c| g_f[l * C + c] * w[a][c]).sum();
            out.grad[a][l] = g;
            sum += g;
        }
        out.grad[0][l] = -sum;
    }
    // H[(a,l),(b,k)] = Σ_{c,d} w_ac w_bd H_F[(l,c),(k,d)]. First contract the right index:
    // t[(l,c), b, k] = Σ_d H_F[(l,c),(k,d)] w_bd, for b ≥ 1.
    let mut t = [[[0.0f64; 3]; 4]; 9];
    for lc in 0..m {
        for b in 1..N {
            for k in 0..3 {
                t[lc][b][k] = (0..C).map(|d| h_f[lc * m + k * C + d] * w[b][d]).sum();
            }
        }
    }
    for a in 1..N {
        for b in a..N {
            for l in 0..3 {
                // Within a diagonal block, each entry pair once.
                let k0 = if a == b { l } else { 0 };
                for k in k0..3 {
                    let v: f64 = (0..C).map(|c| w[a][c] * t[l * C + c][b][k]).sum();
                    out.hess[a][l][b][k] = v;
                    out.hess[b][k][a][l] = v;
                }
            }
        }
    }
    // Node 0: H[(0,l),(b,k)] = −Σ_{a≥1} H[(a,l),(b,k)], and H[(0,l),(0,k)] = −Σ_{b≥1} of those.
    for b in 1..N {
        for l in 0..3 {
            for k in 0..3 {
                let v: f64 = -(1..N).map(|a| out.hess[a][l][b][k]).sum::<f64>();
                out.hess[0][l][b][k] = v;
                out.hess[b][k][0][l] = v;
            }
        }
    }
    for l in 0..3 {
        for k in l..3 {
            let v: f64 = -(1..N).map(|b| out.hess[0][l][b][k]).sum::<f64>();
            out.hess[0][l][0][k] = v;
            out.hess[0][k][0][l] = v;
        }
    }
}
