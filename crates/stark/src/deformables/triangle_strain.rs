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
use crate::energy::symbolic::KernelSpec;
use crate::energy::{
    flat_from_points, points_from_flat, HyperDual, Mat, Mat2, Node, Potential, Scalar, Stencil,
    Vec3,
};
use crate::error::{check_param, Result, StarkError};
use crate::generated;
use crate::state::NodeArrays;
use nalgebra::{Matrix2, Vector3};
use serde::{Deserialize, Serialize};

/// Material of a membrane.
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

    fn needs_full_kernel(&self) -> bool {
        self.damping > 0.0 || self.strain_limit.is_finite()
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

/// Elastic kernel parameters: `D_m⁻¹` (4), `h·A`, `μ`, `λ`, inflation force (3).
pub const ELASTIC_PARAMS: usize = 10;
/// Full kernel: elastic ones, then `c/dt`, `E₀` (xx, yy, xy), `ε_max`, `k`.
pub const FULL_PARAMS: usize = 16;

/// Energy of one triangle (J).
pub fn triangle_energy<S: Scalar>(x: &[Vec3<S>; 3], p: &[S], full: bool) -> S {
    let ds = Mat::<S, 3, 2>::from_columns3([x[1] - x[0], x[2] - x[0]]);
    let dm_inv: Mat2<S> = Mat([[p[0], p[1]], [p[2], p[3]]]);
    let (h_area, mu, lambda) = (p[4], p[5], p[6]);
    let f = ds.mul_mat(&dm_inv);
    let c: Mat2<S> = f.transpose().mul_mat(&f);
    let ic = c.trace();
    let ln_j = c.det().ln() * 0.5;
    let mut psi = mu * (ic - 2.0) * 0.5 - mu * ln_j + lambda * ln_j.sq() * 0.5;
    if full {
        let (c_over_dt, limit, k) = (p[10], p[14], p[15]);
        let e = c.sub_identity(1.0).scale(S::constant(0.5));
        let de = e.sub(&Mat([[p[11], p[13]], [p[13], p[12]]]));
        psi += c_over_dt * de.frobenius_norm_sq() * 0.5;
        for s in e.symmetric_eigenvalues() {
            let over = s - limit;
            psi += S::select_gt(over, S::zero(), || k * over.powi(3) * (1.0 / 3.0), S::zero);
        }
    }
    let centroid_work = (x[0] + x[1] + x[2]).dot(&Vec3([p[7], p[8], p[9]])) * (1.0 / 3.0);
    h_area * psi - centroid_work
}

/// Generated kernel of the elastic-only energy.
pub const ELASTIC_KERNEL: KernelSpec = KernelSpec {
    name: "triangle_strain_elastic",
    n_inputs: 9,
    n_params: ELASTIC_PARAMS,
    energy: |x, p| triangle_energy(&points_from_flat(x), p, false),
};
/// Generated kernel with damping and strain limiting.
pub const FULL_KERNEL: KernelSpec = KernelSpec {
    name: "triangle_strain_full",
    n_inputs: 9,
    n_params: FULL_PARAMS,
    energy: |x, p| triangle_energy(&points_from_flat(x), p, true),
};

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
            let longest = (x[1] - x[0])
                .norm()
                .max((x[2] - x[0]).norm())
                .max((x[2] - x[1]).norm());
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
        Ok(&self.groups.params[self.groups.check("triangle strain", h.0)?])
    }

    /// Change the parameters of a group.
    pub fn set_params(
        &mut self,
        h: TriangleStrainHandle,
        params: TriangleStrainParams,
    ) -> Result<()> {
        let i = self.groups.check("triangle strain", h.0)?;
        params.validate(&self.groups.labels[i])?;
        self.groups.params[i] = params;
        Ok(())
    }

    fn kernel_params(&self, e: usize, stencil: &Stencil<3>) -> ([f64; FULL_PARAMS], bool) {
        let params = &self.groups.params[self.group[e] as usize];
        let rest = &self.rest[e];
        let s = params.scale;
        let (mu, lambda) = params.lame();
        let mut p = [0.0; FULL_PARAMS];
        p[0] = rest.dm_inv[0][0] / s;
        p[1] = rest.dm_inv[0][1] / s;
        p[2] = rest.dm_inv[1][0] / s;
        p[3] = rest.dm_inv[1][1] / s;
        p[4] = params.thickness_m * rest.area * s * s;
        p[5] = mu;
        p[6] = lambda;
        let x0 = stencil.x0;
        if params.inflation_pa != 0.0 {
            let f = (x0[1] - x0[0]).cross(&(x0[2] - x0[0])) * (0.5 * params.inflation_pa);
            p[7] = f.x;
            p[8] = f.y;
            p[9] = f.z;
        }
        let full = params.needs_full_kernel();
        if full {
            let dm_inv = Matrix2::new(p[0], p[1], p[2], p[3]);
            let e1 = x0[1] - x0[0];
            let e2 = x0[2] - x0[0];
            let ds = nalgebra::Matrix3x2::from_columns(&[e1, e2]);
            let f0 = ds * dm_inv;
            let e0 = 0.5 * (f0.transpose() * f0 - Matrix2::identity());
            p[10] = params.damping / stencil.dt;
            p[11] = e0[(0, 0)];
            p[12] = e0[(1, 1)];
            p[13] = e0[(0, 1)];
            p[14] = params.strain_limit;
            p[15] = params.strain_limit_stiffness;
        }
        (p, full)
    }
}

impl Potential<3> for TriangleStrain {
    fn name(&self) -> &str {
        "triangle strain"
    }
    fn num_elements(&self) -> usize {
        self.triangles.len()
    }
    fn nodes(&self, e: usize) -> [Node; 3] {
        self.triangles[e].map(Node::Point)
    }
    fn energy<S: Scalar>(&self, e: usize, x: &[Vec3<S>; 3], stencil: &Stencil<3>) -> S {
        let (p, full) = self.kernel_params(e, stencil);
        triangle_energy(x, &p.map(S::constant), full)
    }
    fn derivatives(&self, e: usize, stencil: &Stencil<3>, out: &mut HyperDual<3>) -> bool {
        let (p, full) = self.kernel_params(e, stencil);
        let mut x = [0.0; 9];
        flat_from_points(&stencil.x, &mut x);
        let grad = out.grad.as_flattened_mut();
        let hess = out
            .hess
            .as_flattened_mut()
            .as_flattened_mut()
            .as_flattened_mut();
        out.value = if full {
            generated::triangle_strain_full(&x, &p, grad, hess)
        } else {
            generated::triangle_strain_elastic(&x, &p[..ELASTIC_PARAMS], grad, hess)
        };
        true
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
                tris.add(&st.nodes, set, "cloth", &[[0, 1, 2]], full)
                    .unwrap();
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
            .add(
                &st.nodes,
                set,
                "sheet",
                &[[0, 1, 2]],
                TriangleStrainParams::default(),
            )
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
