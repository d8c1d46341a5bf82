//! Attachments between deformable objects: a node glued to another node, to a point on an edge,
//! or to a point on a triangle, by a stiff spring hardened until within a tolerance.
//!
//! `E = ½ k ‖x_p − Σᵢ wᵢ yᵢ‖²` with barycentric weights `wᵢ` of the target primitive's nodes `yᵢ`
//! (the original Stark's point–point, point–edge and point–triangle attachments).

use super::{Groups, NodeSetHandle};
use crate::energy::symbolic::KernelSpec;
use crate::energy::{
    points_from_flat, run_kernel, EnergyTerm, FastDerivatives, HyperDual, Kernel, Node, Potential, PotentialTerm,
    Scalar, Stencil, StepCheck, Vec3,
};
use crate::error::{check_param, Result, StarkError};
use crate::generated;
use crate::state::EvalState;
use serde::{Deserialize, Serialize};

crate::params::param_struct! {
    /// Attachments between deformable objects: stiff springs hardened to a tolerance.
    #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct AttachmentParams {
        /// Spring stiffness `k`, N/m (default: 1e3).
        pub stiffness: f64,
        /// Largest allowed gap after a step, m; exceeding it doubles the stiffness and repeats the
        /// step (default: ∞, no hardening).
        pub tolerance_m: f64,
    }
}

impl Default for AttachmentParams {
    fn default() -> Self {
        AttachmentParams {
            stiffness: 1e3,
            tolerance_m: f64::INFINITY,
        }
    }
}

impl AttachmentParams {
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

/// Handle to a group of attachments: which kind and which group.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum AttachmentHandle {
    /// Point–point group.
    PointPoint(u32),
    /// Point–edge group.
    PointEdge(u32),
    /// Point–triangle group.
    PointTriangle(u32),
}

/// Energy `½ k ‖x₀ − Σᵢ₌₁ wᵢ xᵢ‖²`; parameters `k, w₁, …, w_{N−1}`.
pub fn attachment_energy<S: Scalar, const N: usize>(x: &[Vec3<S>; N], p: &[S]) -> S {
    let mut target = x[1] * p[1];
    for i in 2..N {
        target = target + x[i] * p[i];
    }
    (x[0] - target).norm_sq() * p[0] * 0.5
}

/// Generated kernel, point–point.
pub const POINT_POINT_KERNEL: KernelSpec = KernelSpec {
    name: "attachment_point_point",
    n_inputs: 6,
    n_params: 2,
    energy: |x, p| attachment_energy::<_, 2>(&points_from_flat(x), p),
};
/// Generated kernel, point–edge.
pub const POINT_EDGE_KERNEL: KernelSpec = KernelSpec {
    name: "attachment_point_edge",
    n_inputs: 9,
    n_params: 3,
    energy: |x, p| attachment_energy::<_, 3>(&points_from_flat(x), p),
};
/// Generated kernel, point–triangle.
pub const POINT_TRIANGLE_KERNEL: KernelSpec = KernelSpec {
    name: "attachment_point_triangle",
    n_inputs: 12,
    n_params: 4,
    energy: |x, p| attachment_energy::<_, 4>(&points_from_flat(x), p),
};

/// Attachments of one arity: a node (first) glued to a combination of `N − 1` nodes.
pub struct AttachmentSet<const N: usize> {
    groups: Groups<AttachmentParams>,
    ranges: Vec<std::ops::Range<usize>>,
    nodes: Vec<[u32; N]>,
    /// Barycentric weights of nodes `1..N` (the first entry is unused).
    weights: Vec<[f64; N]>,
    group: Vec<u32>,
    version: u64,
    name: &'static str,
}

impl<const N: usize> AttachmentSet<N> {
    fn new(name: &'static str) -> Self {
        AttachmentSet {
            groups: Groups::default(),
            ranges: vec![],
            nodes: vec![],
            weights: vec![],
            group: vec![],
            version: 0,
            name,
        }
    }

