//! Shells and cloth: Neo-Hookean membrane strain of linear triangles, with strain-rate damping,
//! strain limiting and inflation pressure.
//!
//! Per triangle, times thickness `h` and rest area `A` (as in the original Stark):
//!
//! `ψ = μ/2 (I_C − 2) − μ ln J + λ/2 ln² J`, with `F = D_s D_m⁻¹` (3×2), `C = FᵀF`,
//! `I_C = tr C`, `J = √det C` (the area ratio) and the plane-stress `λ = Eν/((1 + ν)(1 − ν))`.
//!
//! Damping `½ (c/dt) ‖E₁ − E₀‖²` on the Green strain `E = ½(C − I)` (a Rayleigh dissipation
//! `½ c ‖Ė‖²` times `dt`; see `tet_strain`). Strain limiting adds `k (s − ε_max)³/3` for each
//! principal Green strain `s` above the limit, which keeps cloth from stretching past ~10%.
//!
//! Inflation is a pressure `p` (Pa) on the triangle, with the area-weighted normal lagged at the
//! start of the step: the force `p·½(e₁⁰ × e₂⁰)` is shared equally by the three nodes.

use super::{globalize, Groups, NodeSetHandle};
use crate::energy::deformation::{deformation_gradient, gradient_weights, map_to_nodes};
use crate::energy::symbolic::{KernelSpec, Sym};
use crate::energy::{FastDerivatives, HyperDual, Mat, Mat2, Mat32, Node, Potential, Scalar, Stencil, Vec3};
use crate::error::{check_param, Result, StarkError};
use crate::generated;
use crate::state::NodeArrays;
use nalgebra::{Matrix2, Vector3};
use serde::{Deserialize, Serialize};

crate::params::param_struct! {
    /// Membrane strain of a shell or cloth (Neo-Hookean triangles with strain limiting).
    #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct TriangleStrainParams {
        /// Shell thickness, m (default: 1e-3).
        pub thickness_m: f64,
        /// Young's modulus, Pa (default: 1e3).
        pub youngs_modulus: f64,
        /// Poisson's ratio, unitless in (0, 0.5) (default: 0.3).
        pub poissons_ratio: f64,
        /// Strain-rate damping coefficient `c`, Pa·s (default: 0).
        pub damping: f64,
        /// Principal Green strain above which strain limiting acts, unitless (default: ∞, off).
        pub strain_limit: f64,
        /// Stiffness of the strain-limiting penalty, Pa (default: 1e3).
        pub strain_limit_stiffness: f64,
        /// Inflation pressure, Pa, along the triangle normal `(x₁ − x₀) × (x₂ − x₀)` (default: 0).
        pub inflation_pa: f64,
        /// Uniform scale of the rest shape, unitless (default: 1).
        pub scale: f64,
    }
}

impl Default for TriangleStrainParams {
    fn default() -> Self {
        TriangleStrainParams {
            thickness_m: 1e-3,
            youngs_modulus: 1e3,
            poissons_ratio: 0.3,
            damping: 0.0,
            strain_limit: f64::INFINITY,
            strain_limit_stiffness: 1e3,
            inflation_pa: 0.0,
            scale: 1.0,
        }
    }
}

