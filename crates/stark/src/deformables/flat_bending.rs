//! Cloth bending with a flat rest shape: the quadratic bending energy of Bergou et al. 2006
//! ("A quadratic bending model for inextensible surfaces").
//!
//! For a hinge `[x₀, x₁, x₂, x₃]` (shared edge `x₀x₁`, opposite vertices `x₂`, `x₃`) the discrete
//! mean-curvature vector is linear in the positions, `Σᵢ Kᵢ xᵢ`, with cotangent weights
//! `K = (c₀₃ + c₀₄, c₀₁ + c₀₂, −c₀₁ − c₀₃, −c₀₂ − c₀₄)` of the rest angles. The energy is
//! `½ k q Σ_d (K·x_d)²` per coordinate `d`, with `q = 3/(2(A₀ + A₁))` as in the original Stark
//! (Bergou's `3/(A₀ + A₁)` times ½), so its Hessian is constant. Beyond the original, a damping
//! term `½ (c/dt) q Σ_d (K·(x_d − x⁰_d))²` dissipates bending motion.

use super::{globalize, Groups, NodeSetHandle};
use crate::energy::symbolic::KernelSpec;
use crate::energy::{points_from_flat, run_kernel, FastDerivatives, HyperDual, Node, Potential, Scalar, Stencil, Vec3};
use crate::error::{check_param, Result, StarkError};
use crate::generated;
use crate::geometry::mesh::find_hinges;
use crate::state::NodeArrays;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

crate::params::param_struct! {
    /// Quadratic bending towards the flat state (cloth).
    #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct FlatBendingParams {
        /// Bending stiffness `k`, N·m (default: 1e-6).
        pub stiffness: f64,
        /// Bending damping `c`, N·m·s (default: 0).
        pub damping: f64,
    }
}

impl Default for FlatBendingParams {
    fn default() -> Self {
        FlatBendingParams {
            stiffness: 1e-6,
            damping: 0.0,
        }
    }
}

impl FlatBendingParams {
    /// Check every field.
    pub fn validate(&self, object: &str) -> Result<()> {
        let k = self.stiffness;
        check_param(
            object,
            "stiffness",
            k,
            k >= 0.0 && k.is_finite(),
            "must be non-negative and finite (N·m)",
        )?;
        let c = self.damping;
        check_param(
            object,
            "damping",
            c,
            c >= 0.0 && c.is_finite(),
            "must be non-negative and finite (N·m·s)",
        )
    }
}

/// Handle to a group of hinges.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct FlatBendingHandle(pub u32);

/// Flat bending of all cloth-like shells.
#[derive(Default)]
pub struct FlatBending {
    groups: Groups<FlatBendingParams>,
    hinges: Vec<[u32; 4]>,
    group: Vec<u32>,
    /// Cotangent weights `K` and area factor `q` per hinge.
    weights: Vec<([f64; 4], f64)>,
    version: u64,
}

/// Kernel parameters: `K` (4), `k q`, `(c/dt) q`, `K·x⁰` per coordinate (3).
pub const PARAMS: usize = 9;

/// Energy of one hinge (J).
pub fn flat_bending_energy<S: Scalar>(x: &[Vec3<S>; 4], p: &[S]) -> S {
    let mut e = S::zero();
    for d in 0..3 {
        let kx = x[0][d] * p[0] + x[1][d] * p[1] + x[2][d] * p[2] + x[3][d] * p[3];
        e += p[4] * kx.sq() * 0.5 + p[5] * (kx - p[6 + d]).sq() * 0.5;
    }
    e
}

/// Generated kernel.
pub const KERNEL: KernelSpec = KernelSpec {
    name: "flat_bending",
    n_inputs: 12,
    n_params: PARAMS,
    energy: |x, p| flat_bending_energy(&points_from_flat(x), p),
};

fn cot(a: Vector3<f64>, b: Vector3<f64>) -> f64 {
    a.dot(&b) / a.cross(&b).norm()
}

impl FlatBending {
    /// Add bending to the interior edges of a triangle mesh (indices local to `set`).
    pub fn add(
        &mut self,
        nodes: &NodeArrays,
        set: NodeSetHandle,
        label: &str,
        triangles: &[[usize; 3]],
        params: FlatBendingParams,
    ) -> Result<FlatBendingHandle> {
        params.validate(label)?;
        let local =
            find_hinges(triangles).map_err(|e| StarkError::InvalidInput(format!("bending of '{label}': {e}")))?;
        let hinges = globalize(&set, label, "hinge", &local)?;
        let mut weights = Vec::with_capacity(hinges.len());
        for (index, h) in hinges.iter().enumerate() {
            let x = h.map(|i| nodes.rest[i as usize]);
            let (e0, e1, e2, e3, e4) = (x[1] - x[0], x[2] - x[0], x[3] - x[0], x[2] - x[1], x[3] - x[1]);
            let a0 = 0.5 * e0.cross(&e1).norm();
            let a1 = 0.5 * e0.cross(&e2).norm();
            let (c01, c02, c03, c04) = (cot(e0, e1), cot(e0, e2), cot(-e0, e3), cot(-e0, e4));
            let k = [c03 + c04, c01 + c02, -c01 - c03, -c02 - c04];
            let q = 3.0 / (a0 + a1) * 0.5;
            if !(k.iter().all(|v| v.is_finite()) && q.is_finite()) {
                return Err(StarkError::BadElement {
                    object: label.to_string(),
                    kind: "hinge",
                    index,
                    detail: "a triangle of the hinge is degenerate".into(),
                });
            }
            weights.push((k, q));
        }
        let g = self.groups.push(label, params);
        self.group.extend(std::iter::repeat_n(g, hinges.len()));
        self.hinges.extend(hinges);
        self.weights.extend(weights);
        self.version += 1;
        Ok(FlatBendingHandle(g))
    }

