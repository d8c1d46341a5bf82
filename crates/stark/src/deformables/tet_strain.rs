//! Volumetric solids: Stable Neo-Hookean strain energy of linear tetrahedra, with strain-rate
//! damping and strain limiting.
//!
//! Energy per tet, times the rest volume `V` (Smith et al. 2022, "Stable Neo-Hookean Flesh
//! Simulation", eq. 49; the same form as the original Stark):
//!
//! `ψ(F) = μ'/2 (I_C − 3) + λ'/2 (J − α)² − μ'/2 ln(I_C + 1)`, with `F = D_s D_m⁻¹`,
//! `I_C = ‖F‖²_F`, `J = det F`, `μ' = 4μ/3`, `λ' = λ + 5μ/6`, `α = 1 + 3μ'/(4λ')` (so the rest
//! state is stress free), and the Lamé parameters of Young's modulus `E` and Poisson's ratio `ν`.
//!
//! Damping is a Rayleigh dissipation `½ c ‖Ė‖²` on the Green strain rate `Ė ≈ (E₁ − E₀)/dt`; in
//! the velocity-form objective it enters as `dt · ½ c ‖Ė‖² = ½ (c/dt) ‖E₁ − E₀‖²`, so the damping
//! stress `c Ė` does not depend on the step size. (Stark omits the factor `dt`, so its damping
//! grows as `1/dt`.)
//!
//! Strain limiting adds `k (λ̃ − ε_max)³/3` when a smooth upper bound of the largest principal
//! Green strain, `λ̃ = tr E/3 + √(2/3) ‖dev E‖`, exceeds the limit.

use super::{globalize, Groups, NodeSetHandle};
use crate::energy::deformation::{deformation_gradient, gradient_weights, map_to_nodes};
use crate::energy::kinematics::{DeformableRow, DerivativeSink};
use crate::energy::symbolic::{KernelSpec, Sym};
use crate::energy::{FastDerivatives, HyperDual, Mat, Mat3, Node, Potential, Scalar, Stencil, Vec3};
use crate::error::{check_param, Result, StarkError};
use crate::generated;
use crate::state::NodeArrays;
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

crate::params::param_struct! {
    /// Volumetric strain of a solid (Stable Neo-Hookean tets with strain limiting).
    #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct TetStrainParams {
        /// Young's modulus, Pa (default: 1e3).
        pub youngs_modulus: f64,
        /// Poisson's ratio, unitless in (0, 0.5) (default: 0.3).
        pub poissons_ratio: f64,
        /// Strain-rate damping coefficient `c`, Pa·s (default: 0).
        pub damping: f64,
        /// Green strain above which the strain-limiting penalty acts, unitless (default: ∞, off).
        pub strain_limit: f64,
        /// Stiffness of the strain-limiting penalty, Pa (default: 1e3).
        pub strain_limit_stiffness: f64,
        /// Uniform scale of the rest shape (growth or shrinkage), unitless (default: 1).
        pub scale: f64,
    }
}

impl Default for TetStrainParams {
    fn default() -> Self {
        TetStrainParams {
            youngs_modulus: 1e3,
            poissons_ratio: 0.3,
            damping: 0.0,
            strain_limit: f64::INFINITY,
            strain_limit_stiffness: 1e3,
            scale: 1.0,
        }
    }
}

impl TetStrainParams {
    /// Check every field; the error names `object` and the field.
    pub fn validate(&self, object: &str) -> Result<()> {
        let e = self.youngs_modulus;
        check_param(
            object,
            "youngs_modulus",
            e,
            e > 0.0 && e.is_finite(),
            "must be positive and finite (Pa)",
        )?;
        let nu = self.poissons_ratio;
        check_param(
            object,
            "poissons_ratio",
            nu,
            nu > 0.0 && nu < 0.5,
            "must lie in (0, 0.5)",
        )?;
        let c = self.damping;
        check_param(
            object,
            "damping",
            c,
            c >= 0.0 && c.is_finite(),
            "must be non-negative and finite (Pa·s)",
        )?;
        check_param(
            object,
            "strain_limit",
            self.strain_limit,
            self.strain_limit > 0.0,
            "must be positive (∞ disables it)",
        )?;
        let k = self.strain_limit_stiffness;
        check_param(
            object,
            "strain_limit_stiffness",
            k,
            k >= 0.0 && k.is_finite(),
            "must be non-negative and finite (Pa)",
        )?;
        let s = self.scale;
        check_param(
            object,
            "scale",
            s,
            s > 0.0 && s.is_finite(),
            "must be positive and finite",
        )
    }