impl TriangleStrainParams {
    /// Check every field.
    pub fn validate(&self, object: &str) -> Result<()> {
        let t = self.thickness_m;
        check_param(
            object,
            "thickness_m",
            t,
            t > 0.0 && t.is_finite(),
            "must be positive and finite (m)",
        )?;
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
        check_param(
            object,
            "inflation_pa",
            self.inflation_pa,
            self.inflation_pa.is_finite(),
            "must be finite (Pa)",
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

    /// Lamé parameters `(μ, λ)` with the plane-stress `λ`, Pa.
    pub fn lame(&self) -> (f64, f64) {
        let (e, nu) = (self.youngs_modulus, self.poissons_ratio);
        (e / (2.0 * (1.0 + nu)), e * nu / ((1.0 + nu) * (1.0 - nu)))
    }
}

/// Handle to a group of triangles.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct TriangleStrainHandle(pub u32);

#[derive(Clone, Copy, Debug)]
struct TriangleRest {
    dm_inv: [[f64; 2]; 2],
    area: f64,
}

/// Membrane energy of all shells.
#[derive(Default)]
pub struct TriangleStrain {
    groups: Groups<TriangleStrainParams>,
    triangles: Vec<[u32; 3]>,
    group: Vec<u32>,
    rest: Vec<TriangleRest>,
    version: u64,
}

/// Parameters of the `Ψ(F)` kernels: `h·A`, `μ`, `λ`, `c/dt`, `E₀` (xx, yy, xy), `ε_max`, `k`.
pub const PSI_PARAMS: usize = 9;
/// Parameters of the position-space energy: `D_m⁻¹` (4, row-major), the `Ψ(F)` parameters, and
/// the inflation force (3).
pub const PARAMS: usize = 4 + PSI_PARAMS + 3;

/// Which principal strains exceed the limit (the strain-limiting term of a traced energy).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Limiting {
    /// Neither.
    Off,
    /// Decided inside the energy with branches (the oracle).
    Branch,
    /// The larger one only.
    Largest,
    /// Both.
    Both,
}

/// `Σᵢ (sᵢ − L)³` over both eigenvalues of the symmetric 2×2 `e`, written with its invariants
/// (`Σ sᵢ = t`, `Σ sᵢ² = t² − 2d`, `Σ sᵢ³ = t³ − 3td`), which stays smooth where they coincide.
fn both_over_cubed<S: Scalar>(e: &Mat2<S>, limit: S) -> S {
    let t = e.trace();
    let d = e.det();
    (t.powi(3) - t * d * 3.0) - limit * (t.sq() - d * 2.0) * 3.0 + limit.sq() * t * 3.0 - limit.powi(3) * 2.0
}

/// Energy `h A ψ(F)` of one triangle given its 3×2 deformation gradient (J).
pub fn triangle_psi<S: Scalar>(f: &Mat32<S>, p: &[S], damped: bool, limiting: Limiting) -> S {
    let (h_area, mu, lambda) = (p[0], p[1], p[2]);
    let c: Mat2<S> = f.transpose().mul_mat(f);
    let ic = c.trace();
    let ln_j = c.det().ln() * 0.5;
    let mut psi = mu * (ic - 2.0) * 0.5 - mu * ln_j + lambda * ln_j.sq() * 0.5;
    if damped || limiting != Limiting::Off {
        let e = c.sub_identity(1.0).scale(S::constant(0.5));
        if damped {
            psi += p[3] * e.sub(&Mat([[p[4], p[6]], [p[6], p[5]]])).frobenius_norm_sq() * 0.5;
        }
        let (limit, k) = (p[7], p[8]);
        let third = 1.0 / 3.0;
        match limiting {
            Limiting::Off => {}
            Limiting::Largest => psi += k * (e.symmetric_eigenvalues()[0] - limit).powi(3) * third,
            Limiting::Both => psi += k * both_over_cubed(&e, limit) * third,
            Limiting::Branch => {
                let [s_max, s_min] = e.symmetric_eigenvalues();
                psi += S::select_gt(
                    s_min - limit,
                    S::zero(),
                    || k * both_over_cubed(&e, limit) * third,
                    || {
                        S::select_gt(
                            s_max - limit,
                            S::zero(),
                            || k * (s_max - limit).powi(3) * third,
                            S::zero,
                        )
                    },
                );
            }
        }
    }
    h_area * psi
}

/// Energy of one triangle (J) in terms of its node positions: `F = D_s D_m⁻¹`, [`triangle_psi`],
/// and the work of the inflation force on the centroid.
pub fn triangle_energy<S: Scalar>(x: &[Vec3<S>; 3], p: &[S]) -> S {
    let ds = Mat32::from_columns3([x[1] - x[0], x[2] - x[0]]);
    let dm_inv: Mat2<S> = Mat([[p[0], p[1]], [p[2], p[3]]]);
    let psi = triangle_psi(&ds.mul_mat(&dm_inv), &p[4..4 + PSI_PARAMS], true, Limiting::Branch);
    let force = Vec3([p[13], p[14], p[15]]);
    psi - (x[0] + x[1] + x[2]).dot(&force) * (1.0 / 3.0)
}

fn mat32_from_flat<S: Scalar>(f: &[S]) -> Mat32<S> {
    Mat([[f[0], f[1]], [f[2], f[3]], [f[4], f[5]]])
}

fn psi_kernel(name: &'static str, energy: fn(&[Sym], &[Sym]) -> Sym) -> KernelSpec {
    KernelSpec {
        name,
        n_inputs: 6,
        n_params: PSI_PARAMS,
        energy,
    }
}

/// Generated `Ψ(F)` kernels: elastic, damped, and damped with one or both strains limited.
pub fn kernels() -> [KernelSpec; 4] {
    [
        psi_kernel("triangle_psi_elastic", |f, p| {
            triangle_psi(&mat32_from_flat(f), p, false, Limiting::Off)
        }),
        psi_kernel("triangle_psi_damped", |f, p| {
            triangle_psi(&mat32_from_flat(f), p, true, Limiting::Off)
        }),
        psi_kernel("triangle_psi_limited_largest", |f, p| {
            triangle_psi(&mat32_from_flat(f), p, true, Limiting::Largest)
        }),
        psi_kernel("triangle_psi_limited_both", |f, p| {
            triangle_psi(&mat32_from_flat(f), p, true, Limiting::Both)
        }),
    ]
}

/// `D_m` of a rest triangle in an orthonormal frame of its plane, and its area.
pub fn triangle_rest_frame(x: [Vector3<f64>; 3]) -> (Matrix2<f64>, f64) {
    let e1 = x[1] - x[0];
    let e2 = x[2] - x[0];
    let u = e1.normalize();
    let w = (e2 - u * u.dot(&e2)).normalize();
    let dm = Matrix2::new(u.dot(&e1), u.dot(&e2), w.dot(&e1), w.dot(&e2));
    (dm, 0.5 * e1.cross(&e2).norm())
}

impl TriangleStrain {
    /// Add the triangles of an object (indices local to `set`).
    pub fn add(
        &mut self,
        nodes: &NodeArrays,
        set: NodeSetHandle,
        label: &str,
        triangles: &[[usize; 3]],
        params: TriangleStrainParams,
    ) -> Result<TriangleStrainHandle> {
        params.validate(label)?;
        let global = globalize(&set, label, "triangle", triangles)?;
        let mut rest = Vec::with_capacity(global.len());
        for (index, t) in global.iter().enumerate() {
            let x = t.map(|i| nodes.rest[i as usize]);
            let longest = (x[1] - x[0]).norm().max((x[2] - x[0]).norm()).max((x[2] - x[1]).norm());
            let area = 0.5 * (x[1] - x[0]).cross(&(x[2] - x[0])).norm();
            if !(area > 1e-12 * longest * longest) {
                return Err(StarkError::BadElement {
                    object: label.to_string(),
                    kind: "triangle",
                    index,
                    detail: format!("rest area {area:e} m² is zero or degenerate"),
                });
            }
            let (dm, area) = triangle_rest_frame(x);
            let inv = dm.try_inverse().expect("non-degenerate");
            rest.push(TriangleRest {
                dm_inv: [[inv[(0, 0)], inv[(0, 1)]], [inv[(1, 0)], inv[(1, 1)]]],
                area,
            });
        }
        let g = self.groups.push(label, params);
        self.triangles.extend(global);
        self.group.extend(std::iter::repeat_n(g, rest.len()));
        self.rest.extend(rest);
        self.version += 1;
        Ok(TriangleStrainHandle(g))
    }

