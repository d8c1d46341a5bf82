//! Prescribed positions: nodes pulled to kinematic targets by a stiff spring, hardened until within
//! a tolerance.
//!
//! `E = ½ k ‖x − x̂‖²` per node. The targets `x̂` are the nodes' rest positions under a rigid
//! transform (`set_transform`) or are set per node. After Newton converges, if any node of a group
//! is farther than `tolerance_m` from its target, the group's stiffness is doubled and the step is
//! repeated (the original's hardening rule).

use super::{Groups, NodeSetHandle};
use crate::energy::symbolic::KernelSpec;
use crate::energy::{
    points_from_flat, run_kernel, FastDerivatives, HyperDual, Node, Potential, Scalar, Stencil, StepCheck, Vec3,
};
use crate::error::{check_param, Result, StarkError};
use crate::generated;
use crate::state::{EvalState, NodeArrays};
use nalgebra::{Rotation3, Unit, Vector3};
use serde::{Deserialize, Serialize};

crate::params::param_struct! {
    /// Prescribed positions: nodes pulled to targets by stiff springs hardened to a tolerance.
    #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct PrescribedParams {
        /// Spring stiffness `k`, N/m (default: 1e3).
        pub stiffness: f64,
        /// Largest allowed distance to the target after a step, m; exceeding it doubles the stiffness
        /// and repeats the step (default: ∞, no hardening).
        pub tolerance_m: f64,
    }
}

impl Default for PrescribedParams {
    fn default() -> Self {
        PrescribedParams {
            stiffness: 1e3,
            tolerance_m: f64::INFINITY,
        }
    }
}

impl PrescribedParams {
    /// Check every field.
    pub fn validate(&self, object: &str) -> Result<()> {
        let k = self.stiffness;
        check_param(
            object,
            "stiffness",
            k,
            k > 0.0 && k.is_finite(),
            "must be positive and finite (N/m)",
        )?;
        check_param(
            object,
            "tolerance_m",
            self.tolerance_m,
            self.tolerance_m > 0.0,
            "must be positive (∞ disables hardening)",
        )
    }
}

/// Handle to a group of prescribed nodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct PrescribedHandle(pub u32);

/// All prescribed nodes.
#[derive(Default)]
pub struct PrescribedPositions {
    groups: Groups<PrescribedParams>,
    /// Element range of each group.
    ranges: Vec<std::ops::Range<usize>>,
    node: Vec<u32>,
    group: Vec<u32>,
    /// Reference positions the group transform acts on (positions when added), m.
    reference: Vec<Vector3<f64>>,
    target: Vec<Vector3<f64>>,
    version: u64,
    /// Number of hardenings so far (for logs).
    pub hardenings: usize,
}

/// Kernel parameters: target (3), stiffness.
pub const PARAMS: usize = 4;

/// `½ k ‖x − x̂‖²`.
pub fn prescribed_energy<S: Scalar>(x: &[Vec3<S>; 1], p: &[S]) -> S {
    let d = Vec3([x[0][0] - p[0], x[0][1] - p[1], x[0][2] - p[2]]);
    d.norm_sq() * p[3] * 0.5
}

/// Generated kernel.
pub const KERNEL: KernelSpec = KernelSpec {
    name: "prescribed_position",
    n_inputs: 3,
    n_params: PARAMS,
    energy: |x, p| prescribed_energy(&points_from_flat(x), p),
};

impl PrescribedPositions {
    /// Prescribe local nodes `points` of `set`; targets start at their current positions.
    pub fn add(
        &mut self,
        nodes: &NodeArrays,
        set: NodeSetHandle,
        label: &str,
        points: &[usize],
        params: PrescribedParams,
    ) -> Result<PrescribedHandle> {
        params.validate(label)?;
        if let Some(&bad) = points.iter().find(|&&p| p >= set.len as usize) {
            return Err(StarkError::InvalidInput(format!(
                "prescribed positions of '{label}': node {bad} does not exist ({} nodes)",
                set.len
            )));
        }
        let g = self.groups.push(label, params);
        let start = self.node.len();
        for &p in points {
            let i = set.global(p);
            self.node.push(i as u32);
            self.group.push(g);
            self.reference.push(nodes.x[i]);
            self.target.push(nodes.x[i]);
        }
        self.ranges.push(start..self.node.len());
        self.version += 1;
        Ok(PrescribedHandle(g))
    }