    fn add(
        &mut self,
        label: &str,
        nodes: Vec<[u32; N]>,
        weights: Vec<[f64; N]>,
        params: AttachmentParams,
    ) -> Result<u32> {
        params.validate(label)?;
        for (i, w) in weights.iter().enumerate() {
            let sum: f64 = w[1..].iter().sum();
            if !w.iter().all(|x| x.is_finite()) || (sum - 1.0).abs() > 1e-9 {
                return Err(StarkError::InvalidInput(format!(
                    "attachment {i} of '{label}': barycentric weights {:?} must be finite and sum to 1",
                    &w[1..]
                )));
            }
        }
        let g = self.groups.push(label, params);
        let start = self.nodes.len();
        self.group.extend(std::iter::repeat_n(g, nodes.len()));
        self.nodes.extend(nodes);
        self.weights.extend(weights);
        self.ranges.push(start..self.nodes.len());
        self.version += 1;
        Ok(g)
    }

    fn gap(&self, e: usize, x: &[nalgebra::Vector3<f64>]) -> f64 {
        let n = &self.nodes[e];
        let w = &self.weights[e];
        let target: nalgebra::Vector3<f64> = (1..N).map(|i| x[n[i] as usize] * w[i]).sum();
        (x[n[0] as usize] - target).norm()
    }

    fn kernel_params(&self, e: usize) -> [f64; N] {
        let mut p = self.weights[e];
        p[0] = self.groups.params[self.group[e] as usize].stiffness;
        p
    }
}

impl<const N: usize> AttachmentSet<N> {
    /// Every node taking part in an attachment (global indices, with repeats).
    pub fn attached_nodes(&self) -> impl Iterator<Item = u32> + '_ {
        self.nodes.iter().flatten().copied()
    }
}

impl<const N: usize> Potential<N> for AttachmentSet<N> {
    fn name(&self) -> &str {
        self.name
    }
    fn save_state(&self) -> Vec<u8> {
        // Parameters may change between steps (`set_params`, time events, hardening).
        crate::energy::encode_state(&self.groups.params)
    }
    fn restore_state(&mut self, bytes: &[u8]) -> Result<(), String> {
        crate::energy::restore_vec(&mut self.groups.params, crate::energy::decode_state(bytes)?, "groups")
    }
    fn num_elements(&self) -> usize {
        self.nodes.len()
    }
    fn nodes(&self, e: usize) -> [Node; N] {
        self.nodes[e].map(Node::Point)
    }
    fn energy<S: Scalar>(&self, e: usize, x: &[Vec3<S>; N], _stencil: &Stencil<N>) -> S {
        attachment_energy(x, &self.kernel_params(e).map(S::constant))
    }
    fn derivatives(&self, e: usize, stencil: &Stencil<N>, _project: bool, out: &mut HyperDual<N>) -> FastDerivatives {
        let kernel: Kernel = match N {
            2 => generated::attachment_point_point,
            3 => generated::attachment_point_edge,
            4 => generated::attachment_point_triangle,
            _ => return FastDerivatives::Unavailable,
        };
        run_kernel(kernel, &stencil.x, &self.kernel_params(e), out)
    }
    fn topology_version(&self) -> u64 {
        self.version
    }
    fn is_convex(&self) -> bool {
        true
    }
    fn check_converged_step(&mut self, state: &EvalState) -> StepCheck {
        let gaps: Vec<f64> = (0..self.nodes.len()).map(|e| self.gap(e, state.x)).collect();
        harden_out_of_tolerance(&mut self.groups, &self.ranges, |e| gaps[e], "attachments")
    }
}

/// Double the stiffness of every attachment group whose largest gap (`gap` of its elements)
/// exceeds its tolerance, and ask for a retry if any did (shared by the deformable and the
/// deformable–rigid attachments).
pub(crate) fn harden_out_of_tolerance(
    groups: &mut Groups<AttachmentParams>,
    ranges: &[std::ops::Range<usize>],
    gap: impl Fn(usize) -> f64,
    what: &str,
) -> StepCheck {
    let mut hardened = Vec::new();
    for (g, range) in ranges.iter().enumerate() {
        let tol = groups.params[g].tolerance_m;
        if !tol.is_finite() {
            continue;
        }
        let worst = range.clone().map(&gap).fold(0.0, f64::max);
        if worst > tol {
            let p = &mut groups.params[g];
            p.stiffness *= 2.0;
            hardened.push(format!(
                "'{}' ({worst:.3e} m > {tol:.3e} m, k → {:.3e} N/m)",
                groups.labels[g], p.stiffness
            ));
        }
    }
    if hardened.is_empty() {
        StepCheck::Accept
    } else {
        StepCheck::Retry(format!(
            "{what} out of tolerance, stiffness doubled: {}",
            hardened.join(", ")
        ))
    }
}