    /// Lamé parameters `(μ, λ)` in Pa.
    pub fn lame(&self) -> (f64, f64) {
        let (e, nu) = (self.youngs_modulus, self.poissons_ratio);
        (e / (2.0 * (1.0 + nu)), e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)))
    }
}

/// Handle to a group of tets added together.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct TetStrainHandle(pub u32);

/// Rest data of one tet.
#[derive(Clone, Copy, Debug)]
struct TetRest {
    /// `D_m⁻¹` at scale 1, row-major.
    dm_inv: [[f64; 3]; 3],
    /// Rest volume at scale 1, m³.
    volume: f64,
}

/// The Stable Neo-Hookean tet energy of all volumetric objects.
#[derive(Default)]
pub struct TetStrain {
    groups: Groups<TetStrainParams>,
    tets: Vec<[u32; 4]>,
    group: Vec<u32>,
    rest: Vec<TetRest>,
    version: u64,
}

/// Parameters of the `Ψ(F)` kernels: `V`, `μ'`, `λ'`, `α`, `c/dt`, `E₀` (xx, yy, zz, xy, yz, zx),
/// `ε_max`, `k`.
pub const PSI_PARAMS: usize = 13;
/// Parameters of the position-space energy: `D_m⁻¹` (9, row-major) then the `Ψ(F)` parameters.
pub const PARAMS: usize = 9 + PSI_PARAMS;

/// How the strain-limiting term enters a traced energy.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Limiting {
    /// Left out (the limit is not reached).
    Off,
    /// Decided inside the energy with a branch (the oracle).
    Branch,
    /// Included unconditionally (the limit is exceeded).
    Active,
}

/// Smooth upper bound `tr E/3 + √(2/3) ‖dev E‖` of the largest principal Green strain. A tiny
/// regulariser (1e-10 in strain) keeps it differentiable at pure dilation.
fn largest_strain_bound<S: Scalar>(e: &Mat3<S>) -> S {
    let third = e.trace() * (1.0 / 3.0);
    let dev_sq = e.sub_identity(0.0).frobenius_norm_sq() - third.sq() * 3.0;
    third + (dev_sq + 1e-20).sqrt() * (2.0f64 / 3.0).sqrt()
}

/// The elastic part of `ψ` in the invariants `I_C = ‖F‖²_F` and `J = det F` (parameters `μ'`,
/// `λ'`, `α`).
fn elastic_density<S: Scalar>(ic: S, j: S, mu_: S, lambda_: S, alpha: S) -> S {
    mu_ * (ic - 3.0) * 0.5 + lambda_ * (j - alpha).sq() * 0.5 - mu_ * (ic + 1.0).ln() * 0.5
}

