//! Rods and cables: axial strain of segments, with strain limiting and strain-rate damping.
//!
//! Per segment of rest length `L` and cross-section `A = π r²` (volume `V = A L`), with the strain
//! `ε = (l − L)/L`: `V E ε²/2`, plus `V k (ε − ε_max)³/3` above the limit, plus the damping
//! `½ (c/dt) V (ε − ε⁰)²` (a Rayleigh dissipation `½ c V ε̇²` times `dt`). The original Stark
//! has no volume factor and an extra `dt` in its damping; ours matches the triangle and tet models.
//! There is no bending or twisting stiffness (cables, nets, rubber bands).

use super::{globalize, Groups, NodeSetHandle};
use crate::energy::symbolic::KernelSpec;
use crate::energy::{points_from_flat, run_kernel, FastDerivatives, HyperDual, Node, Potential, Scalar, Stencil, Vec3};
use crate::error::{check_param, Result, StarkError};
use crate::generated;
use crate::state::NodeArrays;
use serde::{Deserialize, Serialize};

crate::params::param_struct! {
    /// Axial strain of a rod or cable made of segments.
    #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct SegmentStrainParams {
        /// Radius of the circular cross-section, m (default: 5e-3).
        pub section_radius_m: f64,
        /// Young's modulus, Pa (default: 1e3).
        pub youngs_modulus: f64,
        /// Strain-rate damping coefficient `c`, Pa·s (default: 0).
        pub damping: f64,
        /// Strain above which strain limiting acts, unitless (default: ∞, off).
        pub strain_limit: f64,
        /// Stiffness of the strain-limiting penalty, Pa (default: 1e3).
        pub strain_limit_stiffness: f64,
        /// Uniform scale of the rest length, unitless (default: 1).
        pub scale: f64,
    }
}

impl Default for SegmentStrainParams {
    fn default() -> Self {
        SegmentStrainParams {
            section_radius_m: 5e-3,
            youngs_modulus: 1e3,
            damping: 0.0,
            strain_limit: f64::INFINITY,
            strain_limit_stiffness: 1e3,
            scale: 1.0,
        }
    }
}

