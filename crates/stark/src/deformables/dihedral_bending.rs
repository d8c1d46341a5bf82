//! Shell bending towards a curved rest shape: discrete shells (Grinspun et al. 2003).
//!
//! For a hinge `[x₀, x₁, x₂, x₃]` (shared edge `x₀x₁`, opposite vertices `x₂` of triangle A and
//! `x₃` of triangle B) the energy is `k (θ − θ̄)² ‖ē‖/h̄`, with `h̄ = (h_A + h_B)/6` from the rest
//! triangle heights over the edge, as in the original Stark. The dihedral angle is *signed*,
//! `θ = atan2((n_A × n_B)·ê, n_A·n_B)` with `n_A = (x₁−x₀)×(x₂−x₀)`, `n_B = (x₃−x₀)×(x₁−x₀)`, so
//! it stays smooth through the flat state (the original's `acos` form is not). Damping adds
//! `½ (c/dt) (θ − θ⁰)² ‖ē‖/h̄`, a Rayleigh dissipation on the angle rate.

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
    /// Discrete-shell bending towards the rest dihedral angles (curved shells).
    #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct DihedralBendingParams {
        /// Bending stiffness `k`, N·m (default: 1e-6).
        pub stiffness: f64,
        /// Bending damping `c`, N·m·s (default: 0).
        pub damping: f64,
    }
}

impl Default for DihedralBendingParams {
    fn default() -> Self {
        DihedralBendingParams {
            stiffness: 1e-6,
            damping: 0.0,
        }
    }
}

impl DihedralBendingParams {
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
pub struct DihedralBendingHandle(pub u32);

/// Discrete-shell bending of all shells with a curved rest shape.
#[derive(Default)]
pub struct DihedralBending {
    groups: Groups<DihedralBendingParams>,
    hinges: Vec<[u32; 4]>,
    group: Vec<u32>,
    /// Rest angle θ̄ (rad) and `‖ē‖/h̄` per hinge.
    rest: Vec<(f64, f64)>,
    version: u64,
}

/// Kernel parameters: `θ̄`, `k ‖ē‖/h̄`, `(c/dt) ‖ē‖/h̄`, `θ⁰`.
pub const PARAMS: usize = 4;

/// Signed dihedral angle of a hinge, rad.
pub fn dihedral_angle<S: Scalar>(x: &[Vec3<S>; 4]) -> S {
    let e = x[1] - x[0];
    let na = e.cross(&(x[2] - x[0]));
    let nb = (x[3] - x[0]).cross(&e);
    let sin_part = na.cross(&nb).dot(&e) * e.norm().recip();
    sin_part.atan2(na.dot(&nb))
}

/// Energy of one hinge (J).
pub fn dihedral_bending_energy<S: Scalar>(x: &[Vec3<S>; 4], p: &[S]) -> S {
    let theta = dihedral_angle(x);
    p[1] * (theta - p[0]).sq() + p[2] * (theta - p[3]).sq() * 0.5
}

/// Generated kernel.
pub const KERNEL: KernelSpec = KernelSpec {
    name: "dihedral_bending",
    n_inputs: 12,
    n_params: PARAMS,
    energy: |x, p| dihedral_bending_energy(&points_from_flat(x), p),
};

impl DihedralBending {
    /// Add bending to the interior edges of a triangle mesh (indices local to `set`); the rest
    /// angles are those of the rest positions.
    pub fn add(
        &mut self,
        nodes: &NodeArrays,
        set: NodeSetHandle,
        label: &str,
        triangles: &[[usize; 3]],
        params: DihedralBendingParams,
    ) -> Result<DihedralBendingHandle> {
        params.validate(label)?;
        let local =
            find_hinges(triangles).map_err(|e| StarkError::InvalidInput(format!("bending of '{label}': {e}")))?;
        let hinges = globalize(&set, label, "hinge", &local)?;
        let mut rest = Vec::with_capacity(hinges.len());
        for (index, h) in hinges.iter().enumerate() {
            let x: [Vector3<f64>; 4] = h.map(|i| nodes.rest[i as usize]);
            let e = x[1] - x[0];
            let len = e.norm();
            let ha = e.cross(&(x[2] - x[0])).norm() / len;
            let hb = e.cross(&(x[3] - x[0])).norm() / len;
            let ratio = len / ((ha + hb) / 6.0);
            let theta: f64 = dihedral_angle(&x.map(|p| Vec3::constant(&p)));
            if !(ratio.is_finite() && theta.is_finite() && ha > 0.0 && hb > 0.0) {
                return Err(StarkError::BadElement {
                    object: label.to_string(),
                    kind: "hinge",
                    index,
                    detail: "a triangle of the hinge is degenerate".into(),
                });
            }
            rest.push((theta, ratio));
        }
        let g = self.groups.push(label, params);
        self.group.extend(std::iter::repeat_n(g, hinges.len()));
        self.hinges.extend(hinges);
        self.rest.extend(rest);
        self.version += 1;
        Ok(DihedralBendingHandle(g))
    }