/// Node-space value, gradient and Hessian of `V ψ(I_C, J)` (the elastic energy, no damping or
/// limiting) by the chain rule through the invariants, with no `9 × 9` Hessian in `F`:
///
/// `∂ψ/∂F = 2ψ_I F + ψ_J cof F` and `∂²ψ/∂F² = 2ψ_I 𝕀 + 4ψ_II f fᵀ + 2ψ_IJ (f gᵀ + g fᵀ) +
/// ψ_JJ g gᵀ + ψ_J ∂²J/∂F²` (`f = vec F`, `g = vec cof F`). With `F = Σ_a x_a w_aᵀ`, node `a`'s
/// gradient is `P w_a` and block `(a, b)` of the Hessian is `2ψ_I (w_a·w_b) I + p_a s_bᵀ +
/// q_a t_bᵀ + ψ_J ε·(F (w_a × w_b))`, where `p_a = F w_a`, `q_a = cof F w_a`, `s_b = 4ψ_II p_b +
/// 2ψ_IJ q_b`, `t_b = 2ψ_IJ p_b + ψ_JJ q_b`, and the last term is the cross-product matrix that
/// `∂²J/∂F_ic ∂F_jd = ε_ijk ε_cdl F_kl` contracts to. The scalar derivatives `ψ_I … ψ_JJ` are
/// automatic (the generated kernel of `ψ(I_C, J)`). About half the work of the generated `Ψ(F)`
/// kernel and its `9 × 9 → 12 × 12` map; equal to it to round-off (tests).
fn elastic_derivatives_by_invariants(w: &[[f64; 3]; 4], f: &[f64; 9], p: &[f64], out: &mut impl DerivativeSink) {
    let fm = Matrix3::from_row_slice(f);
    // cof F: its columns are the cross products of F's columns.
    let (c0, c1, c2) = (fm.column(0), fm.column(1), fm.column(2));
    let cof = Matrix3::from_columns(&[c1.cross(&c2), c2.cross(&c0), c0.cross(&c1)]);
    let j = c0.dot(&cof.column(0));
    let (mut d, mut dd) = ([0.0; 2], [0.0; 4]);
    let value = generated::tet_psi_invariants(&[fm.norm_squared(), j], p, &mut d, &mut dd);
    let [psi_i, psi_j] = d;
    let [psi_ii, psi_ij, _, psi_jj] = dd;
    let wv: [Vector3<f64>; 4] = w.map(Vector3::from);
    let pa: [Vector3<f64>; 4] = wv.map(|wa| fm * wa);
    let qa: [Vector3<f64>; 4] = wv.map(|wa| cof * wa);
    out.set_value(value);
    for a in 0..4 {
        out.set_gradient(a, &(2.0 * psi_i * pa[a] + psi_j * qa[a]));
    }
    let sa: [Vector3<f64>; 4] = std::array::from_fn(|b| 4.0 * psi_ii * pa[b] + 2.0 * psi_ij * qa[b]);
    let ta: [Vector3<f64>; 4] = std::array::from_fn(|b| 2.0 * psi_ij * pa[b] + psi_jj * qa[b]);
    for a in 0..4 {
        for b in a..4 {
            let mut block = pa[a] * sa[b].transpose() + qa[a] * ta[b].transpose();
            let diagonal = 2.0 * psi_i * wv[a].dot(&wv[b]);
            for i in 0..3 {
                block[(i, i)] += diagonal;
            }
            if a != b {
                // ε_ijk v_k with v = F (w_a × w_b): the cross-product matrix of −ψ_J v.
                let v = psi_j * (fm * wv[a].cross(&wv[b]));
                block[(0, 1)] += v.z;
                block[(1, 0)] -= v.z;
                block[(0, 2)] -= v.y;
                block[(2, 0)] += v.y;
                block[(1, 2)] += v.x;
                block[(2, 1)] -= v.x;
            }
            out.set_hessian_pair(a, b, &block);
        }
    }
}

/// Energy `V ψ(F)` of one tet given its deformation gradient (J).
pub fn tet_psi<S: Scalar>(f: &Mat3<S>, p: &[S], damped: bool, limiting: Limiting) -> S {
    let (volume, mu_, lambda_, alpha) = (p[0], p[1], p[2], p[3]);
    let mut psi = elastic_density(f.frobenius_norm_sq(), f.det(), mu_, lambda_, alpha);
    if damped || limiting != Limiting::Off {
        let e = f.transpose().mul_mat(f).sub_identity(1.0).scale(S::constant(0.5));
        if damped {
            let e0 = [[p[5], p[8], p[10]], [p[8], p[6], p[9]], [p[10], p[9], p[7]]];
            psi += p[4] * e.sub(&Mat(e0)).frobenius_norm_sq() * 0.5;
        }
        let (limit, k) = (p[11], p[12]);
        let over = largest_strain_bound(&e) - limit;
        match limiting {
            Limiting::Off => {}
            Limiting::Active => psi += k * over.powi(3) * (1.0 / 3.0),
            Limiting::Branch => psi += S::select_gt(over, S::zero(), || k * over.powi(3) * (1.0 / 3.0), S::zero),
        }
    }
    volume * psi
}

/// Energy of one tet (J) in terms of its node positions: `F = D_s D_m⁻¹`, then [`tet_psi`].
pub fn tet_energy<S: Scalar>(x: &[Vec3<S>; 4], p: &[S]) -> S {
    let ds = Mat3::from_columns3([x[1] - x[0], x[2] - x[0], x[3] - x[0]]);
    let dm_inv: Mat3<S> = Mat([[p[0], p[1], p[2]], [p[3], p[4], p[5]], [p[6], p[7], p[8]]]);
    tet_psi(&ds.mul_mat(&dm_inv), &p[9..], true, Limiting::Branch)
}

fn psi_kernel(name: &'static str, energy: fn(&[Sym], &[Sym]) -> Sym) -> KernelSpec {
    KernelSpec {
        name,
        n_inputs: 9,
        n_params: PSI_PARAMS,
        energy,
    }
}

fn mat3_from_flat<S: Scalar>(f: &[S]) -> Mat3<S> {
    Mat([[f[0], f[1], f[2]], [f[3], f[4], f[5]], [f[6], f[7], f[8]]])
}

