//! Lumped inertia of deformable nodes, with gravity, external forces and inertial damping.
//!
//! Per node of mass `m`, with `v = (x − x0)/dt` the end-of-step velocity (DESIGN §2):
//!
//! `E = ½ m ‖v − v0‖² + ½ m d dt ‖v‖² − dt (m (g + a) + f)·v`
//!
//! Its stationarity condition `m (v − v0)/dt = m (g + a) + f − m d v` is backward Euler with a
//! drag `−m d v` (inertial Rayleigh damping, `d` in 1/s; the original's "inertia damping").
//! In quasistatic mode the kinetic terms are dropped and only the external work remains.

use super::{Groups, NodeSetHandle};
use crate::energy::symbolic::KernelSpec;
use crate::energy::{points_from_flat, run_kernel, FastDerivatives, HyperDual, Node, Potential, Scalar, Stencil, Vec3};
use crate::error::{check_param, Result, StarkError};
use crate::generated;
use serde::{Deserialize, Serialize};

crate::params::param_struct! {
    /// Lumped inertia of a deformable object.
    #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct InertiaParams {
        /// Density per unit length, area or volume of the elements the mass is lumped from: kg/m,
        /// kg/m² or kg/m³ (default: 1).
        pub density: f64,
        /// Inertial damping `d`, 1/s: a drag force `−m d v` (default: 0).
        pub damping: f64,
        /// Drop the kinetic terms: each step solves for static equilibrium (default: false).
        pub quasistatic: bool,
    }
}

impl Default for InertiaParams {
    fn default() -> Self {
        InertiaParams {
            density: 1.0,
            damping: 0.0,
            quasistatic: false,
        }
    }
}

impl InertiaParams {
    /// Check every field.
    pub fn validate(&self, object: &str) -> Result<()> {
        let r = self.density;
        check_param(
            object,
            "density",
            r,
            r > 0.0 && r.is_finite(),
            "must be positive and finite",
        )?;
        let d = self.damping;
        check_param(
            object,
            "damping",
            d,
            d >= 0.0 && d.is_finite(),
            "must be non-negative and finite (1/s)",
        )
    }
}

/// Handle to the inertia of one object.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct InertiaHandle(pub u32);

/// Lumped masses of all deformable nodes.
#[derive(Default)]
pub struct LumpedInertia {
    groups: Groups<InertiaParams>,
    node: Vec<u32>,
    /// Lumped measure (length, area or volume) per element; mass = measure · density.
    measure: Vec<f64>,
    group: Vec<u32>,
    version: u64,
}

/// Kernel parameters: `x0` (3), `v0` (3), external force `m(g + a) + f` (3), `m`, `d`, `dt`,
/// `inertial` (1, or 0 in quasistatic mode).
pub const PARAMS: usize = 13;

/// Energy of one node (J·s²/s² units of the velocity objective, see module docs).
pub fn inertia_energy<S: Scalar>(x: &[Vec3<S>; 1], p: &[S]) -> S {
    let (m, damping, dt, inertial) = (p[9], p[10], p[11], p[12]);
    let inv_dt = dt.recip();
    let v = Vec3([
        (x[0][0] - p[0]) * inv_dt,
        (x[0][1] - p[1]) * inv_dt,
        (x[0][2] - p[2]) * inv_dt,
    ]);
    let dv = Vec3([v[0] - p[3], v[1] - p[4], v[2] - p[5]]);
    let work = (v[0] * p[6] + v[1] * p[7] + v[2] * p[8]) * dt;
    (dv.norm_sq() * 0.5 + v.norm_sq() * damping * dt * 0.5) * m * inertial - work
}

/// Generated kernel.
pub const KERNEL: KernelSpec = KernelSpec {
    name: "lumped_inertia",
    n_inputs: 3,
    n_params: PARAMS,
    energy: |x, p| inertia_energy(&points_from_flat(x), p),
};

impl LumpedInertia {
    /// Add nodes of `set` with lumped measures (length, area or volume per node, indexed locally);
    /// nodes with zero measure get no inertia from this group.
    pub fn add(
        &mut self,
        set: NodeSetHandle,
        label: &str,
        measures: &[f64],
        params: InertiaParams,
    ) -> Result<InertiaHandle> {
        params.validate(label)?;
        if measures.len() != set.len as usize {
            return Err(StarkError::InvalidInput(format!(
                "inertia of '{label}': {} lumped measures given for {} nodes",
                measures.len(),
                set.len
            )));
        }
        let g = self.groups.push(label, params);
        for (i, &w) in measures.iter().enumerate() {
            if !(w >= 0.0 && w.is_finite()) {
                return Err(StarkError::InvalidInput(format!(
                    "inertia of '{label}': lumped measure {w} of node {i} is invalid"
                )));
            }
            if w > 0.0 {
                self.node.push(set.global(i) as u32);
                self.measure.push(w);
                self.group.push(g);
            }
        }
        self.version += 1;
        Ok(InertiaHandle(g))
    }