    /// Prescribe the nodes of `set` inside (or, with `inside = false`, outside) the axis-aligned
    /// box of `center` and full `size` (m). Returns the handle and the number of nodes selected.
    pub fn add_in_box(
        &mut self,
        nodes: &NodeArrays,
        set: NodeSetHandle,
        label: &str,
        center: Vector3<f64>,
        size: Vector3<f64>,
        inside: bool,
        params: PrescribedParams,
    ) -> Result<(PrescribedHandle, usize)> {
        let lo = center - size * 0.5;
        let hi = center + size * 0.5;
        let points: Vec<usize> = (0..set.len as usize)
            .filter(|&i| {
                let p = nodes.x[set.global(i)];
                let within = (0..3).all(|d| p[d] >= lo[d] && p[d] <= hi[d]);
                within == inside
            })
            .collect();
        let n = points.len();
        Ok((self.add(nodes, set, label, &points, params)?, n))
    }

    /// Parameters of a group.
    pub fn params(&self, h: PrescribedHandle) -> Result<&PrescribedParams> {
        self.groups.get("prescribed positions", h.0)
    }

    /// Change the parameters of a group.
    pub fn set_params(&mut self, h: PrescribedHandle, params: PrescribedParams) -> Result<()> {
        self.groups
            .set("prescribed positions", h.0, params, |p, label| p.validate(label))
    }

    /// Targets of the group become `R·p + t` for the reference positions `p` (positions when the
    /// group was added).
    pub fn set_transform(
        &mut self,
        h: PrescribedHandle,
        translation_m: Vector3<f64>,
        rotation: Rotation3<f64>,
    ) -> Result<()> {
        let g = self.groups.check("prescribed positions", h.0)?;
        for k in self.ranges[g].clone() {
            self.target[k] = rotation * self.reference[k] + translation_m;
        }
        Ok(())
    }

    /// [`Self::set_transform`] with a rotation by `angle_deg` about `axis` through the origin.
    pub fn set_transform_deg(
        &mut self,
        h: PrescribedHandle,
        translation_m: Vector3<f64>,
        angle_deg: f64,
        axis: Vector3<f64>,
    ) -> Result<()> {
        let rotation = Rotation3::from_axis_angle(&Unit::new_normalize(axis), angle_deg.to_radians());
        self.set_transform(h, translation_m, rotation)
    }

    /// Set the target of the `i`-th node of the group.
    pub fn set_target(&mut self, h: PrescribedHandle, i: usize, target_m: Vector3<f64>) -> Result<()> {
        let g = self.groups.check("prescribed positions", h.0)?;
        let r = self.ranges[g].clone();
        if i >= r.len() {
            return Err(StarkError::InvalidInput(format!(
                "prescribed group '{}' has {} nodes, not {}",
                self.groups.labels[g],
                r.len(),
                i + 1
            )));
        }
        self.target[r.start + i] = target_m;
        Ok(())
    }

    /// Targets of a group.
    pub fn targets(&self, h: PrescribedHandle) -> Result<&[Vector3<f64>]> {
        let g = self.groups.check("prescribed positions", h.0)?;
        Ok(&self.target[self.ranges[g].clone()])
    }

    /// Global node indices of a group.
    pub fn nodes_of(&self, h: PrescribedHandle) -> Result<&[u32]> {
        let g = self.groups.check("prescribed positions", h.0)?;
        Ok(&self.node[self.ranges[g].clone()])
    }

    /// Largest distance of a group's nodes to their targets at positions `x`, m.
    pub fn max_violation_m(&self, h: PrescribedHandle, x: &[Vector3<f64>]) -> Result<f64> {
        let g = self.groups.check("prescribed positions", h.0)?;
        Ok(self.ranges[g]
            .clone()
            .map(|k| (x[self.node[k] as usize] - self.target[k]).norm())
            .fold(0.0, f64::max))
    }
}

impl PrescribedPositions {
    /// Every prescribed node (global indices).
    pub fn prescribed_nodes(&self) -> &[u32] {
        &self.node
    }
}