/// Generated kernels: `Ψ(F)` elastic only, with damping, and with damping and active limiting;
/// and the elastic energy in the invariants `(I_C, J)` (see [`elastic_derivatives_by_invariants`]).
pub fn kernels() -> [KernelSpec; 4] {
    [
        psi_kernel("tet_psi_elastic", |f, p| {
            tet_psi(&mat3_from_flat(f), p, false, Limiting::Off)
        }),
        psi_kernel("tet_psi_damped", |f, p| {
            tet_psi(&mat3_from_flat(f), p, true, Limiting::Off)
        }),
        psi_kernel("tet_psi_limited", |f, p| {
            tet_psi(&mat3_from_flat(f), p, true, Limiting::Active)
        }),
        KernelSpec {
            name: "tet_psi_invariants",
            n_inputs: 2,
            n_params: PSI_PARAMS,
            energy: |i, p| p[0] * elastic_density(i[0], i[1], p[1], p[2], p[3]),
        },
    ]
}

impl TetStrain {
    /// Add the tets of an object (indices local to `set`).
    pub fn add(
        &mut self,
        nodes: &NodeArrays,
        set: NodeSetHandle,
        label: &str,
        tets: &[[usize; 4]],
        params: TetStrainParams,
    ) -> Result<TetStrainHandle> {
        params.validate(label)?;
        let global = globalize(&set, label, "tet", tets)?;
        let mut rest = Vec::with_capacity(global.len());
        for (index, t) in global.iter().enumerate() {
            let x = t.map(|i| nodes.rest[i as usize]);
            let dm = Matrix3::from_columns(&[x[1] - x[0], x[2] - x[0], x[3] - x[0]]);
            let volume = dm.determinant() / 6.0;
            let size = (x[1] - x[0]).norm().max((x[2] - x[0]).norm()).max((x[3] - x[0]).norm());
            if !(volume > 1e-14 * size.powi(3)) {
                let detail = if volume < 0.0 {
                    format!("rest volume {volume:e} m³ is negative (inverted tet: swap two nodes)")
                } else {
                    format!("rest volume {volume:e} m³ is zero or degenerate")
                };
                return Err(StarkError::BadElement {
                    object: label.to_string(),
                    kind: "tet",
                    index,
                    detail,
                });
            }
            let inv = dm.try_inverse().expect("non-degenerate");
            let dm_inv = std::array::from_fn(|i| std::array::from_fn(|j| inv[(i, j)]));
            rest.push(TetRest { dm_inv, volume });
        }
        let g = self.groups.push(label, params);
        self.tets.extend(global);
        self.group.extend(std::iter::repeat_n(g, rest.len()));
        self.rest.extend(rest);
        self.version += 1;
        Ok(TetStrainHandle(g))
    }

    /// Parameters of a group.
    pub fn params(&self, h: TetStrainHandle) -> Result<&TetStrainParams> {
        self.groups.get("tet strain", h.0)
    }

    /// Change the parameters of a group (validated).
    pub fn set_params(&mut self, h: TetStrainHandle, params: TetStrainParams) -> Result<()> {
        self.groups.set("tet strain", h.0, params, |p, label| p.validate(label))
    }

    /// Number of tets with an inverted or flat current configuration (`det F ≤ 0`) at positions `x`.
    pub fn count_inverted(&self, x: &[Vector3<f64>]) -> usize {
        self.tets
            .iter()
            .filter(|t| {
                let p = t.map(|i| x[i as usize]);
                (p[1] - p[0]).cross(&(p[2] - p[0])).dot(&(p[3] - p[0])) <= 0.0
            })
            .count()
    }

