//! Frictional contact that never penetrates (DESIGN §4): contact objects, the IPC barrier over
//! point–triangle and edge–edge pairs, continuous collision detection in the line search, lagged
//! friction, and the exact intersection check.
//!
//! Contact is one solver term whose elements are the active barrier pairs followed by the lagged
//! friction elements. Its energies see only world positions, so the same code will serve rigid
//! bodies through the kinematic map.

pub mod barrier;
mod broad_phase;
mod ccd;
mod checkpoint;
mod forces;
pub mod friction;
mod friction_lag;
mod narrow_phase;
mod objects;
pub mod pairs;
mod placement;
pub mod stiffness;
mod term;
#[cfg(test)]
mod tests;
mod validity;
pub use barrier::BarrierKind;

use crate::error::{check_param, Result};
use crate::state::NodeSetHandle;
use broad_phase::Candidates;
use friction::FrictionElement;
use pairs::ContactPair;
pub use pairs::PairHessian;
use serde::{Deserialize, Serialize};
use stiffness::PairStiffness;
use validity::RigidSplit;

crate::params::documented_struct! {
    /// Contact settings (part of the simulation settings).
    #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct ContactSettings {
        /// Contact thickness of objects that set none, m; objects with neither take no part in
        /// contact (default: none).
        pub default_thickness_m: Option<f64>,
        /// Barrier function: `log` (IPC, infinite at contact) or `cubic` (the original Stark's)
        /// (default: `log`).
        pub barrier: BarrierKind,
        /// Barrier stiffness `κ` of every pair, N/m; `None` chooses one per pair of objects from the
        /// masses they carry, the time step, gravity and `d̂` (see `contact::stiffness`; default:
        /// automatic).
        pub stiffness: Option<f64>,
        /// A pair of objects' `κ` doubles after a step in which one of their pairs came closer than
        /// this fraction of its `d̂`, up to `max_stiffness_factor` times its initial value
        /// (default: 1e-3).
        pub min_distance_fraction: f64,
        /// Upper bound of the adaptive `κ` relative to its initial value (default: 1e8).
        pub max_stiffness_factor: f64,
        /// Relative speed below which friction sticks (the smoothing `ε_v`), m/s (default: 1e-4: a
        /// body held below its friction limit creeps slower than this, and a grasp slips within a
        /// few percent of μN; 1e-3 costs fewer Newton iterations on cloth, see BENCHMARKS.md, but
        /// lets force-limited jaws slip early, at 0.85 μN).
        pub friction_stick_slide_threshold_m_s: f64,
        /// Friction solves per step: 1 lags normal forces and tangents once from the start of the
        /// step; more re-lag them from the converged state and solve again (default: 1).
        pub friction_iterations: usize,
        /// Positive semi-definite Hessian used for barrier pairs far from the solution and whenever
        /// the solver projects: `exact`, `projected`, `gauss_newton` or `adaptive` (default:
        /// `adaptive`; `adaptive` and `gauss_newton` turn `projected` for the rest of a time step
        /// once Newton's steps keep being cut short or keep raising the residual there); near the
        /// solution (once Newton took a full step, see `NewtonSettings::definite_far_from_solution`)
        /// the pairs take their exact Hessian.
        pub hessian: PairHessian,
        /// Continuous collision detection in the line search (default: true). Without it only the
        /// barrier keeps pairs apart, which fast motion can tunnel through.
        pub ccd: bool,
    }
}

impl Default for ContactSettings {
    fn default() -> Self {
        ContactSettings {
            default_thickness_m: None,
            barrier: BarrierKind::Log,
            stiffness: None,
            min_distance_fraction: 1e-3,
            max_stiffness_factor: 1e8,
            friction_stick_slide_threshold_m_s: 1e-4,
            friction_iterations: 1,
            hessian: PairHessian::Adaptive,
            ccd: true,
        }
    }
}

impl ContactSettings {
    /// Check every field.
    pub fn validate(&self) -> Result<()> {
        let o = "settings.contact";
        if let Some(t) = self.default_thickness_m {
            check_param(
                o,
                "default_thickness_m",
                t,
                t > 0.0 && t.is_finite(),
                "must be positive (m)",
            )?;
        }
        if let Some(k) = self.stiffness {
            check_param(o, "stiffness", k, k > 0.0 && k.is_finite(), "must be positive (N/m)")?;
        }
        let v = self.friction_stick_slide_threshold_m_s;
        check_param(
            o,
            "friction_stick_slide_threshold_m_s",
            v,
            v > 0.0 && v.is_finite(),
            "must be positive (m/s)",
        )?;
        check_param(
            o,
            "friction_iterations",
            self.friction_iterations as f64,
            self.friction_iterations >= 1,
            "must be at least 1",
        )?;
        check_param(
            o,
            "max_stiffness_factor",
            self.max_stiffness_factor,
            self.max_stiffness_factor >= 1.0,
            "must be at least 1",
        )
    }
}

/// Handle to a contact object.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct ContactHandle(pub u32);

/// A contact object: the surface primitives of one deformable object.
#[derive(Clone, Debug)]
pub struct ContactObject {
    /// Label of the object.
    pub label: String,
    /// Contact thickness, m; a pair activates within `d̂ = thickness_a + thickness_b`.
    pub thickness_m: f64,
    /// Its nodes.
    pub nodes: NodeSetHandle,
}