    /// Parameters of a group.
    pub fn params(&self, h: InertiaHandle) -> Result<&InertiaParams> {
        self.groups.get("inertia", h.0)
    }

    /// Change the parameters of a group.
    pub fn set_params(&mut self, h: InertiaHandle, params: InertiaParams) -> Result<()> {
        self.groups.set("inertia", h.0, params, |p, label| p.validate(label))
    }

    /// Mass of each node (kg), summed over groups, for `n_nodes` nodes.
    pub fn node_masses(&self, n_nodes: usize) -> Vec<f64> {
        let mut m = vec![0.0; n_nodes];
        for k in 0..self.node.len() {
            m[self.node[k] as usize] += self.measure[k] * self.groups.params[self.group[k] as usize].density;
        }
        m
    }

    /// Total mass of a group, kg.
    pub fn mass(&self, h: InertiaHandle) -> Result<f64> {
        let g = self.groups.check("inertia", h.0)?;
        let density = self.groups.params[g].density;
        Ok((0..self.node.len())
            .filter(|&k| self.group[k] as usize == g)
            .map(|k| self.measure[k] * density)
            .sum())
    }

    fn kernel_params(&self, e: usize, stencil: &Stencil<1>) -> [f64; PARAMS] {
        let params = &self.groups.params[self.group[e] as usize];
        let m = self.measure[e] * params.density;
        let i = self.node[e] as usize;
        let s = stencil.state;
        let f = (s.gravity + s.nodes.acceleration[i]) * m + s.nodes.force[i];
        let (x0, v0) = (stencil.x0[0], s.nodes.v[i]);
        [
            x0.x,
            x0.y,
            x0.z,
            v0.x,
            v0.y,
            v0.z,
            f.x,
            f.y,
            f.z,
            m,
            params.damping,
            stencil.dt,
            if params.quasistatic { 0.0 } else { 1.0 },
        ]
    }
}

impl Potential<1> for LumpedInertia {
    fn name(&self) -> &str {
        "lumped inertia"
    }
    fn save_state(&self) -> Vec<u8> {
        // Parameters may change between steps (`set_params`, time events, hardening).
        crate::energy::encode_state(&self.groups.params)
    }
    fn restore_state(&mut self, bytes: &[u8]) -> Result<(), String> {
        crate::energy::restore_vec(&mut self.groups.params, crate::energy::decode_state(bytes)?, "groups")
    }
    fn num_elements(&self) -> usize {
        self.node.len()
    }
    fn nodes(&self, e: usize) -> [Node; 1] {
        [Node::Point(self.node[e])]
    }
    fn energy<S: Scalar>(&self, e: usize, x: &[Vec3<S>; 1], stencil: &Stencil<1>) -> S {
        inertia_energy(x, &self.kernel_params(e, stencil).map(S::constant))
    }
    fn derivatives(&self, e: usize, stencil: &Stencil<1>, _project: bool, out: &mut HyperDual<1>) -> FastDerivatives {
        run_kernel(
            generated::lumped_inertia,
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
    use nalgebra::Vector3;

    #[test]
    fn derivatives_match_finite_differences() {
        let x0 = vec![Vector3::new(0.1, -0.2, 0.3), Vector3::new(1.0, 2.0, 3.0)];
        let mut st = TestState::new(
            x0.clone(),
            x0,
            vec![Vector3::new(0.5, 0.1, -2.0), Vector3::zeros()],
            vec![Vector3::new(0.3, -0.4, 1.0), Vector3::new(2.0, 0.0, 0.1)],
            0.02,
        );
        st.nodes.force[1] = Vector3::new(0.0, 3.0, 0.0);
        let set = NodeSetHandle {
            index: 0,
            first: 0,
            len: 2,
        };
        let mut inertia = LumpedInertia::default();
        inertia
            .add(
                set,
                "a",
                &[0.5, 0.25],
                InertiaParams {
                    density: 2.0,
                    damping: 0.3,
                    quasistatic: false,
                },
            )
            .unwrap();
        inertia
            .add(
                set,
                "q",
                &[0.0, 1.0],
                InertiaParams {
                    quasistatic: true,
                    ..Default::default()
                },
            )
            .unwrap();
        assert_derivatives(&inertia, &st.eval(), 1e-6);
        assert_eq!(inertia.node_masses(2), vec![1.0, 1.5]);
    }
}