    /// Parameters of tet `e` (layout of [`PARAMS`]) and whether it is damped.
    fn kernel_params(&self, e: usize, stencil: &Stencil<4>) -> ([f64; PARAMS], bool) {
        let params = &self.groups.params[self.group[e] as usize];
        let rest = &self.rest[e];
        let s = params.scale;
        let (mu, lambda) = params.lame();
        let mu_ = 4.0 / 3.0 * mu;
        let lambda_ = lambda + 5.0 / 6.0 * mu;
        let mut p = [0.0; PARAMS];
        // One division instead of nine (the same values at the usual scale 1).
        let inv_scale = 1.0 / s;
        for i in 0..3 {
            for j in 0..3 {
                p[3 * i + j] = rest.dm_inv[i][j] * inv_scale;
            }
        }
        p[9] = rest.volume * s * s * s;
        p[10] = mu_;
        p[11] = lambda_;
        p[12] = 1.0 + 0.75 * mu_ / lambda_;
        let damped = params.damping > 0.0;
        if damped {
            let x0 = stencil.x0;
            let ds0 = Matrix3::from_columns(&[x0[1] - x0[0], x0[2] - x0[0], x0[3] - x0[0]]);
            let f0 = ds0 * Matrix3::from_fn(|i, j| p[3 * i + j]);
            let e0 = 0.5 * (f0.transpose() * f0 - Matrix3::identity());
            p[13] = params.damping / stencil.dt;
            p[14] = e0[(0, 0)];
            p[15] = e0[(1, 1)];
            p[16] = e0[(2, 2)];
            p[17] = e0[(0, 1)];
            p[18] = e0[(1, 2)];
            p[19] = e0[(0, 2)];
        }
        p[20] = params.strain_limit;
        p[21] = params.strain_limit_stiffness;
        (p, damped)
    }
}

/// What a tet's derivatives start from: its kernel parameters, whether damping acts, the
/// gradient weights (`F = Σ_a x_a w_aᵀ`), `F` and whether the strain limit is active.
struct TetState {
    p: [f64; PARAMS],
    damped: bool,
    w: [[f64; 3]; 4],
    f: [f64; 9],
    limited: bool,
}

impl TetStrain {
    fn tet_state(&self, e: usize, stencil: &Stencil<4>) -> TetState {
        let (p, damped) = self.kernel_params(e, stencil);
        let dm_inv = [[p[0], p[1], p[2]], [p[3], p[4], p[5]], [p[6], p[7], p[8]]];
        let w = gradient_weights::<4, 3>(&dm_inv);
        let mut f = [0.0; 9];
        deformation_gradient(&w, &stencil.x, &mut f);
        let limit = p[9 + 11];
        let limited = limit.is_finite() && {
            let fm: Mat3<f64> = mat3_from_flat(&f);
            let e = fm.transpose().mul_mat(&fm).sub_identity(1.0).scale(0.5);
            largest_strain_bound(&e) > limit
        };
        TetState {
            p,
            damped,
            w,
            f,
            limited,
        }
    }

    /// Strain and stress of every tet of the group labelled `label` (in the order they were
    /// added) at positions `x`, for output; `None` without such a group. The stress is the
    /// elastic one (strain limiting included, damping left out): Cauchy `σ = P Fᵀ / J` with
    /// `P = ∂ψ/∂F` of the Stable Neo-Hookean density, by hyper-duals on `F`.
    pub fn cell_fields(&self, label: &str, x: &[Vector3<f64>]) -> Option<Vec<crate::energy::cell_fields::CellFields>> {
        let g = self.groups.labels.iter().position(|l| l == label)? as u32;
        let params = &self.groups.params[g as usize];
        let (mu, lambda) = params.lame();
        let mu_ = 4.0 / 3.0 * mu;
        let lambda_ = lambda + 5.0 / 6.0 * mu;
        let mut p = [0.0; PSI_PARAMS];
        p[0] = 1.0; // ψ per unit volume: its derivative is the first Piola–Kirchhoff stress
        p[1] = mu_;
        p[2] = lambda_;
        p[3] = 1.0 + 0.75 * mu_ / lambda_;
        p[11] = params.strain_limit;
        p[12] = params.strain_limit_stiffness;
        let out = (0..self.tets.len())
            .filter(|&e| self.group[e] == g)
            .map(|e| {
                let t = self.tets[e];
                let q = t.map(|i| x[i as usize]);
                let ds = Matrix3::from_columns(&[q[1] - q[0], q[2] - q[0], q[3] - q[0]]);
                let dm_inv = Matrix3::from_fn(|i, j| self.rest[e].dm_inv[i][j] / params.scale);
                let f = ds * dm_inv;
                let rows: [Vector3<f64>; 3] = std::array::from_fn(|r| f.row(r).transpose());
                let v = HyperDual::<3>::variables(&rows);
                let fd = Mat([v[0].0, v[1].0, v[2].0]);
                let d = tet_psi(&fd, &p.map(HyperDual::constant), false, Limiting::Branch);
                let pk1 = Matrix3::from_fn(|r, c| d.grad[r][c]);
                let green = 0.5 * (f.transpose() * f - Matrix3::identity());
                let ge = Mat(std::array::from_fn(|r| std::array::from_fn(|c| green[(r, c)])));
                let active = largest_strain_bound(&ge) > params.strain_limit;
                crate::energy::cell_fields::CellFields::new(green, pk1 * f.transpose() / f.determinant(), active)
            })
            .collect();
        Some(out)
    }
}