/// All deformable–deformable attachments.
pub struct Attachments {
    /// Node glued to node.
    pub point_point: PotentialTerm<AttachmentSet<2>, 2>,
    /// Node glued to a point on an edge.
    pub point_edge: PotentialTerm<AttachmentSet<3>, 3>,
    /// Node glued to a point on a triangle.
    pub point_triangle: PotentialTerm<AttachmentSet<4>, 4>,
}

impl Default for Attachments {
    fn default() -> Self {
        Attachments {
            point_point: PotentialTerm::new(AttachmentSet::new("point-point attachments")),
            point_edge: PotentialTerm::new(AttachmentSet::new("point-edge attachments")),
            point_triangle: PotentialTerm::new(AttachmentSet::new("point-triangle attachments")),
        }
    }
}

fn check_local(set: &NodeSetHandle, label: &str, i: usize) -> Result<u32> {
    if i < set.len as usize {
        Ok(set.global(i) as u32)
    } else {
        Err(StarkError::InvalidInput(format!(
            "attachment '{label}': node {i} does not exist ({} nodes)",
            set.len
        )))
    }
}

impl Attachments {
    /// Glue node `points_a[i]` of `a` to node `points_b[i]` of `b`.
    pub fn add_point_point(
        &mut self,
        label: &str,
        a: NodeSetHandle,
        points_a: &[usize],
        b: NodeSetHandle,
        points_b: &[usize],
        params: AttachmentParams,
    ) -> Result<AttachmentHandle> {
        if points_a.len() != points_b.len() {
            return Err(StarkError::InvalidInput(format!(
                "attachment '{label}': {} points on one side, {} on the other",
                points_a.len(),
                points_b.len()
            )));
        }
        let nodes = points_a
            .iter()
            .zip(points_b)
            .map(|(&p, &q)| Ok([check_local(&a, label, p)?, check_local(&b, label, q)?]))
            .collect::<Result<Vec<_>>>()?;
        let weights = vec![[0.0, 1.0]; nodes.len()];
        Ok(AttachmentHandle::PointPoint(
            self.point_point.add(label, nodes, weights, params)?,
        ))
    }

    /// Glue node `points[i]` of `a` to the point `(1 − t) e₀ + t e₁` of edge `edges[i]` of `b`.
    pub fn add_point_edge(
        &mut self,
        label: &str,
        a: NodeSetHandle,
        points: &[usize],
        b: NodeSetHandle,
        edges: &[[usize; 2]],
        edge_parameters: &[f64],
        params: AttachmentParams,
    ) -> Result<AttachmentHandle> {
        if points.len() != edges.len() || points.len() != edge_parameters.len() {
            return Err(StarkError::InvalidInput(format!(
                "attachment '{label}': points, edges and edge parameters differ in length"
            )));
        }
        let mut nodes = Vec::new();
        let mut weights = Vec::new();
        for ((&p, e), &t) in points.iter().zip(edges).zip(edge_parameters) {
            nodes.push([
                check_local(&a, label, p)?,
                check_local(&b, label, e[0])?,
                check_local(&b, label, e[1])?,
            ]);
            weights.push([0.0, 1.0 - t, t]);
        }
        Ok(AttachmentHandle::PointEdge(
            self.point_edge.add(label, nodes, weights, params)?,
        ))
    }

    /// Glue node `points[i]` of `a` to the point with barycentric coordinates `barycentric[i]`
    /// (summing to 1) of triangle `triangles[i]` of `b`.
    pub fn add_point_triangle(
        &mut self,
        label: &str,
        a: NodeSetHandle,
        points: &[usize],
        b: NodeSetHandle,
        triangles: &[[usize; 3]],
        barycentric: &[[f64; 3]],
        params: AttachmentParams,
    ) -> Result<AttachmentHandle> {
        if points.len() != triangles.len() || points.len() != barycentric.len() {
            return Err(StarkError::InvalidInput(format!(
                "attachment '{label}': points, triangles and coordinates differ in length"
            )));
        }
        let mut nodes = Vec::new();
        let mut weights = Vec::new();
        for ((&p, t), w) in points.iter().zip(triangles).zip(barycentric) {
            nodes.push([
                check_local(&a, label, p)?,
                check_local(&b, label, t[0])?,
                check_local(&b, label, t[1])?,
                check_local(&b, label, t[2])?,
            ]);
            weights.push([0.0, w[0], w[1], w[2]]);
        }
        Ok(AttachmentHandle::PointTriangle(
            self.point_triangle.add(label, nodes, weights, params)?,
        ))
    }