impl SegmentStrainParams {
    /// Check every field.
    pub fn validate(&self, object: &str) -> Result<()> {
        let r = self.section_radius_m;
        check_param(
            object,
            "section_radius_m",
            r,
            r > 0.0 && r.is_finite(),
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
}

/// Handle to a group of segments.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct SegmentStrainHandle(pub u32);

/// Axial strain of all rods.
#[derive(Default)]
pub struct SegmentStrain {
    groups: Groups<SegmentStrainParams>,
    segments: Vec<[u32; 2]>,
    group: Vec<u32>,
    rest_length: Vec<f64>,
    version: u64,
}

/// Kernel parameters: `L`, `V E`, `V (c/dt)`, `ε⁰`, `ε_max`, `V k`.
pub const PARAMS: usize = 6;

/// Energy of one segment (J).
pub fn segment_energy<S: Scalar>(x: &[Vec3<S>; 2], p: &[S]) -> S {
    let strain = ((x[1] - x[0]).norm() - p[0]) / p[0];
    let over = strain - p[4];
    p[1] * strain.sq() * 0.5
        + p[2] * (strain - p[3]).sq() * 0.5
        + S::select_gt(over, S::zero(), || p[5] * over.powi(3) * (1.0 / 3.0), S::zero)
}

/// Generated kernel.
pub const KERNEL: KernelSpec = KernelSpec {
    name: "segment_strain",
    n_inputs: 6,
    n_params: PARAMS,
    energy: |x, p| segment_energy(&points_from_flat(x), p),
};

impl SegmentStrain {
    /// Add the segments of an object (indices local to `set`).
    pub fn add(
        &mut self,
        nodes: &NodeArrays,
        set: NodeSetHandle,
        label: &str,
        segments: &[[usize; 2]],
        params: SegmentStrainParams,
    ) -> Result<SegmentStrainHandle> {
        params.validate(label)?;
        let global = globalize(&set, label, "segment", segments)?;
        let mut lengths = Vec::with_capacity(global.len());
        for (index, s) in global.iter().enumerate() {
            let l = (nodes.rest[s[1] as usize] - nodes.rest[s[0] as usize]).norm();
            if !(l > 0.0) {
                return Err(StarkError::BadElement {
                    object: label.to_string(),
                    kind: "segment",
                    index,
                    detail: "rest length is zero".into(),
                });
            }
            lengths.push(l);
        }
        let g = self.groups.push(label, params);
        self.group.extend(std::iter::repeat_n(g, global.len()));
        self.segments.extend(global);
        self.rest_length.extend(lengths);
        self.version += 1;
        Ok(SegmentStrainHandle(g))
    }

    /// Parameters of a group.
    pub fn params(&self, h: SegmentStrainHandle) -> Result<&SegmentStrainParams> {
        self.groups.get("segment strain", h.0)
    }

    /// Change the parameters of a group.
    pub fn set_params(&mut self, h: SegmentStrainHandle, params: SegmentStrainParams) -> Result<()> {
        self.groups
            .set("segment strain", h.0, params, |p, label| p.validate(label))
    }

    fn kernel_params(&self, e: usize, stencil: &Stencil<2>) -> [f64; PARAMS] {
        let params = &self.groups.params[self.group[e] as usize];
        let l = self.rest_length[e] * params.scale;
        let volume = std::f64::consts::PI * params.section_radius_m.powi(2) * l;
        let strain0 = ((stencil.x0[1] - stencil.x0[0]).norm() - l) / l;
        [
            l,
            volume * params.youngs_modulus,
            volume * params.damping / stencil.dt,
            strain0,
            params.strain_limit,
            volume * params.strain_limit_stiffness,
        ]
    }
}

impl Potential<2> for SegmentStrain {
    fn name(&self) -> &str {
        "segment strain"
    }
    fn save_state(&self) -> Vec<u8> {
        // Parameters may change between steps (`set_params`, time events, hardening).
        crate::energy::encode_state(&self.groups.params)
    }
    fn restore_state(&mut self, bytes: &[u8]) -> Result<(), String> {
        crate::energy::restore_vec(&mut self.groups.params, crate::energy::decode_state(bytes)?, "groups")
    }
    fn num_elements(&self) -> usize {
        self.segments.len()
    }
    fn nodes(&self, e: usize) -> [Node; 2] {
        self.segments[e].map(Node::Point)
    }
    fn energy<S: Scalar>(&self, e: usize, x: &[Vec3<S>; 2], stencil: &Stencil<2>) -> S {
        segment_energy(x, &self.kernel_params(e, stencil).map(S::constant))
    }
    fn derivatives(&self, e: usize, stencil: &Stencil<2>, _project: bool, out: &mut HyperDual<2>) -> FastDerivatives {
        run_kernel(
            generated::segment_strain,
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
    use nalgebra::Vector3;

    #[test]
    fn derivatives_match_finite_differences() {
        for stretch in [1.02, 1.3] {
            let rest = vec![Vector3::new(0.0, 0.0, 0.0), Vector3::new(0.1, 0.02, -0.01)];
            let x0: Vec<_> = rest.iter().map(|p| p * stretch).collect();
            let st = TestState::new(
                rest.clone(),
                x0,
                vec![Vector3::zeros(); 2],
                vec![Vector3::new(0.1, 0.2, 0.3), Vector3::new(-0.2, 0.0, 0.4)],
                0.01,
            );
            let set = NodeSetHandle {
                index: 0,
                first: 0,
                len: 2,
            };
            let mut s = SegmentStrain::default();
            let p = SegmentStrainParams {
                youngs_modulus: 1e4,
                damping: 1e-2,
                strain_limit: 0.1,
                strain_limit_stiffness: 1e5,
                ..Default::default()
            };
            s.add(&st.nodes, set, "band", &[[0, 1]], p).unwrap();
            assert_derivatives(&s, &st.eval(), 1e-7);
        }
    }
}