impl Potential<4> for TetStrain {
    fn name(&self) -> &str {
        "tet strain"
    }
    fn save_state(&self) -> Vec<u8> {
        // Parameters may change between steps (`set_params`, time events, hardening).
        crate::energy::encode_state(&self.groups.params)
    }
    fn restore_state(&mut self, bytes: &[u8]) -> Result<(), String> {
        crate::energy::restore_vec(&mut self.groups.params, crate::energy::decode_state(bytes)?, "groups")
    }
    fn num_elements(&self) -> usize {
        self.tets.len()
    }
    fn nodes(&self, e: usize) -> [Node; 4] {
        self.tets[e].map(Node::Point)
    }
    fn energy<S: Scalar>(&self, e: usize, x: &[Vec3<S>; 4], stencil: &Stencil<4>) -> S {
        let (p, _) = self.kernel_params(e, stencil);
        tet_energy(x, &p.map(S::constant))
    }
    fn write_deformable(&self, e: usize, stencil: &Stencil<4>, project: bool, row: &mut DeformableRow) -> bool {
        if project {
            return false;
        }
        let t = self.tet_state(e, stencil);
        if t.limited || t.damped {
            return false;
        }
        elastic_derivatives_by_invariants(&t.w, &t.f, &t.p[9..], row);
        true
    }
    fn derivatives(&self, e: usize, stencil: &Stencil<4>, project: bool, out: &mut HyperDual<4>) -> FastDerivatives {
        let TetState {
            p,
            damped,
            w,
            f,
            limited,
        } = self.tet_state(e, stencil);
        let psi = &p[9..];
        if !(limited || damped || project) {
            elastic_derivatives_by_invariants(&w, &f, psi, out);
            return FastDerivatives::Exact;
        }
        let mut g = [0.0; 9];
        let mut h = [0.0; 81];
        let value = if limited {
            generated::tet_psi_limited(&f, psi, &mut g, &mut h)
        } else if damped {
            generated::tet_psi_damped(&f, psi, &mut g, &mut h)
        } else {
            generated::tet_psi_elastic(&f, psi, &mut g, &mut h)
        };
        map_to_nodes(&w, value, &g, &mut h, project, out);
        if project {
            FastDerivatives::Projected
        } else {
            FastDerivatives::Exact
        }
    }
    fn topology_version(&self) -> u64 {
        self.version
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::testing::{assert_derivatives, TestState};
    use rand::{Rng, SeedableRng};

    fn random_state(seed: u64, stretch: f64) -> (TetStrain, TestState) {
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let mut r = |s: f64| {
            Vector3::new(
                rng.random_range(-s..s),
                rng.random_range(-s..s),
                rng.random_range(-s..s),
            )
        };
        let rest = vec![
            Vector3::new(0.0, 0.0, 0.0) + r(0.02),
            Vector3::new(0.1, 0.0, 0.0) + r(0.02),
            Vector3::new(0.0, 0.1, 0.0) + r(0.02),
            Vector3::new(0.0, 0.0, 0.1) + r(0.02),
        ];
        let x0: Vec<_> = rest.iter().map(|p| p * stretch + r(0.005)).collect();
        let v0 = vec![Vector3::zeros(); 4];
        let v: Vec<_> = (0..4).map(|_| r(0.3)).collect();
        let state = TestState::new(rest.clone(), x0, v0, v, 0.01);
        let mut nodes = NodeArrays::default();
        let set = NodeSetHandle {
            index: 0,
            first: nodes.push(&rest) as u32,
            len: 4,
        };
        let mut tets = TetStrain::default();
        let p = TetStrainParams {
            youngs_modulus: 1e4,
            damping: 20.0,
            strain_limit: 0.05,
            strain_limit_stiffness: 1e5,
            ..Default::default()
        };
        tets.add(&nodes, set, "t", &[[0, 1, 2, 3]], p.clone()).unwrap();
        tets.add(
            &nodes,
            set,
            "elastic",
            &[[0, 1, 2, 3]],
            TetStrainParams {
                youngs_modulus: 2e3,
                poissons_ratio: 0.45,
                ..Default::default()
            },
        )
        .unwrap();
        (tets, state)
    }

    /// `f(tets, e, stencil)` for every tet of `random_state` at seeds 0–7 and stretches 1 and
    /// 1.6 (the strain limit inactive, then active).
    fn for_each_test_tet(mut f: impl FnMut(&TetStrain, usize, &Stencil<4>)) {
        for seed in 0..8 {
            for stretch in [1.0, 1.6] {
                let (tets, state) = random_state(seed, stretch);
                let eval = state.eval();
                for e in 0..tets.num_elements() {
                    f(&tets, e, &Stencil::new(tets.nodes(e), &eval));
                }
            }
        }
    }

    /// The largest difference between `a` and `b` relative to `b`'s largest entry.
    fn rel(a: &[f64], b: &[f64]) -> f64 {
        let scale = b.iter().fold(0.0f64, |m, y| m.max(y.abs()));
        a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / scale
    }

    #[test]
    fn derivatives_match_finite_differences() {
        for seed in 0..8 {
            // Strain limit inactive (1.0) and active (1.6) stretch.
            for stretch in [1.0, 1.6] {
                let (tets, state) = random_state(seed, stretch);
                assert_derivatives(&tets, &state.eval(), 1e-6);
            }
        }
    }

    /// The Stable Neo-Hookean tet traced and compiled at run time (position form, 12 inputs)
    /// equals the built-in generated kernel (`Ψ(F)` kernel and the map to nodes) to 1e-12.
    #[test]
    fn jit_traced_tet_equals_builtin_kernel() {
        let kernel = crate::energy::jit::compile_fn(12, PARAMS, |x, p| {
            tet_energy(&crate::energy::points_from_flat::<Sym, 4>(x), p)
        })
        .unwrap();
        let mut worst = 0.0f64;
        for_each_test_tet(|tets, e, stencil| {
            let mut builtin = HyperDual::<4>::constant(0.0);
            assert_eq!(
                tets.derivatives(e, stencil, false, &mut builtin),
                FastDerivatives::Exact
            );
            let (p, _) = tets.kernel_params(e, stencil);
            let mut x = [0.0; 12];
            crate::energy::flat_from_points(&stencil.x, &mut x);
            let (mut g, mut h) = ([0.0; 12], [0.0; 144]);
            let v = kernel.evaluate(&x, &p, &mut g, &mut h);
            worst = worst
                .max(rel(&[v], &[builtin.value]))
                .max(rel(&g, builtin.gradient_flat()))
                .max(rel(&h, builtin.hess.as_flattened().as_flattened().as_flattened()));
        });
        assert!(worst < 1e-12, "largest relative difference {worst:e}");
    }

    /// The chain rule through the invariants equals the generated `Ψ(F)` kernel mapped to the
    /// nodes, to round-off, for stretched, compressed and inverted tets.
    #[test]
    fn elastic_derivatives_by_invariants_equal_the_generated_kernel() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let mut worst = 0.0f64;
        for case in 0..200 {
            let dm_inv: [[f64; 3]; 3] = std::array::from_fn(|_| std::array::from_fn(|_| rng.random_range(-12.0..12.0)));
            let w = gradient_weights::<4, 3>(&dm_inv);
            // F near identity, far from it, and inverted (a reflection) in turn.
            let spread = [0.1, 0.8, 0.3][case % 3];
            let mut f: [f64; 9] = std::array::from_fn(|_| rng.random_range(-spread..spread));
            for i in 0..3 {
                f[4 * i] += if case % 3 == 2 && i == 0 { -1.0 } else { 1.0 };
            }
            // V, μ', λ', α; no damping; no strain limit.
            let mut p = [0.0; PSI_PARAMS];
            p[..4].copy_from_slice(&[rng.random_range(1e-4..1e-3), 3e3, 2e4, 1.1]);
            p[11] = f64::INFINITY;
            let mut fast = HyperDual::<4>::constant(0.0);
            elastic_derivatives_by_invariants(&w, &f, &p, &mut fast);
            let (mut g, mut h) = ([0.0; 9], [0.0; 81]);
            let value = generated::tet_psi_elastic(&f, &p, &mut g, &mut h);
            let mut generic = HyperDual::<4>::constant(0.0);
            map_to_nodes(&w, value, &g, &mut h, false, &mut generic);
            let flat = |d: &HyperDual<4>| d.hess.as_flattened().as_flattened().as_flattened().to_vec();
            worst = worst
                .max(rel(&[fast.value], &[generic.value]))
                .max(rel(fast.gradient_flat(), generic.gradient_flat()))
                .max(rel(&flat(&fast), &flat(&generic)));
        }
        assert!(worst < 1e-11, "largest relative difference {worst:e}");
    }