    /// Parameters of a group.
    pub fn params(&self, h: AttachmentHandle) -> Result<&AttachmentParams> {
        match h {
            AttachmentHandle::PointPoint(g) => self.point_point.groups.get("attachment", g),
            AttachmentHandle::PointEdge(g) => self.point_edge.groups.get("attachment", g),
            AttachmentHandle::PointTriangle(g) => self.point_triangle.groups.get("attachment", g),
        }
    }

    /// Change the parameters of a group (stiffness, tolerance).
    pub fn set_params(&mut self, h: AttachmentHandle, params: AttachmentParams) -> Result<()> {
        let validate = |p: &AttachmentParams, label: &str| p.validate(label);
        match h {
            AttachmentHandle::PointPoint(g) => self.point_point.groups.set("attachment", g, params, validate),
            AttachmentHandle::PointEdge(g) => self.point_edge.groups.set("attachment", g, params, validate),
            AttachmentHandle::PointTriangle(g) => self.point_triangle.groups.set("attachment", g, params, validate),
        }
    }

    /// Largest gap of a group at positions `x`, m.
    pub fn max_gap_m(&self, h: AttachmentHandle, x: &[nalgebra::Vector3<f64>]) -> Result<f64> {
        fn worst<const N: usize>(s: &AttachmentSet<N>, g: u32, x: &[nalgebra::Vector3<f64>]) -> Result<f64> {
            let g = s.groups.check("attachment", g)?;
            Ok(s.ranges[g].clone().map(|e| s.gap(e, x)).fold(0.0, f64::max))
        }
        match h {
            AttachmentHandle::PointPoint(g) => worst(&self.point_point, g, x),
            AttachmentHandle::PointEdge(g) => worst(&self.point_edge, g, x),
            AttachmentHandle::PointTriangle(g) => worst(&self.point_triangle, g, x),
        }
    }

    /// The three terms, for the solver.
    pub fn terms_mut(&mut self) -> Vec<&mut dyn EnergyTerm> {
        vec![&mut self.point_point, &mut self.point_edge, &mut self.point_triangle]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::testing::{assert_derivatives, TestState};
    use nalgebra::Vector3;

    #[test]
    fn derivatives_match_finite_differences() {
        let x0: Vec<_> = (0..5)
            .map(|i| Vector3::new(i as f64 * 0.1, (i * i) as f64 * 0.05, 0.02 * i as f64))
            .collect();
        let v: Vec<_> = (0..5)
            .map(|i| Vector3::new(0.3 - 0.1 * i as f64, 0.2, -0.1 * i as f64))
            .collect();
        let st = TestState::new(x0.clone(), x0, vec![Vector3::zeros(); 5], v, 0.02);
        let set = NodeSetHandle {
            index: 0,
            first: 0,
            len: 5,
        };
        let mut att = Attachments::default();
        let p = AttachmentParams {
            stiffness: 1e4,
            tolerance_m: 1e-3,
        };
        att.add_point_point("pp", set, &[0], set, &[4], p.clone()).unwrap();
        att.add_point_edge("pe", set, &[0], set, &[[1, 2]], &[0.3], p.clone())
            .unwrap();
        att.add_point_triangle("pt", set, &[0], set, &[[1, 2, 3]], &[[0.2, 0.5, 0.3]], p)
            .unwrap();
        let eval = st.eval();
        assert_derivatives(&*att.point_point, &eval, 1e-6);
        assert_derivatives(&*att.point_edge, &eval, 1e-6);
        assert_derivatives(&*att.point_triangle, &eval, 1e-6);
        let err = att
            .add_point_triangle(
                "bad",
                set,
                &[0],
                set,
                &[[1, 2, 3]],
                &[[0.2, 0.2, 0.2]],
                AttachmentParams::default(),
            )
            .unwrap_err();
        assert!(err.to_string().contains("sum to 1"), "{err}");
    }
}