    /// Parameters of a group.
    pub fn params(&self, h: DihedralBendingHandle) -> Result<&DihedralBendingParams> {
        self.groups.get("dihedral bending", h.0)
    }

    /// Change the parameters of a group.
    pub fn set_params(&mut self, h: DihedralBendingHandle, params: DihedralBendingParams) -> Result<()> {
        self.groups
            .set("dihedral bending", h.0, params, |p, label| p.validate(label))
    }

    fn kernel_params(&self, e: usize, stencil: &Stencil<4>) -> [f64; PARAMS] {
        let params = &self.groups.params[self.group[e] as usize];
        let (theta_rest, ratio) = self.rest[e];
        let theta0 = dihedral_angle(&stencil.x0.map(|p| Vec3::constant(&p)));
        [
            theta_rest,
            params.stiffness * ratio,
            params.damping / stencil.dt * ratio,
            theta0,
        ]
    }
}

impl Potential<4> for DihedralBending {
    fn name(&self) -> &str {
        "dihedral bending"
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
        dihedral_bending_energy(x, &self.kernel_params(e, stencil).map(S::constant))
    }
    fn derivatives(&self, e: usize, stencil: &Stencil<4>, _project: bool, out: &mut HyperDual<4>) -> FastDerivatives {
        run_kernel(
            generated::dihedral_bending,
            &stencil.x,
            &self.kernel_params(e, stencil),
            out,
        )
    }
    fn topology_version(&self) -> u64 {
        self.version
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::testing::{assert_derivatives, TestState};

    #[test]
    fn angle_sign_and_derivatives() {
        // A hinge folded by +30° about the x axis: x₃ lifted above the plane.
        let a = 30f64.to_radians();
        let rest = vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.4, 0.8, 0.0),
            Vector3::new(0.5, -0.8 * a.cos(), 0.8 * a.sin()),
        ];
        let theta: f64 = dihedral_angle(&[0, 1, 2, 3].map(|i| Vec3::constant(&rest[i])));
        assert!((theta.abs() - a).abs() < 1e-12, "{theta}");
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
        let mut db = DihedralBending::default();
        db.add(
            &st.nodes,
            set,
            "shell",
            &tris,
            DihedralBendingParams {
                stiffness: 1e-3,
                damping: 1e-4,
            },
        )
        .unwrap();
        assert_derivatives(&db, &st.eval(), 1e-7);
        // At rest, no bending force.
        let st0 = TestState::new(
            rest.clone(),
            rest,
            vec![Vector3::zeros(); 4],
            vec![Vector3::zeros(); 4],
            0.05,
        );
        let eval = st0.eval();
        let d = crate::energy::potential::dual_derivatives(&db, 0, &Stencil::new(db.nodes(0), &eval));
        assert!(d.gradient_flat().iter().all(|g| g.abs() < 1e-12));
    }
}