    /// The row written straight in DOF space equals the hyper-dual derivatives mapped by
    /// `write_deformable_element`, bit for bit, and is written only where it applies (elastic,
    /// limit inactive, no projection asked).
    #[test]
    fn deformable_row_equals_the_mapped_derivatives() {
        use crate::energy::kinematics::write_deformable_element;
        use crate::energy::term::element_stride;
        let mut written = 0;
        for_each_test_tet(|tets, e, stencil| {
            for width in [4, 6] {
                let mut direct = vec![f64::NAN; element_stride(width)];
                let fast =
                    tets.write_deformable(e, stencil, false, &mut DeformableRow::new(4, stencil.dt, &mut direct));
                // Tet 0 is damped (and limited when stretched), tet 1 elastic with no limit.
                assert_eq!(fast, e == 1, "tet {e}");
                let mut spare = direct.clone();
                assert!(!tets.write_deformable(e, stencil, true, &mut DeformableRow::new(4, stencil.dt, &mut spare)));
                if !fast {
                    continue;
                }
                written += 1;
                let mut d = HyperDual::<4>::constant(0.0);
                tets.derivatives(e, stencil, false, &mut d);
                let mut mapped = vec![f64::NAN; element_stride(width)];
                write_deformable_element(&d, stencil.dt, &mut mapped);
                // Padding slots' Hessian blocks are never read; everything else is equal.
                let read = 1 + 3 * width;
                assert_eq!(direct[..read], mapped[..read]);
                for a in 0..4 {
                    for b in 0..4 {
                        let k = read + 9 * (a * width + b);
                        assert_eq!(direct[k..k + 9], mapped[k..k + 9], "block ({a}, {b})");
                    }
                }
            }
        });
        assert!(written > 0);
    }