    /// Parameters of a group.
    pub fn params(&self, h: FlatBendingHandle) -> Result<&FlatBendingParams> {
        self.groups.get("flat bending", h.0)
    }

    /// Change the parameters of a group.
    pub fn set_params(&mut self, h: FlatBendingHandle, params: FlatBendingParams) -> Result<()> {
        self.groups
            .set("flat bending", h.0, params, |p, label| p.validate(label))
    }

    fn kernel_params(&self, e: usize, stencil: &Stencil<4>) -> [f64; PARAMS] {
        let params = &self.groups.params[self.group[e] as usize];
        let (k, q) = self.weights[e];
        let x0 = stencil.x0;
        let kx0 = |d: usize| k[0] * x0[0][d] + k[1] * x0[1][d] + k[2] * x0[2][d] + k[3] * x0[3][d];
        [
            k[0],
            k[1],
            k[2],
            k[3],
            params.stiffness * q,
            params.damping / stencil.dt * q,
            kx0(0),
            kx0(1),
            kx0(2),
        ]
    }
}

impl Potential<4> for FlatBending {
    fn name(&self) -> &str {
        "flat bending"
    }
    fn save_state(&self) -> Vec<u8> {
        // Parameters may change between steps (`set_params`, time events, hardening).
        crate::energy::encode_state(&self.groups.params)
    }
    fn restore_state(&mut self, bytes: &[u8]) -> Result<(), String> {
        crate::energy::restore_vec(&mut self.groups.params, crate::energy::decode_state(bytes)?, "groups")
    }
    fn num_elements(&self) -> usize {
        self.hinges.len()
    }
    fn nodes(&self, e: usize) -> [Node; 4] {
        self.hinges[e].map(Node::Point)
    }
    fn energy<S: Scalar>(&self, e: usize, x: &[Vec3<S>; 4], stencil: &Stencil<4>) -> S {
        flat_bending_energy(x, &self.kernel_params(e, stencil).map(S::constant))
    }
    fn derivatives(&self, e: usize, stencil: &Stencil<4>, _project: bool, out: &mut HyperDual<4>) -> FastDerivatives {
        run_kernel(
            generated::flat_bending,
            &stencil.x,
            &self.kernel_params(e, stencil),
            out,
        )
    }
    fn topology_version(&self) -> u64 {
        self.version
    }
    fn is_convex(&self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::testing::{assert_derivatives, TestState};

    #[test]
    fn flat_is_energy_free_and_derivatives_match() {
        let rest = vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.3, 0.8, 0.0),
            Vector3::new(0.6, -0.7, 0.0),
        ];
        let tris = [[0, 1, 2], [1, 0, 3]];
        let v = vec![
            Vector3::new(0.1, 0.2, 0.5),
            Vector3::new(-0.3, 0.0, 0.1),
            Vector3::new(0.0, 0.4, -2.0),
            Vector3::new(0.2, 0.1, 1.0),
        ];
        let st = TestState::new(rest.clone(), rest.clone(), vec![Vector3::zeros(); 4], v, 0.05);
        let set = NodeSetHandle {
            index: 0,
            first: 0,
            len: 4,
        };
        let mut fb = FlatBending::default();
        fb.add(
            &st.nodes,
            set,
            "cloth",
            &tris,
            FlatBendingParams {
                stiffness: 1e-3,
                damping: 1e-4,
            },
        )
        .unwrap();
        assert_eq!(fb.num_elements(), 1);
        assert_derivatives(&fb, &st.eval(), 1e-6);
        // A rigid motion of a flat hinge costs no bending energy (K sums to zero, K·x = 0 in plane).
        let st0 = TestState::new(
            rest.clone(),
            rest.clone(),
            vec![Vector3::zeros(); 4],
            vec![Vector3::new(0.1, -0.2, 0.3); 4],
            0.05,
        );
        let eval = st0.eval();
        let stencil = Stencil::new(fb.nodes(0), &eval);
        let e: f64 = fb.energy(0, &stencil.x_as::<f64>(), &stencil);
        assert!(e.abs() < 1e-14, "{e}");
    }
}