/// Contact statistics of the last evaluation and step.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize)]
pub struct ContactStats {
    /// Active barrier pairs.
    pub active_pairs: usize,
    /// Friction elements (lagged pairs with μ > 0).
    pub friction_pairs: usize,
    /// Smallest distance among active pairs, m (∞ without contact).
    pub min_distance_m: f64,
    /// Barrier stiffness κ, N/m.
    pub stiffness: f64,
    /// Smallest CCD step fraction of the last line search.
    pub min_ccd_fraction: f64,
    /// Candidate pairs that needed the exact CCD in the last line search.
    pub ccd_queries: usize,
    /// Trial states tested for edge–triangle intersections in the last step (only when a contact
    /// object is a rigid body's mesh: see [`Contact::rigid_pairs_intersect`]).
    pub validity_checks: usize,
    /// Trial states of the last step rejected because an edge crossed a triangle.
    pub invalid_trials: usize,
    /// Wall time of those tests in the last step, s.
    pub validity_time_s: f64,
}

/// All contact objects and their interactions, as one solver term.
pub struct Contact {
    /// Settings.
    pub settings: ContactSettings,
    objects: Vec<ContactObject>,
    points: Vec<u32>,
    point_obj: Vec<u16>,
    edges: Vec<[u32; 2]>,
    edge_obj: Vec<u16>,
    edge_rest_len_sq: Vec<f64>,
    triangles: Vec<[u32; 3]>,
    tri_obj: Vec<u16>,
    /// `enabled[a * n + b]`: objects a and b collide.
    enabled: Vec<bool>,
    /// `friction[a * n + b]`: friction coefficient.
    friction: Vec<f64>,
    pairs: Vec<ContactPair>,
    friction_elements: Vec<FrictionElement>,
    /// Per pair, the friction element on the same nodes evaluated with it as one element
    /// ([`NO_FRICTION`] if none): one scatter into the matrix instead of two.
    pair_friction: Vec<u32>,
    /// The friction elements no pair carries, evaluated as elements of their own.
    lone_friction: Vec<u32>,
    /// The first friction element on each stencil (set with the friction elements).
    friction_by_nodes: std::collections::HashMap<[u32; 4], u32>,
    /// The friction elements' stencils, packed (set with them): the matching to the pairs reads
    /// them in order, ~1 MB instead of the elements' ~9 MB on a folded towel.
    friction_nodes: Vec<[u32; 4]>,
    /// The friction duals before a tentative acceptance (`EnergyTerm::save_iterate`).
    saved_duals: Vec<[f64; 2]>,
    /// `κ` per pair of objects.
    kappa: PairStiffness,
    /// Mean contact mass of each object (kg; 0: kinematic), set with the stiffness.
    object_masses_kg: Vec<f64>,
    /// Smallest CCD fraction and exact CCD queries of the last line search.
    ccd_record: (f64, usize),
    /// Candidates of the last line-search segment or detection (reused while they cover it).
    candidate_cache: Option<Candidates>,
    /// Pruning opportunities of candidates left to skip (`broad_phase`).
    prune_skips: std::sync::atomic::AtomicU32,
    /// `candidate_config()` when the cached candidates were found.
    candidate_config: u64,
    /// Primitives of rigid bodies' meshes and of the other objects (set in `before_step`), for
    /// the intersection test of trial states.
    rigid_split: RigidSplit,
    /// Intersection tests, rejections and their wall time in the current step.
    validity_record: (usize, usize, f64),
    version: u64,
    relag_pending: bool,
    lag_solves: usize,
    /// Newton asked for the barrier pairs' positive semi-definite Hessian, `settings.hessian`
    /// (`use_definite_hessian`); otherwise they take their exact one.
    definite_barriers: bool,
    /// The definite form is the projected one for the rest of the time step (see
    /// `EnergyTerm::tighten_definite_form`).
    definite_projected: bool,
    /// Statistics.
    pub stats: ContactStats,
}

impl Default for Contact {
    fn default() -> Self {
        Contact {
            settings: ContactSettings::default(),
            objects: vec![],
            points: vec![],
            point_obj: vec![],
            edges: vec![],
            edge_obj: vec![],
            edge_rest_len_sq: vec![],
            triangles: vec![],
            tri_obj: vec![],
            enabled: vec![],
            friction: vec![],
            pairs: vec![],
            friction_elements: vec![],
            pair_friction: vec![],
            lone_friction: vec![],
            friction_by_nodes: Default::default(),
            friction_nodes: vec![],
            saved_duals: vec![],
            kappa: PairStiffness::default(),
            object_masses_kg: vec![],
            ccd_record: (1.0, 0),
            candidate_cache: None,
            prune_skips: Default::default(),
            candidate_config: 0,
            rigid_split: RigidSplit::default(),
            validity_record: (0, 0, 0.0),
            version: 0,
            relag_pending: false,
            lag_solves: 0,
            definite_barriers: true,
            definite_projected: false,
            stats: ContactStats {
                min_distance_m: f64::INFINITY,
                min_ccd_fraction: 1.0,
                ..Default::default()
            },
        }
    }
}