    #[test]
    fn rest_state_is_stress_free() {
        let (tets, _) = random_state(3, 1.0);
        let rest = tets.rest[0];
        let _ = rest;
        let (_, state) = random_state(3, 1.0);
        let mut st = TestState::new(
            state.nodes.rest.clone(),
            state.nodes.rest.clone(),
            vec![Vector3::zeros(); 4],
            vec![Vector3::zeros(); 4],
            0.01,
        );
        st.gravity = Vector3::zeros();
        let eval = st.eval();
        let stencil = Stencil::new(tets.nodes(1), &eval);
        let d = crate::energy::potential::dual_derivatives(&tets, 1, &stencil);
        assert!(d.gradient_flat().iter().all(|g| g.abs() < 1e-10), "{:?}", d.grad);
    }

    #[test]
    fn bad_input_is_a_clear_error() {
        let mut nodes = NodeArrays::default();
        let rest = [Vector3::zeros(), Vector3::x(), Vector3::y(), Vector3::z()];
        let set = NodeSetHandle {
            index: 0,
            first: nodes.push(&rest) as u32,
            len: 4,
        };
        let mut tets = TetStrain::default();
        let err = tets
            .add(&nodes, set, "cup", &[[0, 2, 1, 3]], TetStrainParams::default())
            .unwrap_err()
            .to_string();
        assert!(err.contains("tet 0 of 'cup'") && err.contains("negative"), "{err}");
        let flat = [
            Vector3::zeros(),
            Vector3::x(),
            Vector3::y(),
            Vector3::new(1.0, 1.0, 0.0),
        ];
        let set2 = NodeSetHandle {
            index: 1,
            first: nodes.push(&flat) as u32,
            len: 4,
        };
        let err = tets
            .add(&nodes, set2, "flat", &[[0, 1, 2, 3]], TetStrainParams::default())
            .unwrap_err()
            .to_string();
        assert!(err.contains("zero or degenerate"), "{err}");
        let bad = TetStrainParams {
            youngs_modulus: f64::NAN,
            ..Default::default()
        };
        let err = tets
            .add(&nodes, set, "cube", &[[0, 1, 2, 3]], bad)
            .unwrap_err()
            .to_string();
        assert!(err.contains("`youngs_modulus` = NaN on 'cube'"), "{err}");
        let bad = TetStrainParams {
            youngs_modulus: -5.0,
            ..Default::default()
        };
        assert!(tets
            .add(&nodes, set, "cube", &[[0, 1, 2, 3]], bad)
            .unwrap_err()
            .to_string()
            .contains("must be positive"));
        let err = tets
            .add(&nodes, set, "cube", &[[0, 1, 2, 7]], TetStrainParams::default())
            .unwrap_err()
            .to_string();
        assert!(err.contains("refers to node 7"), "{err}");
    }
}