impl Potential<1> for PrescribedPositions {
    fn name(&self) -> &str {
        "prescribed positions"
    }
    fn save_state(&self) -> Vec<u8> {
        // Hardened stiffnesses live in the parameters; targets move with time events.
        crate::energy::encode_state(&(&self.groups.params, &self.reference, &self.target, self.hardenings))
    }
    fn restore_state(&mut self, bytes: &[u8]) -> Result<(), String> {
        type Saved = (Vec<PrescribedParams>, Vec<Vector3<f64>>, Vec<Vector3<f64>>, usize);
        let (params, reference, target, hardenings): Saved = crate::energy::decode_state(bytes)?;
        crate::energy::restore_vec(&mut self.groups.params, params, "groups")?;
        crate::energy::restore_vec(&mut self.reference, reference, "reference positions")?;
        crate::energy::restore_vec(&mut self.target, target, "targets")?;
        self.hardenings = hardenings;
        Ok(())
    }
    fn num_elements(&self) -> usize {
        self.node.len()
    }
    fn nodes(&self, e: usize) -> [Node; 1] {
        [Node::Point(self.node[e])]
    }
    fn energy<S: Scalar>(&self, e: usize, x: &[Vec3<S>; 1], _stencil: &Stencil<1>) -> S {
        let t = self.target[e];
        let k = self.groups.params[self.group[e] as usize].stiffness;
        prescribed_energy(x, &[t.x, t.y, t.z, k].map(S::constant))
    }
    fn derivatives(&self, e: usize, stencil: &Stencil<1>, _project: bool, out: &mut HyperDual<1>) -> FastDerivatives {
        let t = self.target[e];
        let k = self.groups.params[self.group[e] as usize].stiffness;
        run_kernel(generated::prescribed_position, &stencil.x, &[t.x, t.y, t.z, k], out)
    }
    fn topology_version(&self) -> u64 {
        self.version
    }
    fn is_convex(&self) -> bool {
        true
    }
    fn check_converged_step(&mut self, state: &EvalState) -> StepCheck {
        let mut hardened = Vec::new();
        for (g, range) in self.ranges.iter().enumerate() {
            let params = &mut self.groups.params[g];
            let tol = params.tolerance_m;
            if !tol.is_finite() {
                continue;
            }
            let worst = range
                .clone()
                .map(|k| (state.x[self.node[k] as usize] - self.target[k]).norm())
                .fold(0.0, f64::max);
            if worst > tol {
                params.stiffness *= 2.0;
                hardened.push(format!(
                    "'{}' ({worst:.3e} m > {tol:.3e} m, k → {:.3e} N/m)",
                    self.groups.labels[g], params.stiffness
                ));
            }
        }
        if hardened.is_empty() {
            StepCheck::Accept
        } else {
            self.hardenings += 1;
            StepCheck::Retry(format!(
                "prescribed positions out of tolerance, stiffness doubled: {}",
                hardened.join(", ")
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::testing::{assert_derivatives, TestState};

    #[test]
    fn derivatives_and_transforms() {
        let x0 = vec![Vector3::new(0.1, -0.2, 0.3), Vector3::new(1.0, 0.0, 0.0)];
        let st = TestState::new(
            x0.clone(),
            x0,
            vec![Vector3::zeros(); 2],
            vec![Vector3::new(0.3, -0.4, 1.0), Vector3::new(2.0, 0.0, 0.1)],
            0.02,
        );
        let set = NodeSetHandle {
            index: 0,
            first: 0,
            len: 2,
        };
        let mut pp = PrescribedPositions::default();
        let h = pp
            .add(
                &st.nodes,
                set,
                "pin",
                &[0, 1],
                PrescribedParams {
                    stiffness: 1e5,
                    tolerance_m: 1e-3,
                },
            )
            .unwrap();
        pp.set_transform_deg(h, Vector3::new(0.0, 0.0, 1.0), 90.0, Vector3::z())
            .unwrap();
        let t = pp.targets(h).unwrap();
        assert!((t[1] - Vector3::new(0.0, 1.0, 1.0)).norm() < 1e-12);
        assert_derivatives(&pp, &st.eval(), 1e-6);
        // Far from target: hardened and retried.
        assert!(matches!(pp.check_converged_step(&st.eval()), StepCheck::Retry(_)));
        assert_eq!(pp.params(h).unwrap().stiffness, 2e5);
        let (_, n) = pp
            .add_in_box(
                &st.nodes,
                set,
                "box",
                Vector3::new(1.0, 0.0, 0.0),
                Vector3::repeat(0.01),
                true,
                PrescribedParams::default(),
            )
            .unwrap();
        assert_eq!(n, 1);
    }
}