    /// Parameters of a group.
    pub fn params(&self, h: TriangleStrainHandle) -> Result<&TriangleStrainParams> {
        self.groups.get("triangle strain", h.0)
    }

    /// Change the parameters of a group.
    pub fn set_params(&mut self, h: TriangleStrainHandle, params: TriangleStrainParams) -> Result<()> {
        self.groups
            .set("triangle strain", h.0, params, |p, label| p.validate(label))
    }

    /// Parameters of triangle `e` (layout of [`PARAMS`]) and whether it is damped.
    fn kernel_params(&self, e: usize, stencil: &Stencil<3>) -> ([f64; PARAMS], bool) {
        let params = &self.groups.params[self.group[e] as usize];
        let rest = &self.rest[e];
        let s = params.scale;
        let (mu, lambda) = params.lame();
        let mut p = [0.0; PARAMS];
        p[0] = rest.dm_inv[0][0] / s;
        p[1] = rest.dm_inv[0][1] / s;
        p[2] = rest.dm_inv[1][0] / s;
        p[3] = rest.dm_inv[1][1] / s;
        p[4] = params.thickness_m * rest.area * s * s;
        p[5] = mu;
        p[6] = lambda;
        let x0 = stencil.x0;
        let damped = params.damping > 0.0;
        if damped {
            let dm_inv = Matrix2::new(p[0], p[1], p[2], p[3]);
            let ds = nalgebra::Matrix3x2::from_columns(&[x0[1] - x0[0], x0[2] - x0[0]]);
            let f0 = ds * dm_inv;
            let e0 = 0.5 * (f0.transpose() * f0 - Matrix2::identity());
            p[7] = params.damping / stencil.dt;
            p[8] = e0[(0, 0)];
            p[9] = e0[(1, 1)];
            p[10] = e0[(0, 1)];
        }
        p[11] = params.strain_limit;
        p[12] = params.strain_limit_stiffness;
        if params.inflation_pa != 0.0 {
            let f = (x0[1] - x0[0]).cross(&(x0[2] - x0[0])) * (0.5 * params.inflation_pa);
            p[13] = f.x;
            p[14] = f.y;
            p[15] = f.z;
        }
        (p, damped)
    }
}

impl TriangleStrain {
    /// Strain and stress of every triangle of the group labelled `label` (in the order they
    /// were added) at positions `x`, for output; `None` without such a group. The Green strain
    /// is the 2×2 one of the rest plane (in the upper-left block); the stress is the membrane's
    /// Cauchy stress `σ = P Fᵀ / J` (plane stress, `J` the area ratio, damping left out,
    /// strain limiting included) with `P = ∂ψ/∂F` by hyper-duals on the 3×2 `F`.
    pub fn cell_fields(&self, label: &str, x: &[Vector3<f64>]) -> Option<Vec<crate::energy::cell_fields::CellFields>> {
        let g = self.groups.labels.iter().position(|l| l == label)? as u32;
        let params = &self.groups.params[g as usize];
        let (mu, lambda) = params.lame();
        let mut p = [0.0; PSI_PARAMS];
        p[0] = 1.0; // ψ per unit volume
        p[1] = mu;
        p[2] = lambda;
        p[7] = params.strain_limit;
        p[8] = params.strain_limit_stiffness;
        let out = (0..self.triangles.len())
            .filter(|&e| self.group[e] == g)
            .map(|e| {
                let t = self.triangles[e];
                let q = t.map(|i| x[i as usize]);
                let ds = nalgebra::Matrix3x2::from_columns(&[q[1] - q[0], q[2] - q[0]]);
                let r = &self.rest[e].dm_inv;
                let dm_inv = Matrix2::new(r[0][0], r[0][1], r[1][0], r[1][1]) / params.scale;
                let f = ds * dm_inv;
                // Variables: column c of F is "node" c.
                let cols: [Vector3<f64>; 2] = [f.column(0).into(), f.column(1).into()];
                let v = HyperDual::<2>::variables(&cols);
                let fd = Mat(std::array::from_fn(|row| [v[0].0[row], v[1].0[row]]));
                let d = triangle_psi(&fd, &p.map(HyperDual::constant), false, Limiting::Branch);
                let pk1 = nalgebra::Matrix3x2::from_fn(|row, c| d.grad[c][row]);
                let c2 = f.transpose() * f;
                let green2 = 0.5 * (c2 - Matrix2::identity());
                let area_ratio = c2.determinant().max(0.0).sqrt();
                let mut green = nalgebra::Matrix3::zeros();
                green.fixed_view_mut::<2, 2>(0, 0).copy_from(&green2);
                let active = green2.symmetric_eigen().eigenvalues.max() > params.strain_limit;
                crate::energy::cell_fields::CellFields::new(green, pk1 * f.transpose() / area_ratio, active)
            })
            .collect();
        Some(out)
    }
}

impl Potential<3> for TriangleStrain {
    fn name(&self) -> &str {
        "triangle strain"
    }
    fn save_state(&self) -> Vec<u8> {
        // Parameters may change between steps (`set_params`, time events, hardening).
        crate::energy::encode_state(&self.groups.params)
    }
    fn restore_state(&mut self, bytes: &[u8]) -> Result<(), String> {
        crate::energy::restore_vec(&mut self.groups.params, crate::energy::decode_state(bytes)?, "groups")
    }
    fn num_elements(&self) -> usize {
        self.triangles.len()
    }
    fn nodes(&self, e: usize) -> [Node; 3] {
        self.triangles[e].map(Node::Point)
    }
    fn energy<S: Scalar>(&self, e: usize, x: &[Vec3<S>; 3], stencil: &Stencil<3>) -> S {
        let (p, _) = self.kernel_params(e, stencil);
        triangle_energy(x, &p.map(S::constant))
    }
    fn derivatives(&self, e: usize, stencil: &Stencil<3>, project: bool, out: &mut HyperDual<3>) -> FastDerivatives {
        let (p, damped) = self.kernel_params(e, stencil);
        let w = gradient_weights::<3, 2>(&[[p[0], p[1]], [p[2], p[3]]]);
        let mut f = [0.0; 6];
        deformation_gradient(&w, &stencil.x, &mut f);
        let psi = &p[4..4 + PSI_PARAMS];
        let limit = psi[7];
        let limiting = if limit.is_finite() {
            let fm: Mat32<f64> = mat32_from_flat(&f);
            let c: Mat2<f64> = fm.transpose().mul_mat(&fm);
            let [s_max, s_min] = c.sub_identity(1.0).scale(0.5).symmetric_eigenvalues();
            if s_min > limit {
                Limiting::Both
            } else if s_max > limit {
                Limiting::Largest
            } else {
                Limiting::Off
            }
        } else {
            Limiting::Off
        };
        let mut g = [0.0; 6];
        let mut h = [0.0; 36];
        let value = match (limiting, damped) {
            (Limiting::Both, _) => generated::triangle_psi_limited_both(&f, psi, &mut g, &mut h),
            (Limiting::Largest, _) => generated::triangle_psi_limited_largest(&f, psi, &mut g, &mut h),
            (_, true) => generated::triangle_psi_damped(&f, psi, &mut g, &mut h),
            (_, false) => generated::triangle_psi_elastic(&f, psi, &mut g, &mut h),
        };
        map_to_nodes(&w, value, &g, &mut h, project, out);
        // Inflation: linear in x, gradient only.
        let force = [p[13], p[14], p[15]];
        let centroid_work: f64 = (0..3)
            .map(|i| (stencil.x[0][i] + stencil.x[1][i] + stencil.x[2][i]) * force[i])
            .sum::<f64>()
            / 3.0;
        out.value -= centroid_work;
        for a in 0..3 {
            for i in 0..3 {
                out.grad[a][i] -= force[i] / 3.0;
            }
        }
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

    #[test]
    fn derivatives_match_finite_differences() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(1);
        for _ in 0..8 {
            for stretch in [1.0, 1.3] {
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
                ];
                let x0: Vec<_> = rest.iter().map(|p| p * stretch + r(0.005)).collect();
                let v: Vec<_> = (0..3).map(|_| r(0.3)).collect();
                let st = TestState::new(rest.clone(), x0, vec![Vector3::zeros(); 3], v, 0.01);
                let set = NodeSetHandle {
                    index: 0,
                    first: 0,
                    len: 3,
                };
                let mut tris = TriangleStrain::default();
                let full = TriangleStrainParams {
                    youngs_modulus: 5e3,
                    damping: 0.5,
                    strain_limit: 0.1,
                    strain_limit_stiffness: 1e6,
                    inflation_pa: 30.0,
                    ..Default::default()
                };
                tris.add(&st.nodes, set, "cloth", &[[0, 1, 2]], full).unwrap();
                tris.add(
                    &st.nodes,
                    set,
                    "elastic",
                    &[[0, 1, 2]],
                    TriangleStrainParams {
                        scale: 0.9,
                        ..Default::default()
                    },
                )
                .unwrap();
                assert_derivatives(&tris, &st.eval(), 1e-7);
            }
        }
    }

    #[test]
    fn degenerate_triangle_is_an_error() {
        let rest = vec![Vector3::zeros(), Vector3::x(), Vector3::x() * 2.0];
        let st = TestState::new(
            rest.clone(),
            rest,
            vec![Vector3::zeros(); 3],
            vec![Vector3::zeros(); 3],
            0.01,
        );
        let set = NodeSetHandle {
            index: 0,
            first: 0,
            len: 3,
        };
        let err = TriangleStrain::default()
            .add(&st.nodes, set, "sheet", &[[0, 1, 2]], TriangleStrainParams::default())
            .unwrap_err();
        assert!(err.to_string().contains("triangle 0 of 'sheet'"), "{err}");
        let bad = TriangleStrainParams {
            poissons_ratio: 0.5,
            ..Default::default()
        };
        let err = TriangleStrain::default()
            .add(&st.nodes, set, "sheet", &[[0, 1, 2]], bad)
            .unwrap_err();
        assert!(
            err.to_string()
                .contains("`poissons_ratio` = 0.5 on 'sheet' must lie in (0, 0.5)"),
            "{err}"
        );
    }
}
