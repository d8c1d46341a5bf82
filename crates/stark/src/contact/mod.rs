//! Frictional contact that never penetrates (DESIGN §4): contact objects, the IPC barrier over
//! point–triangle and edge–edge pairs, continuous collision detection in the line search, lagged
//! friction, and the exact intersection check.
//!
//! Contact is one solver term whose elements are the active barrier pairs followed by the lagged
//! friction elements. Its energies see only world positions, so the same code will serve rigid
//! bodies through the kinematic map.

pub mod barrier;
mod checkpoint;
pub mod friction;
pub mod pairs;
pub mod stiffness;
pub use barrier::BarrierKind;

use crate::deformables::NodeSetHandle;
use crate::energy::kinematics::{element_blocks, map_element, MapProjection, NodeMap};
use crate::energy::term::{element_stride, NO_DOF};
use crate::energy::Node;
use crate::energy::{EnergyTerm, EvalMode, HyperDual, Scalar, StepCheck, Vec3};
use crate::error::{check_param, Result, StarkError};
use crate::geometry::aabb::{edge_aabb, edge_swept_aabb, point_swept_aabb, triangle_aabb, triangle_swept_aabb, Aabb};
use crate::geometry::bvh::Bvh;
use crate::geometry::ccd::{edge_edge_max_step, point_triangle_max_step, CcdParams};
use crate::geometry::distance::{
    edge_edge_closest_parameters_typed, edge_edge_cross_norm_sq, edge_edge_distance_sq_typed, edge_edge_distance_type,
    point_edge_closest_parameter_typed, point_triangle_closest_barycentric_typed, point_triangle_distance_sq_typed,
    point_triangle_distance_type, EdgeEdgeDistanceType as Ee, PointEdgeDistanceType, PointTriangleDistanceType as Pt,
};
use crate::geometry::intersection::{edge_triangle_intersect, find_edge_triangle_intersections};
use crate::state::{EvalState, NO_BODY};
use barrier::barrier;
use friction::FrictionElement;
use nalgebra::Vector3;
pub use pairs::PairHessian;
use pairs::{pair_derivatives, pair_energy, ContactPair, PairKind};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use stiffness::{object_contact_masses, PairStiffness};

/// Contact settings (part of the simulation settings).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ContactSettings {
    /// Contact thickness of objects that set none, m; objects with neither take no part in
    /// contact (default: none).
    pub default_thickness_m: Option<f64>,
    /// Barrier function (default: log, infinite at contact).
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
    /// the solver projects (default: adaptive); near the solution (once Newton took a full step,
    /// see `NewtonSettings::majorizer_far_from_solution`) the pairs take their exact Hessian.
    pub hessian: PairHessian,
    /// Continuous collision detection in the line search (default: true). Without it only the
    /// barrier keeps pairs apart, which fast motion can tunnel through.
    pub ccd: bool,
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
    /// `κ` per pair of objects.
    kappa: PairStiffness,
    /// Mean contact mass of each object (kg; 0: kinematic), set with the stiffness.
    object_masses_kg: Vec<f64>,
    /// Smallest CCD fraction and exact CCD queries of the last line search (`max_step_fraction`
    /// takes `&self`).
    ccd_record: std::sync::Mutex<(f64, usize)>,
    /// Candidates of the last line-search segment (set by `max_step_fraction`, which takes
    /// `&self`).
    candidate_cache: std::sync::Mutex<Option<Candidates>>,
    /// Primitives of rigid bodies' meshes and of the other objects (set in `before_step`), for
    /// the intersection test of trial states.
    rigid_split: RigidSplit,
    /// Intersection tests, rejections and their wall time in the current step
    /// (`is_valid_state` takes `&self`).
    validity_record: std::sync::Mutex<(usize, usize, f64)>,
    version: u64,
    relag_pending: bool,
    lag_solves: usize,
    /// Newton asked for the friction Hessian's majorising stand-in (`use_majorizer_hessian`).
    friction_majorizer: bool,
    /// Newton asked for the barrier pairs' positive semi-definite Hessian, `settings.hessian`
    /// (`use_definite_hessian`); otherwise they take their exact one.
    definite_barriers: bool,
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
            kappa: PairStiffness::default(),
            object_masses_kg: vec![],
            ccd_record: std::sync::Mutex::new((1.0, 0)),
            candidate_cache: std::sync::Mutex::new(None),
            rigid_split: RigidSplit::default(),
            validity_record: std::sync::Mutex::new((0, 0, 0.0)),
            version: 0,
            relag_pending: false,
            lag_solves: 0,
            friction_majorizer: false,
            definite_barriers: true,
            stats: ContactStats {
                min_distance_m: f64::INFINITY,
                min_ccd_fraction: 1.0,
                ..Default::default()
            },
        }
    }
}

/// The contact primitives split by whether they belong to a rigid body's collision mesh.
#[derive(Default)]
struct RigidSplit {
    /// Triangles of rigid objects.
    rigid_triangles: Vec<u32>,
    /// Edges of rigid objects.
    rigid_edges: Vec<u32>,
    /// Triangles of the other objects.
    other_triangles: Vec<u32>,
}

impl RigidSplit {
    fn is_empty(&self) -> bool {
        self.rigid_triangles.is_empty() && self.rigid_edges.is_empty()
    }
}

fn sorted_objects([a, b]: [u16; 2]) -> [u16; 2] {
    if a < b {
        [a, b]
    } else {
        [b, a]
    }
}

fn sorted2(a: u32, b: u32) -> [u32; 2] {
    if a < b {
        [a, b]
    } else {
        [b, a]
    }
}

impl Contact {
    /// Contact objects.
    pub fn objects(&self) -> &[ContactObject] {
        &self.objects
    }

    /// Active barrier pairs at the last evaluation.
    pub fn pairs(&self) -> &[ContactPair] {
        &self.pairs
    }

    /// The largest barrier stiffness κ of any pair of objects, N/m (0 before the first step).
    pub fn stiffness(&self) -> f64 {
        self.kappa.max()
    }

    /// Barrier stiffness κ between two objects, N/m (0 before the first step that needs it).
    pub fn pair_stiffness(&self, a: ContactHandle, b: ContactHandle) -> Result<f64> {
        let (i, j) = (self.check(a)?, self.check(b)?);
        Ok(self.kappa.get(i, j))
    }

    /// Register the surface of an object (indices local to `nodes`): its triangles, its edges
    /// and the nodes that act as contact points. Self-contact is on.
    pub fn add_object(
        &mut self,
        label: &str,
        nodes: NodeSetHandle,
        rest: &[Vector3<f64>],
        triangles: &[[usize; 3]],
        edges: &[[usize; 2]],
        points: &[usize],
        thickness_m: f64,
    ) -> Result<ContactHandle> {
        check_param(
            label,
            "contact thickness_m",
            thickness_m,
            thickness_m > 0.0 && thickness_m.is_finite(),
            "must be positive (m)",
        )?;
        if self.objects.len() >= u16::MAX as usize {
            return Err(StarkError::InvalidInput("too many contact objects".into()));
        }
        let n = nodes.len as usize;
        let bad = triangles
            .iter()
            .flatten()
            .chain(edges.iter().flatten())
            .chain(points)
            .find(|&&i| i >= n);
        if let Some(&i) = bad {
            return Err(StarkError::InvalidInput(format!(
                "contact surface of '{label}' refers to node {i}, but the object has {n} nodes"
            )));
        }
        let id = self.objects.len() as u16;
        let g = |i: usize| nodes.global(i) as u32;
        self.points.extend(points.iter().map(|&p| g(p)));
        self.point_obj.extend(std::iter::repeat_n(id, points.len()));
        self.edges.extend(edges.iter().map(|e| [g(e[0]), g(e[1])]));
        self.edge_obj.extend(std::iter::repeat_n(id, edges.len()));
        self.edge_rest_len_sq.extend(
            edges
                .iter()
                .map(|e| (rest[nodes.global(e[1])] - rest[nodes.global(e[0])]).norm_squared()),
        );
        self.triangles
            .extend(triangles.iter().map(|t| [g(t[0]), g(t[1]), g(t[2])]));
        self.tri_obj.extend(std::iter::repeat_n(id, triangles.len()));
        self.objects.push(ContactObject {
            label: label.to_string(),
            thickness_m,
            nodes,
        });
        // Grow the pair tables: everything collides, frictionless, until told otherwise.
        let m = self.objects.len();
        let mut enabled = vec![true; m * m];
        let mut friction = vec![0.0; m * m];
        for a in 0..m - 1 {
            for b in 0..m - 1 {
                enabled[a * m + b] = self.enabled[a * (m - 1) + b];
                friction[a * m + b] = self.friction[a * (m - 1) + b];
            }
        }
        self.enabled = enabled;
        self.friction = friction;
        self.kappa.resize(m);
        self.version += 1;
        Ok(ContactHandle(id as u32))
    }

    fn check(&self, h: ContactHandle) -> Result<usize> {
        let i = h.0 as usize;
        if i < self.objects.len() {
            Ok(i)
        } else {
            Err(StarkError::InvalidHandle {
                kind: "contact object",
                index: i,
                len: self.objects.len(),
            })
        }
    }

    /// The contact object with this label.
    pub fn object_by_label(&self, label: &str) -> Option<ContactHandle> {
        self.objects
            .iter()
            .position(|o| o.label == label)
            .map(|i| ContactHandle(i as u32))
    }

    /// Friction coefficient μ between two objects (`a == b`: self-friction). Takes effect at the
    /// next step.
    pub fn set_friction(&mut self, a: ContactHandle, b: ContactHandle, mu: f64) -> Result<()> {
        let (i, j) = (self.check(a)?, self.check(b)?);
        check_param(
            &self.objects[i].label,
            "friction",
            mu,
            mu >= 0.0 && mu.is_finite(),
            "must be non-negative",
        )?;
        let m = self.objects.len();
        self.friction[i * m + j] = mu;
        self.friction[j * m + i] = mu;
        Ok(())
    }

    /// Friction coefficient between two objects.
    pub fn friction(&self, a: ContactHandle, b: ContactHandle) -> Result<f64> {
        let (i, j) = (self.check(a)?, self.check(b)?);
        Ok(self.friction[i * self.objects.len() + j])
    }

    /// Switch collisions between two objects (`a == b`: self-collision) off or on.
    pub fn set_collision(&mut self, a: ContactHandle, b: ContactHandle, enabled: bool) -> Result<()> {
        let (i, j) = (self.check(a)?, self.check(b)?);
        let m = self.objects.len();
        self.enabled[i * m + j] = enabled;
        self.enabled[j * m + i] = enabled;
        self.version += 1;
        Ok(())
    }

    /// Whether two objects (`a == b`: an object with itself) collide.
    pub fn collision_enabled(&self, a: ContactHandle, b: ContactHandle) -> Result<bool> {
        let (i, j) = (self.check(a)?, self.check(b)?);
        Ok(self.enabled[i * self.objects.len() + j])
    }

    /// Switch collisions between two objects off (the original's `disable_collision`).
    pub fn disable_collision(&mut self, a: ContactHandle, b: ContactHandle) -> Result<()> {
        self.set_collision(a, b, false)
    }

    /// Change an object's contact thickness, m.
    pub fn set_thickness(&mut self, a: ContactHandle, thickness_m: f64) -> Result<()> {
        let i = self.check(a)?;
        check_param(
            &self.objects[i].label,
            "contact thickness_m",
            thickness_m,
            thickness_m > 0.0 && thickness_m.is_finite(),
            "must be positive (m)",
        )?;
        self.objects[i].thickness_m = thickness_m;
        Ok(())
    }

    fn pair_ok(&self, a: u16, b: u16) -> bool {
        self.enabled[a as usize * self.objects.len() + b as usize]
    }

    fn dhat(&self, a: u16, b: u16) -> f64 {
        self.objects[a as usize].thickness_m + self.objects[b as usize].thickness_m
    }

    fn mu(&self, a: u16, b: u16) -> f64 {
        self.friction[a as usize * self.objects.len() + b as usize]
    }

    /// Pairs of edges and triangles that intersect at positions `x` (ignoring pairs of objects
    /// whose collisions are off), as `(edge, triangle)` indices into the contact surfaces, with a
    /// readable description of each. The exact test of `geometry::intersection` (robust
    /// predicates); used on the initial state and by tests after every step.
    pub fn find_intersections(&self, x: &[Vector3<f64>]) -> Vec<String> {
        let edges: Vec<[usize; 2]> = self.edges.iter().map(|e| [e[0] as usize, e[1] as usize]).collect();
        let tris: Vec<[usize; 3]> = self
            .triangles
            .iter()
            .map(|t| [t[0] as usize, t[1] as usize, t[2] as usize])
            .collect();
        let found =
            find_edge_triangle_intersections(x, &edges, &tris, |e, t| self.pair_ok(self.edge_obj[e], self.tri_obj[t]))
                .expect("contact primitives refer to existing nodes");
        found
            .into_iter()
            .map(|(e, t)| {
                format!(
                    "edge {:?} of '{}' crosses triangle {:?} of '{}'",
                    self.edges[e],
                    self.objects[self.edge_obj[e] as usize].label,
                    self.triangles[t],
                    self.objects[self.tri_obj[t] as usize].label
                )
            })
            .collect()
    }

    /// The barrier (normal contact) force on every node at positions `x`, N: minus the gradient
    /// of the barrier energy of the pairs active at `x` (current stiffness κ). Summed over the
    /// mesh nodes of a rigid body it is the contact force on the body (its moment about the
    /// centre of mass the contact torque); summed over an object, the load it carries. Friction
    /// is not included.
    pub fn barrier_forces(&mut self, x: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        let mut forces = vec![Vector3::zeros(); x.len()];
        let pairs = self.detect(x);
        self.add_barrier_forces(&pairs, x, &mut forces);
        forces
    }

    /// Add minus the barrier gradient of `pairs` at `x` to `forces`.
    fn add_barrier_forces(&self, pairs: &[ContactPair], x: &[Vector3<f64>], forces: &mut [Vector3<f64>]) {
        let mut d = HyperDual::<4>::constant(0.0);
        for p in pairs {
            pair_derivatives(
                p,
                &Self::stencil_x(&p.nodes, x),
                p.kappa * p.multiplicity,
                self.settings.barrier,
                PairHessian::GaussNewton,
                &mut d,
            );
            for (k, &i) in p.nodes.iter().enumerate() {
                if i != NO_DOF {
                    forces[i as usize] -= Vector3::from(d.grad[k]);
                }
            }
        }
    }

    /// The contact forces of the last solve on every node at positions `x` (the converged
    /// state, right after a step), N: the normal (barrier) forces of the pairs active at the last
    /// evaluation, and the friction forces of the step's lagged friction elements. These are the
    /// forces the step balanced: summed over a rigid body's mesh nodes, the contact force on the
    /// body. Unlike [`Contact::barrier_forces`] nothing is detected anew.
    pub fn solve_forces(&self, x: &[Vector3<f64>]) -> (Vec<Vector3<f64>>, Vec<Vector3<f64>>) {
        let mut normal = vec![Vector3::zeros(); x.len()];
        let mut friction = vec![Vector3::zeros(); x.len()];
        self.add_barrier_forces(&self.pairs, x, &mut normal);
        let mut d = HyperDual::<4>::constant(0.0);
        for f in &self.friction_elements {
            f.derivatives(&Self::stencil_x(&f.nodes, x), false, &mut d);
            for (k, &i) in f.nodes[..f.len].iter().enumerate() {
                if i != NO_DOF {
                    friction[i as usize] -= Vector3::from(d.grad[k]);
                }
            }
        }
        (normal, friction)
    }

    /// How far a new surface (vertices `p` and `triangles` indexing them, m) can move straight
    /// down (−z) before it touches the contact surfaces at positions `x`: the smallest vertical
    /// distance from one of its vertices down to a contact triangle, or from a contact point up
    /// to one of its triangles. `None`: nothing below it. Used to place spawned objects at rest
    /// just above what they will land on.
    pub fn clearance_below(&self, x: &[Vector3<f64>], p: &[Vector3<f64>], triangles: &[[usize; 3]]) -> Option<f64> {
        // The height of triangle `t` above the vertical line through `q`, if the line meets it.
        fn height_at(t: [&Vector3<f64>; 3], q: &Vector3<f64>) -> Option<f64> {
            let (a, b, c) = (t[0], t[1], t[2]);
            let det = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
            if det.abs() < 1e-30 {
                return None;
            }
            let u = ((q.x - a.x) * (c.y - a.y) - (c.x - a.x) * (q.y - a.y)) / det;
            let v = ((b.x - a.x) * (q.y - a.y) - (q.x - a.x) * (b.y - a.y)) / det;
            (u >= 0.0 && v >= 0.0 && u + v <= 1.0).then(|| a.z + u * (b.z - a.z) + v * (c.z - a.z))
        }
        let mut best = f64::INFINITY;
        for t in &self.triangles {
            let tri = [&x[t[0] as usize], &x[t[1] as usize], &x[t[2] as usize]];
            for q in p {
                if let Some(z) = height_at(tri, q) {
                    if z <= q.z {
                        best = best.min(q.z - z);
                    }
                }
            }
        }
        for t in triangles {
            let tri = [&p[t[0]], &p[t[1]], &p[t[2]]];
            for &i in &self.points {
                let s = &x[i as usize];
                if let Some(z) = height_at(tri, s) {
                    if z >= s.z {
                        best = best.min(z - s.z);
                    }
                }
            }
        }
        best.is_finite().then_some(best)
    }

    /// Some pair of objects has no barrier stiffness yet (see [`Contact::initialize_stiffness`]).
    pub fn needs_stiffness(&self) -> bool {
        self.kappa.needs_initialization()
    }

    /// Choose the barrier stiffness of the pairs of objects that have none (`contact::stiffness`)
    /// from the nodes' effective contact masses (kg; 0 for kinematic nodes), the time step (s) and
    /// the magnitude of gravity (m/s²).
    pub fn initialize_stiffness(&mut self, node_masses_kg: &[f64], dt: f64, gravity_m_s2: f64) {
        let masses = object_contact_masses(self.objects.len(), &self.points, &self.point_obj, node_masses_kg);
        let thickness: Vec<f64> = self.objects.iter().map(|o| o.thickness_m).collect();
        self.object_masses_kg = masses.clone();
        self.kappa.initialize(
            self.settings.stiffness,
            &masses,
            |a, b| thickness[a] + thickness[b],
            dt,
            gravity_m_s2,
            self.settings.barrier,
        );
        self.stats.stiffness = self.kappa.max();
    }

    /// Candidate pairs for every state in which each contact point stays within `margin_m`
    /// (per axis) of the box it sweeps from `from` to `to`: primitives' swept boxes, grown by
    /// their object's thickness plus the margin, that overlap. A pair that comes within its
    /// `d̂ = thickness_a + thickness_b` in such a state has overlapping grown boxes, so the list
    /// serves the line searches (and CCD) of several Newton iterations without a new broad phase.
    fn candidates(&self, from: &[Vector3<f64>], to: &[Vector3<f64>], margin_m: f64) -> Candidates {
        let grow = |o: u16| self.objects[o as usize].thickness_m + margin_m;
        let mut c = Candidates {
            swept: self
                .points
                .par_iter()
                .map(|&p| point_swept_aabb(&from[p as usize], &to[p as usize], 0.0))
                .collect(),
            margin_m,
            ..Default::default()
        };
        if self.objects.is_empty() {
            return c;
        }
        let x = |i: u32| (&from[i as usize], &to[i as usize]);
        if !self.triangles.is_empty() && !self.points.is_empty() {
            let point_boxes: Vec<Aabb> = c
                .swept
                .par_iter()
                .zip(&self.point_obj)
                .map(|(b, &o)| b.inflated(grow(o)))
                .collect();
            let tri_boxes: Vec<Aabb> = self
                .triangles
                .par_iter()
                .zip(&self.tri_obj)
                .map(|(t, &o)| {
                    let (a, b, c) = (x(t[0]), x(t[1]), x(t[2]));
                    triangle_swept_aabb(a.0, b.0, c.0, a.1, b.1, c.1, grow(o))
                })
                .collect();
            let found = Bvh::build(&point_boxes).pairs_with(&Bvh::build(&tri_boxes), 0.0);
            c.point_triangle = found
                .into_par_iter()
                .filter(|&(pi, ti)| {
                    self.pair_ok(self.point_obj[pi], self.tri_obj[ti]) && !self.triangles[ti].contains(&self.points[pi])
                })
                .map(|(pi, ti)| (pi as u32, ti as u32))
                .collect();
        }
        if self.edges.len() > 1 {
            let edge_boxes: Vec<Aabb> = self
                .edges
                .par_iter()
                .zip(&self.edge_obj)
                .map(|(e, &o)| {
                    let (a, b) = (x(e[0]), x(e[1]));
                    edge_swept_aabb(a.0, b.0, a.1, b.1, grow(o))
                })
                .collect();
            let found = Bvh::build(&edge_boxes).self_pairs(0.0);
            c.edge_edge = found
                .into_par_iter()
                .filter(|&(i, j)| {
                    let (ea, eb) = (self.edges[i], self.edges[j]);
                    self.pair_ok(self.edge_obj[i], self.edge_obj[j]) && !ea.iter().any(|v| eb.contains(v))
                })
                .map(|(i, j)| (i as u32, j as u32))
                .collect();
        }
        c
    }

    /// Candidates covering the segment `from → to`: the cached ones if every contact point stays
    /// within their margin on it, else a new broad phase over the segment with a margin of the
    /// largest thickness (so the next, shorter Newton steps usually reuse it).
    fn candidates_for(&self, cache: Option<Candidates>, from: &[Vector3<f64>], to: &[Vector3<f64>]) -> Candidates {
        if let Some(c) = cache {
            if c.cover(&self.points, from) && c.cover(&self.points, to) {
                return c;
            }
        }
        let thickest = self.objects.iter().map(|o| o.thickness_m).fold(0.0, f64::max);
        self.candidates(from, to, thickest)
    }

    /// Active pairs at `x` among candidates: classification by closest-point region; candidates
    /// that reduce to the same pair are merged (their multiplicities summed).
    fn narrow_phase(&self, c: &Candidates, x: &[Vector3<f64>]) -> Vec<ContactPair> {
        let mut found: Vec<ContactPair> = c
            .point_triangle
            .par_iter()
            .filter_map(|&(pi, ti)| self.point_triangle_pair(pi as usize, ti as usize, x))
            .collect();
        found.par_extend(
            c.edge_edge
                .par_iter()
                .filter_map(|&(a, b)| self.edge_edge_pair(a as usize, b as usize, x)),
        );
        // Point–triangle and edge–edge pairs are one per candidate; a pair reduced to a point–point
        // or point–edge distance can come from several candidates (a vertex near a fan of
        // triangles): those are merged into one pair whose multiplicity counts them. Only they
        // need the sort (the candidates' order is deterministic, and so is this one).
        let (mut merged, unique): (Vec<ContactPair>, Vec<ContactPair>) = found
            .into_iter()
            .partition(|p| matches!(p.kind, PairKind::PointPoint | PairKind::PointEdge));
        merged.sort_unstable_by_key(|p| (p.kind, p.nodes));
        merged.dedup_by(|later, kept| {
            let same = later.kind == kept.kind && later.nodes == kept.nodes;
            if same {
                kept.multiplicity += later.multiplicity;
            }
            same
        });
        merged.extend(unique);
        merged
    }

    /// Active pairs at positions `x`, from the cached candidates when they cover `x` (else a new
    /// broad phase, then cached).
    fn detect(&mut self, x: &[Vector3<f64>]) -> Vec<ContactPair> {
        let cached = self.candidate_cache.get_mut().expect("no poisoned lock").take();
        let candidates = self.candidates_for(cached, x, x);
        let pairs = self.narrow_phase(&candidates, x);
        *self.candidate_cache.get_mut().expect("no poisoned lock") = Some(candidates);
        pairs
    }

    /// The pair of a point–triangle candidate at `x`, if within `d̂` (candidates are already
    /// enabled and not adjacent).
    fn point_triangle_pair(&self, pi: usize, ti: usize, x: &[Vector3<f64>]) -> Option<ContactPair> {
        let (po, to) = (self.point_obj[pi], self.tri_obj[ti]);
        let p = self.points[pi];
        let t = self.triangles[ti];
        let (xp, x0, x1, x2) = (&x[p as usize], &x[t[0] as usize], &x[t[1] as usize], &x[t[2] as usize]);
        let dhat = self.dhat(po, to);
        // Cheap rejection: the point is farther than d̂ from the triangle's box on some axis.
        if (0..3).any(|k| xp[k] + dhat < x0[k].min(x1[k]).min(x2[k]) || xp[k] - dhat > x0[k].max(x1[k]).max(x2[k])) {
            return None;
        }
        let ty = point_triangle_distance_type(xp, x0, x1, x2);
        let d_sq = point_triangle_distance_sq_typed(xp, x0, x1, x2, ty);
        if !(d_sq < dhat * dhat) {
            return None;
        }
        let (kind, full) = match ty {
            Pt::PointT0 | Pt::PointT1 | Pt::PointT2 => {
                let v = t[match ty {
                    Pt::PointT0 => 0,
                    Pt::PointT1 => 1,
                    _ => 2,
                }];
                let s = sorted2(p, v);
                (PairKind::PointPoint, [s[0], s[1], NO_DOF, NO_DOF])
            }
            Pt::PointEdge0 | Pt::PointEdge1 | Pt::PointEdge2 => {
                let i = match ty {
                    Pt::PointEdge0 => 0,
                    Pt::PointEdge1 => 1,
                    _ => 2,
                };
                let e = sorted2(t[i], t[(i + 1) % 3]);
                (PairKind::PointEdge, [p, e[0], e[1], NO_DOF])
            }
            Pt::PointTriangle => (PairKind::PointTriangle, [p, t[0], t[1], t[2]]),
        };
        Some(ContactPair {
            kind,
            nodes: full,
            dhat,
            eps_x: 0.0,
            mu: self.mu(po, to),
            kappa: self.kappa.get(po as usize, to as usize),
            objects: [po, to],
            multiplicity: 1.0,
        })
    }

    /// The pair of an edge–edge candidate at `x`, if within `d̂` (candidates are already enabled
    /// and share no vertex).
    fn edge_edge_pair(&self, a: usize, b: usize, x: &[Vector3<f64>]) -> Option<ContactPair> {
        let (oa, ob) = (self.edge_obj[a], self.edge_obj[b]);
        let (ea, eb) = (self.edges[a], self.edges[b]);
        let p = |i: u32| &x[i as usize];
        let (a0, a1, b0, b1) = (p(ea[0]), p(ea[1]), p(eb[0]), p(eb[1]));
        let dhat = self.dhat(oa, ob);
        if (0..3).any(|k| a0[k].max(a1[k]) + dhat < b0[k].min(b1[k]) || a0[k].min(a1[k]) - dhat > b0[k].max(b1[k])) {
            return None;
        }
        let ty = edge_edge_distance_type(a0, a1, b0, b1);
        let d_sq = edge_edge_distance_sq_typed(a0, a1, b0, b1, ty);
        if !(d_sq < dhat * dhat) {
            return None;
        }
        let mu = self.mu(oa, ob);
        let kappa = self.kappa.get(oa as usize, ob as usize);
        let eps_x = 1e-3 * self.edge_rest_len_sq[a] * self.edge_rest_len_sq[b];
        if edge_edge_cross_norm_sq(a0, a1, b0, b1) < eps_x {
            return Some(ContactPair {
                kind: PairKind::EdgeEdgeMollified(ty),
                nodes: [ea[0], ea[1], eb[0], eb[1]],
                dhat,
                eps_x,
                mu,
                kappa,
                objects: [oa, ob],
                multiplicity: 1.0,
            });
        }
        let mut nodes = [NO_DOF; 4];
        let kind = match ty {
            Ee::Ea0Eb0 | Ee::Ea0Eb1 | Ee::Ea1Eb0 | Ee::Ea1Eb1 => {
                let u = if matches!(ty, Ee::Ea0Eb0 | Ee::Ea0Eb1) {
                    ea[0]
                } else {
                    ea[1]
                };
                let v = if matches!(ty, Ee::Ea0Eb0 | Ee::Ea1Eb0) {
                    eb[0]
                } else {
                    eb[1]
                };
                nodes[..2].copy_from_slice(&sorted2(u, v));
                PairKind::PointPoint
            }
            Ee::EaEb0 | Ee::EaEb1 => {
                nodes[0] = if ty == Ee::EaEb0 { eb[0] } else { eb[1] };
                nodes[1..3].copy_from_slice(&sorted2(ea[0], ea[1]));
                PairKind::PointEdge
            }
            Ee::Ea0Eb | Ee::Ea1Eb => {
                nodes[0] = if ty == Ee::Ea0Eb { ea[0] } else { ea[1] };
                nodes[1..3].copy_from_slice(&sorted2(eb[0], eb[1]));
                PairKind::PointEdge
            }
            Ee::EaEb => {
                let (sa, sb) = (sorted2(ea[0], ea[1]), sorted2(eb[0], eb[1]));
                let (first, second) = if sa < sb { (sa, sb) } else { (sb, sa) };
                nodes = [first[0], first[1], second[0], second[1]];
                PairKind::EdgeEdge
            }
        };
        Some(ContactPair {
            kind,
            nodes,
            dhat,
            eps_x,
            mu,
            kappa,
            objects: [oa, ob],
            multiplicity: 1.0,
        })
    }

    /// Distance of an active pair at `x`, m.
    fn pair_distance(p: &ContactPair, x: &[Vector3<f64>]) -> f64 {
        let (dist, idx) = p.kind.distance();
        let x = Self::stencil_x(&p.nodes, x);
        let n = dist.len();
        let sub: [Vec3<f64>; 4] = std::array::from_fn(|k| Vec3::constant(&x[if k < n { idx[k] } else { 0 }]));
        pairs::distance_sq(dist, &sub[..n]).sqrt()
    }

    fn stencil_x(nodes: &[u32; 4], x: &[Vector3<f64>]) -> [Vector3<f64>; 4] {
        nodes.map(|i| if i == NO_DOF { Vector3::zeros() } else { x[i as usize] })
    }

    /// Lagged friction elements from the pairs active at `x0`. The slip is measured from the
    /// start-of-step positions `x_start` (equal to `x0` at the first lag; a re-lag takes normal
    /// forces, tangents and weights from the converged state but must keep the slip origin).
    fn lag_friction(&mut self, pairs: &[ContactPair], x0: &[Vector3<f64>], x_start: &[Vector3<f64>], dt: f64) {
        let eps = self.settings.friction_stick_slide_threshold_m_s * dt;
        let kind = self.settings.barrier;
        self.friction_elements = pairs
            .iter()
            .filter(|p| p.mu > 0.0)
            .filter_map(|p| {
                let x = Self::stencil_x(&p.nodes, x0);
                let weights = match p.kind {
                    PairKind::PointPoint => [1.0, -1.0, 0.0, 0.0],
                    PairKind::PointEdge => {
                        let a =
                            point_edge_closest_parameter_typed(&x[0], &x[1], &x[2], PointEdgeDistanceType::PointEdge);
                        [1.0, -(1.0 - a), -a, 0.0]
                    }
                    PairKind::PointTriangle => {
                        let (b1, b2) =
                            point_triangle_closest_barycentric_typed(&x[0], &x[1], &x[2], &x[3], Pt::PointTriangle);
                        [1.0, -(1.0 - b1 - b2), -b1, -b2]
                    }
                    PairKind::EdgeEdge | PairKind::EdgeEdgeMollified(_) => {
                        let ty = match p.kind {
                            PairKind::EdgeEdgeMollified(r) => r,
                            _ => Ee::EaEb,
                        };
                        let (a, b) = edge_edge_closest_parameters_typed(&x[0], &x[1], &x[2], &x[3], ty);
                        [1.0 - a, a, -(1.0 - b), -b]
                    }
                };
                let rel: Vector3<f64> = (0..p.kind.len()).map(|i| x[i] * weights[i]).sum();
                let d = rel.norm();
                let (_, db, _) = barrier(kind, d, p.dhat);
                let lambda = p.kappa * p.multiplicity * db.abs();
                (lambda > 0.0 && lambda.is_finite()).then(|| {
                    let start = Self::stencil_x(&p.nodes, x_start);
                    FrictionElement::new(p.nodes, p.kind.len(), weights, rel, &start, p.mu * lambda, eps)
                })
            })
            .collect();
        self.stats.friction_pairs = self.friction_elements.len();
    }

    /// Largest fraction of the motion `from → to` free of collisions (additive CCD with a
    /// minimum separation) over the candidates, and the number of exact CCD queries.
    fn ccd_fraction(&self, c: &Candidates, from: &[Vector3<f64>], to: &[Vector3<f64>]) -> (f64, usize) {
        // A bounded search: a query that cannot be decided within the budget returns the start of
        // its earliest undecided box, still a safe (if short) step.
        let params = CcdParams {
            max_iterations: 10_000,
            ..CcdParams::default()
        };
        // A cheap conservative filter first: the distance of a pair can shrink by at most the sum
        // of the largest displacements of its two sides, so a pair farther apart than that
        // cannot collide within the step.
        let disp = |i: u32| (to[i as usize] - from[i as usize]).norm();
        let (a_pt, q_pt) = c
            .point_triangle
            .par_iter()
            .map(|&(pi, ti)| {
                let p = self.points[pi as usize];
                let t = self.triangles[ti as usize];
                let x0 = [
                    from[p as usize],
                    from[t[0] as usize],
                    from[t[1] as usize],
                    from[t[2] as usize],
                ];
                let d0 = point_triangle_distance_sq_typed(
                    &x0[0],
                    &x0[1],
                    &x0[2],
                    &x0[3],
                    point_triangle_distance_type(&x0[0], &x0[1], &x0[2], &x0[3]),
                )
                .sqrt();
                if d0 > disp(p) + disp(t[0]).max(disp(t[1])).max(disp(t[2])) {
                    return (1.0, 0);
                }
                let x1 = [to[p as usize], to[t[0] as usize], to[t[1] as usize], to[t[2] as usize]];
                (point_triangle_max_step(&x0, &x1, 0.0, 1.0, &params), 1)
            })
            .reduce(|| (1.0, 0), |a, b| (a.0.min(b.0), a.1 + b.1));
        let (a_ee, q_ee) = c
            .edge_edge
            .par_iter()
            .map(|&(i, j)| {
                let (ea, eb) = (self.edges[i as usize], self.edges[j as usize]);
                let x0 = [
                    from[ea[0] as usize],
                    from[ea[1] as usize],
                    from[eb[0] as usize],
                    from[eb[1] as usize],
                ];
                let ty = edge_edge_distance_type(&x0[0], &x0[1], &x0[2], &x0[3]);
                let d0 = edge_edge_distance_sq_typed(&x0[0], &x0[1], &x0[2], &x0[3], ty).sqrt();
                if d0 > disp(ea[0]).max(disp(ea[1])) + disp(eb[0]).max(disp(eb[1])) {
                    return (1.0, 0);
                }
                let x1 = [
                    to[ea[0] as usize],
                    to[ea[1] as usize],
                    to[eb[0] as usize],
                    to[eb[1] as usize],
                ];
                (edge_edge_max_step(&x0, &x1, 0.0, 1.0, &params), 1)
            })
            .reduce(|| (1.0, 0), |a, b| (a.0.min(b.0), a.1 + b.1));
        (a_pt.min(a_ee), q_pt + q_ee)
    }
}

/// Candidate pairs (indices into the contact points, edges and triangles), valid while every
/// contact point stays within `margin_m` of the box it `swept` when they were found.
#[derive(Default)]
struct Candidates {
    point_triangle: Vec<(u32, u32)>,
    edge_edge: Vec<(u32, u32)>,
    swept: Vec<Aabb>,
    margin_m: f64,
}

impl Candidates {
    /// Whether every contact point of `x` is within the margin of its swept box.
    fn cover(&self, points: &[u32], x: &[Vector3<f64>]) -> bool {
        let m = self.margin_m;
        self.swept.len() == points.len()
            && points.par_iter().zip(&self.swept).all(|(&p, b)| {
                let q = &x[p as usize];
                (0..3).all(|k| q[k] >= b.min[k] - m && q[k] <= b.max[k] + m)
            })
    }
}

/// How the nodes of a pair (padded with `NO_DOF`) depend on the DOFs.
fn node_maps<'s>(nodes: &[u32; 4], state: &'s EvalState) -> [NodeMap<'s>; 4] {
    nodes.map(|i| {
        if i == NO_DOF {
            NodeMap::Fixed
        } else {
            Node::Point(i).map(state)
        }
    })
}

/// Write node-space derivatives of a 4-node stencil in the deformable DOF layout (`∂x/∂v = dt·I`).
fn write_dofs(d: &HyperDual<4>, dt: f64, out: &mut [f64]) {
    out[0] = d.value;
    for (k, g) in d.grad.as_flattened().iter().enumerate() {
        out[1 + k] = dt * g;
    }
    let dt2 = dt * dt;
    let base = 13;
    for a in 0..4 {
        for b in 0..4 {
            let blk = &mut out[base + 9 * (a * 4 + b)..base + 9 * (a * 4 + b) + 9];
            for i in 0..3 {
                for j in 0..3 {
                    blk[3 * i + j] = dt2 * d.hess[a][i][b][j];
                }
            }
        }
    }
}

/// [`write_dofs`] for a stencil of deformable (`Free`) and absent (`Fixed`) nodes in the layout of
/// [`element_stride`]`(width)` with the blocks of `element_blocks` (the free nodes in order).
fn write_free_dofs(d: &HyperDual<4>, maps: &[NodeMap; 4], dt: f64, out: &mut [f64]) {
    let width = (1..=8)
        .find(|&w| element_stride(w) == out.len())
        .expect("an element stride");
    let mut slot = [usize::MAX; 4];
    let mut m = 0;
    for (a, map) in maps.iter().enumerate() {
        if matches!(map, NodeMap::Free { .. }) {
            slot[a] = m;
            m += 1;
        }
    }
    out.iter_mut().for_each(|o| *o = 0.0);
    out[0] = d.value;
    let dt2 = dt * dt;
    let base = 1 + 3 * width;
    for a in 0..4 {
        let sa = slot[a];
        if sa == usize::MAX {
            continue;
        }
        for i in 0..3 {
            out[1 + 3 * sa + i] = dt * d.grad[a][i];
        }
        for b in 0..4 {
            let sb = slot[b];
            if sb == usize::MAX {
                continue;
            }
            let blk = &mut out[base + 9 * (sa * width + sb)..base + 9 * (sa * width + sb) + 9];
            for i in 0..3 {
                for j in 0..3 {
                    blk[3 * i + j] = dt2 * d.hess[a][i][b][j];
                }
            }
        }
    }
}

impl Contact {
    /// Whether any contact object is a rigid body's mesh.
    fn has_rigid_objects(&self, state: &EvalState) -> bool {
        !state.bodies.is_empty()
            && self
                .objects
                .iter()
                .any(|o| state.nodes.body[o.nodes.first as usize] != NO_BODY)
    }

    /// Split the primitives into those of rigid bodies' meshes and the others (empty without
    /// rigid contact objects, which makes the validity test free).
    fn split_rigid(&self, state: &EvalState) -> RigidSplit {
        if !self.has_rigid_objects(state) {
            return RigidSplit::default();
        }
        let rigid: Vec<bool> = self
            .objects
            .iter()
            .map(|o| state.nodes.body[o.nodes.first as usize] != NO_BODY)
            .collect();
        let (rigid_triangles, other_triangles) =
            (0..self.triangles.len() as u32).partition(|&t| rigid[self.tri_obj[t as usize] as usize]);
        RigidSplit {
            rigid_triangles,
            rigid_edges: (0..self.edges.len() as u32)
                .filter(|&e| rigid[self.edge_obj[e as usize] as usize])
                .collect(),
            other_triangles,
        }
    }

    /// Whether, at positions `x`, an edge crosses a triangle (exact test,
    /// [`edge_triangle_intersect`]) in a pair of enabled objects of which at least one is a rigid
    /// body's mesh; pairs of deformable primitives are not tested. This is the line-search
    /// validity test: deformable nodes move on straight lines in a line search, so CCD on the
    /// chord guards them exactly, but a rigid point moves on an arc (its position is non-linear in
    /// `ω`) and the trial state can leave the chord that CCD checked. Uses the split of the last
    /// `before_step`.
    ///
    /// Cost: a BVH over the rigid triangles and one over the rigid edges, queried with the box of
    /// every edge and of every other triangle that overlaps the rigid primitives' overall box.
    pub fn rigid_pairs_intersect(&self, x: &[Vector3<f64>]) -> bool {
        let split = &self.rigid_split;
        if split.is_empty() {
            return false;
        }
        let p = |i: u32| &x[i as usize];
        let tri_box = |t: u32| {
            let t = self.triangles[t as usize];
            triangle_aabb(p(t[0]), p(t[1]), p(t[2]), 0.0)
        };
        let edge_box = |e: u32| {
            let e = self.edges[e as usize];
            edge_aabb(p(e[0]), p(e[1]), 0.0)
        };
        let crosses = |e: u32, t: u32| {
            let (ea, tb) = (self.edges[e as usize], self.triangles[t as usize]);
            self.pair_ok(self.edge_obj[e as usize], self.tri_obj[t as usize])
                && !tb.contains(&ea[0])
                && !tb.contains(&ea[1])
                && edge_triangle_intersect(p(ea[0]), p(ea[1]), p(tb[0]), p(tb[1]), p(tb[2]))
        };
        // Every edge against the rigid triangles, then the other triangles against the rigid
        // edges. Small sets run sequentially (rayon's start-up costs more than the test).
        let boxes: Vec<Aabb> = split.rigid_triangles.iter().map(|&t| tri_box(t)).collect();
        let bvh = Bvh::build(&boxes);
        let near = bvh.aabb();
        let edge_hits = |e: u32| {
            let b = edge_box(e);
            let mut hit = false;
            if b.intersects(&near) {
                bvh.query_aabb(&b, |k| hit = hit || crosses(e, split.rigid_triangles[k]));
            }
            hit
        };
        let n_edges = self.edges.len() as u32;
        let hit = if n_edges < PARALLEL_VALIDITY_MIN {
            (0..n_edges).any(edge_hits)
        } else {
            (0..n_edges).into_par_iter().any(edge_hits)
        };
        if hit {
            return true;
        }
        let boxes: Vec<Aabb> = split.rigid_edges.iter().map(|&e| edge_box(e)).collect();
        let bvh = Bvh::build(&boxes);
        let near = bvh.aabb();
        let triangle_hits = |&t: &u32| {
            let b = tri_box(t);
            let mut hit = false;
            if b.intersects(&near) {
                bvh.query_aabb(&b, |k| hit = hit || crosses(split.rigid_edges[k], t));
            }
            hit
        };
        if split.other_triangles.len() < PARALLEL_VALIDITY_MIN as usize {
            split.other_triangles.iter().any(triangle_hits)
        } else {
            split.other_triangles.par_iter().any(triangle_hits)
        }
    }
}

/// Primitive counts below which the validity test runs on one thread.
const PARALLEL_VALIDITY_MIN: u32 = 4096;

impl EnergyTerm for Contact {
    fn name(&self) -> &str {
        "contact"
    }
    fn num_elements(&self) -> usize {
        self.pairs.len() + self.friction_elements.len()
    }
    fn stencil_width(&self, state: &EvalState) -> usize {
        // A point of a rigid body against a deformable triangle couples 2 + 3 blocks.
        if self.has_rigid_objects(state) {
            5
        } else {
            4
        }
    }
    fn write_stencils(&self, state: &EvalState, out: &mut [u32]) {
        let all = self
            .pairs
            .iter()
            .map(|p| p.nodes)
            .chain(self.friction_elements.iter().map(|f| f.nodes));
        let w = self.stencil_width(state);
        for (o, nodes) in out.chunks_exact_mut(w).zip(all) {
            if w == 4 {
                o.copy_from_slice(&nodes);
            } else {
                element_blocks(&node_maps(&nodes, state), o);
            }
        }
    }
    fn topology_version(&self) -> u64 {
        self.version
    }
    fn energy(&self, state: &EvalState) -> f64 {
        let kind = self.settings.barrier;
        let barrier_energy: f64 = self
            .pairs
            .iter()
            .map(|p| {
                pair_energy(
                    p,
                    &Self::stencil_x(&p.nodes, state.x).map(|q| Vec3::<f64>::constant(&q)),
                    p.kappa * p.multiplicity,
                    kind,
                )
            })
            .sum();
        let friction_energy: f64 = self
            .friction_elements
            .iter()
            .map(|f| f.energy(&Self::stencil_x(&f.nodes, state.x).map(|q| Vec3::<f64>::constant(&q))))
            .sum();
        barrier_energy + friction_energy
    }
    fn evaluate_element(&self, e: usize, state: &EvalState, mode: EvalMode, out: &mut [f64]) {
        let mut d = HyperDual::<4>::constant(0.0);
        // A barrier pair's Hessian is indefinite (the distance curves), and far from the solution
        // its negative curvature can make the whole Hessian indefinite: there the pairs take a
        // positive semi-definite form (IPC). Near the solution the other energies (inertia above
        // all) carry that curvature, and the projected form would only overestimate it: Newton
        // would converge linearly (measured on a folded towel under a robot: a contraction of
        // 0.69 per iteration over 20 iterations at full steps). There the exact Hessian, and the
        // solver projects anyway when the total turns out indefinite.
        let hessian = if mode == EvalMode::ExactHessian && !self.definite_barriers {
            PairHessian::Exact
        } else {
            self.settings.hessian
        };
        if e < self.pairs.len() {
            let p = &self.pairs[e];
            pair_derivatives(
                p,
                &Self::stencil_x(&p.nodes, state.x),
                p.kappa * p.multiplicity,
                self.settings.barrier,
                hessian,
                &mut d,
            );
        } else {
            let f = &self.friction_elements[e - self.pairs.len()];
            f.derivatives(&Self::stencil_x(&f.nodes, state.x), self.friction_majorizer, &mut d);
        }
        if out.len() == element_stride(4) {
            write_dofs(&d, state.dt, out);
        } else {
            let nodes = if e < self.pairs.len() {
                self.pairs[e].nodes
            } else {
                self.friction_elements[e - self.pairs.len()].nodes
            };
            let maps = node_maps(&nodes, state);
            if maps.iter().all(|m| matches!(m, NodeMap::Free { .. } | NodeMap::Fixed)) {
                // No rigid node (e.g. towel–towel pairs in a scene with bodies): the map is
                // `dt·I` per node, written straight into the wider layout.
                write_free_dofs(&d, &maps, state.dt, out);
                return;
            }
            // Through the kinematic map; the position-space Hessian is already positive
            // semi-definite, the rotation's second-order term may not be.
            let projection = if hessian == PairHessian::Exact {
                MapProjection::None
            } else {
                MapProjection::SecondOrderOnly
            };
            map_element(&maps, &d, state.dt, 5, projection, out);
        }
    }
    fn before_step(&mut self, state: &EvalState) {
        // Objects, thicknesses or enabled pairs may have changed since the last step.
        *self.candidate_cache.get_mut().expect("no poisoned lock") = None;
        self.rigid_split = self.split_rigid(state);
        *self.validity_record.get_mut().expect("no poisoned lock") = (0, 0, 0.0);
        if self.relag_pending {
            self.relag_pending = false;
        } else {
            self.lag_solves = 1;
            let pairs = self.detect(state.x);
            self.lag_friction(&pairs, state.x, state.x, state.dt);
        }
        self.version += 1;
    }
    fn use_majorizer_hessian(&mut self, on: bool) {
        self.friction_majorizer = on;
    }
    fn use_definite_hessian(&mut self, on: bool) {
        self.definite_barriers = on;
    }
    fn prepare_evaluation(&mut self, state: &EvalState) {
        let pairs = self.detect(state.x);
        if pairs
            .iter()
            .map(|p| (p.kind, p.nodes))
            .ne(self.pairs.iter().map(|p| (p.kind, p.nodes)))
        {
            self.version += 1;
        }
        self.pairs = pairs;
        self.stats.active_pairs = self.pairs.len();
    }
    fn rebalance(&mut self, state: &EvalState, gradient: &[f64]) -> bool {
        if self.settings.stiffness.is_some() || self.pairs.is_empty() {
            return false;
        }
        let distances: Vec<f64> = self.pairs.iter().map(|p| Self::pair_distance(p, state.x)).collect();
        let kind = self.settings.barrier;
        // Pairs of objects whose load is to be measured (IPC's gradient balance, per pair of
        // objects): engaged (closer than 0.9 d̂) and either never measured or pressed below a
        // tenth of d̂ (the load grew).
        let mut keys: Vec<[u16; 2]> = Vec::new();
        for (p, &d) in self.pairs.iter().zip(&distances) {
            let key = sorted_objects(p.objects);
            let engaged = d < 0.9 * p.dhat;
            if engaged && (!self.kappa.balanced(key[0] as usize, key[1] as usize) || d < 0.1 * p.dhat) {
                keys.push(key);
            }
        }
        keys.sort_unstable();
        keys.dedup();
        if keys.is_empty() {
            return false;
        }
        let w = self.stencil_width(state);
        let mut blocks = vec![NO_DOF; w];
        let mut out = vec![0.0; element_stride(w)];
        // Kinematic nodes (prescribed obstacles) take any reaction: they are not balanced.
        let kinematic: std::collections::BTreeSet<u32> = self
            .points
            .iter()
            .zip(&self.point_obj)
            .filter(|(_, &o)| self.object_masses_kg.get(o as usize).is_some_and(|&m| m == 0.0))
            .map(|(&p, _)| p)
            .collect();
        // The barrier's DOF-space gradient, in total and per unit κ of each measured key.
        let mut barrier_total: std::collections::BTreeMap<u32, Vector3<f64>> = Default::default();
        let mut per_unit: Vec<std::collections::BTreeMap<u32, Vector3<f64>>> = vec![Default::default(); keys.len()];
        let mut slope_sum = vec![0.0; keys.len()];
        let mut slope_count = vec![0usize; keys.len()];
        for (e, (p, &d)) in self.pairs.iter().zip(&distances).enumerate() {
            if w == 4 {
                blocks.copy_from_slice(&p.nodes);
            } else {
                element_blocks(&node_maps(&p.nodes, state), &mut blocks);
            }
            self.evaluate_element(e, state, EvalMode::ProjectedHessian, &mut out);
            let key = keys
                .binary_search(&sorted_objects(p.objects))
                .ok()
                .filter(|_| d < 0.9 * p.dhat);
            for (k, &b) in blocks.iter().enumerate() {
                if b == NO_DOF {
                    continue;
                }
                let g = Vector3::new(out[1 + 3 * k], out[2 + 3 * k], out[3 + 3 * k]);
                *barrier_total.entry(b).or_insert_with(Vector3::zeros) += g;
                if kinematic.contains(&b) {
                    continue;
                }
                if let Some(i) = key {
                    *per_unit[i].entry(b).or_insert_with(Vector3::zeros) += g / p.kappa;
                }
            }
            if let Some(i) = key {
                slope_sum[i] += barrier(kind, d, p.dhat).1.abs();
                slope_count[i] += 1;
            }
        }
        let other = |b: u32| {
            let i = 3 * b as usize;
            Vector3::new(gradient[i], gradient[i + 1], gradient[i + 2]) - barrier_total[&b]
        };
        // Least squares: the stiffnesses whose barrier forces best cancel everything else.
        let n = keys.len();
        let mut a = nalgebra::DMatrix::<f64>::zeros(n, n);
        let mut r = nalgebra::DVector::<f64>::zeros(n);
        for i in 0..n {
            for (&b, g) in &per_unit[i] {
                r[i] -= g.dot(&other(b));
                for j in 0..n {
                    if let Some(h) = per_unit[j].get(&b) {
                        a[(i, j)] += g.dot(h);
                    }
                }
            }
        }
        let solved = a.clone().lu().solve(&r);
        let mut changed = false;
        // Per measured pair of objects: the stiffness at which the barrier at the current gaps
        // carries the measured load (friction's normal forces), and the one it is set to.
        let mut load_kappa: Vec<f64> = vec![f64::NAN; n];
        for (i, key) in keys.iter().enumerate() {
            let (oa, ob) = (key[0] as usize, key[1] as usize);
            let ls = solved
                .as_ref()
                .map(|k| k[i])
                .filter(|k| k.is_finite() && *k > 0.0)
                .unwrap_or(r[i] / a[(i, i)]);
            if !(ls > 0.0 && ls.is_finite()) {
                continue;
            }
            load_kappa[i] = ls;
            // The load `ls·Σ|b′(d)|` it carries, to be carried at half the activation distance.
            let dhat = self.dhat(key[0], key[1]);
            let target = ls * (slope_sum[i] / slope_count[i] as f64) / barrier(kind, 0.5 * dhat, dhat).1.abs();
            changed |= self
                .kappa
                .set_from_load(oa, ob, target, self.settings.max_stiffness_factor);
        }
        if changed {
            // Friction's normal forces are the measured loads: lag them from the start of the
            // step with the stiffness that carries them at the current gaps.
            let x0 = &state.nodes.x;
            let mut start = self.detect(x0);
            for p in &mut start {
                if let Ok(i) = keys.binary_search(&sorted_objects(p.objects)) {
                    if load_kappa[i].is_finite() {
                        p.kappa = load_kappa[i];
                    }
                }
            }
            self.lag_friction(&start, x0, x0, state.dt);
            for p in &mut self.pairs {
                p.kappa = self.kappa.get(p.objects[0] as usize, p.objects[1] as usize);
            }
            self.stats.stiffness = self.kappa.max();
        }
        changed
    }
    fn max_step_fraction(&self, from: &EvalState, to: &EvalState) -> f64 {
        if self.objects.is_empty() {
            return 1.0;
        }
        let cached = self.candidate_cache.lock().expect("no poisoned lock").take();
        let candidates = self.candidates_for(cached, from.x, to.x);
        let (alpha, queries) = if self.settings.ccd {
            self.ccd_fraction(&candidates, from.x, to.x)
        } else {
            (1.0, 0)
        };
        *self.candidate_cache.lock().expect("no poisoned lock") = Some(candidates);
        *self.ccd_record.lock().expect("no poisoned lock") = (alpha, queries);
        alpha
    }
    fn is_valid_state(&self, state: &EvalState) -> bool {
        if self.rigid_split.is_empty() {
            return true;
        }
        let t0 = std::time::Instant::now();
        let valid = !self.rigid_pairs_intersect(state.x);
        let mut r = self.validity_record.lock().expect("no poisoned lock");
        r.0 += 1;
        r.1 += usize::from(!valid);
        r.2 += t0.elapsed().as_secs_f64();
        valid
    }
    fn check_converged_step(&mut self, state: &EvalState) -> StepCheck {
        if self.lag_solves < self.settings.friction_iterations && self.friction.iter().any(|&m| m > 0.0) {
            let pairs = self.detect(state.x);
            self.lag_friction(&pairs, state.x, &state.nodes.x, state.dt);
            self.lag_solves += 1;
            self.relag_pending = true;
            return StepCheck::Retry(format!(
                "friction re-lagged ({} of {})",
                self.lag_solves, self.settings.friction_iterations
            ));
        }
        StepCheck::Accept
    }
    fn save_state(&self) -> Vec<u8> {
        self.save_checkpoint_state()
    }
    fn restore_state(&mut self, bytes: &[u8]) -> Result<(), String> {
        self.restore_checkpoint_state(bytes)
    }
    fn after_step(&mut self, state: &EvalState) {
        let pairs = self.detect(state.x);
        let mut min_d = f64::INFINITY;
        let mut too_close: Vec<[u16; 2]> = Vec::new();
        for p in &pairs {
            let d = Self::pair_distance(p, state.x);
            min_d = min_d.min(d);
            if d < self.settings.min_distance_fraction * p.dhat {
                too_close.push(p.objects);
            }
        }
        self.stats.min_distance_m = min_d;
        // IPC's adaptive stiffness, per pair of objects: a pair this close means the barrier is
        // too soft for the load it carries; stiffen it (bounded) so gaps stay resolvable.
        too_close.sort_unstable();
        too_close.dedup();
        for [a, b] in too_close {
            self.kappa
                .stiffen(a as usize, b as usize, self.settings.max_stiffness_factor);
        }
        self.stats.stiffness = self.kappa.max();
        let (fraction, queries) = *self.ccd_record.lock().expect("no poisoned lock");
        self.stats.min_ccd_fraction = fraction;
        self.stats.ccd_queries = queries;
        let (checks, rejected, seconds) = *self.validity_record.lock().expect("no poisoned lock");
        self.stats.validity_checks = checks;
        self.stats.invalid_trials = rejected;
        self.stats.validity_time_s = seconds;
    }
}

#[cfg(test)]
mod tests {
    use crate::energy::kinematics::BodyPose;
    use crate::energy::EnergyTerm;
    use crate::state::{dof_blocks, EvalState};
    use crate::{Settings, Simulation};
    use nalgebra::{UnitQuaternion, Vector3};

    fn square(z: f64, half: f64) -> [Vector3<f64>; 4] {
        [
            Vector3::new(-half, -half, z),
            Vector3::new(half, -half, z),
            Vector3::new(half, half, z),
            Vector3::new(-half, half, z),
        ]
    }

    /// Run the contact term's `before_step` at the current state and return the validity of the
    /// positions `x` through `is_valid_state`.
    fn valid_at(sim: &mut Simulation, x: &[Vector3<f64>]) -> bool {
        at_rest(sim, |contact, state| {
            contact.before_step(state);
            let trial = EvalState { x, ..*state };
            contact.is_valid_state(&trial)
        })
    }

    /// Call `f` with the contact term and the state of the simulation at rest (dt = 0.01 s).
    fn at_rest<R>(sim: &mut Simulation, f: impl FnOnce(&mut super::Contact, &EvalState) -> R) -> R {
        let zeros = vec![Vector3::zeros(); dof_blocks(&sim.nodes, &sim.bodies)];
        let poses: Vec<BodyPose> = (0..sim.bodies.len())
            .map(|b| BodyPose::at_rest(sim.bodies.position[b], &sim.bodies.orientation[b], 0.01))
            .collect();
        let nodes = sim.nodes.clone();
        let state = EvalState {
            dt: 0.01,
            time: 0.01,
            gravity: Vector3::zeros(),
            nodes: &nodes,
            v: &zeros,
            x: &nodes.x,
            bodies: &sim.bodies,
            poses: &poses,
        };
        f(&mut sim.contact, &state)
    }

    #[test]
    fn trial_states_with_rigid_crossings_are_invalid() {
        let mut settings = Settings::default();
        settings.contact.default_thickness_m = Some(1e-3);
        let mut sim = Simulation::new(settings).unwrap();
        // A 2 m sheet whose diagonal runs from (−1, −1) to (1, 1), and two 0.1 m boxes above
        // it, far from the diagonal and the border.
        let sheet = sim
            .add_prescribed_surface("sheet", &square(0.0, 1.0), &[[0, 1, 2], [0, 2, 3]], 1e-3, 1e4)
            .unwrap();
        let (q, size) = (UnitQuaternion::identity(), Vector3::repeat(0.1));
        let a = sim
            .add_box("a", 1.0, size, Vector3::new(0.5, -0.5, 0.1), q, None)
            .unwrap();
        let b = sim
            .add_box("b", 1.0, size, Vector3::new(-0.5, 0.5, 0.1), q, None)
            .unwrap();
        let x = sim.nodes.x.clone();
        assert!(valid_at(&mut sim, &x));
        // Box a straddles the sheet: only its vertical edges cross a sheet triangle.
        let mut down = x.clone();
        for i in a.mesh.nodes.range() {
            down[i].z -= 0.1;
        }
        assert!(!valid_at(&mut sim, &down));
        // Box a overlaps box b (rigid–rigid).
        let mut over = x.clone();
        for i in a.mesh.nodes.range() {
            over[i] += Vector3::new(-0.95, 0.95, 0.03);
        }
        assert!(!valid_at(&mut sim, &over));
        // Box a centred on the sheet's diagonal: the diagonal crosses its faces.
        let mut moved = x.clone();
        for i in a.mesh.nodes.range() {
            moved[i] += Vector3::new(-0.5, -0.5, -0.1);
        }
        assert!(!valid_at(&mut sim, &moved));
        // Pairs whose collisions are off are not tested.
        sim.contact.disable_collision(sheet.contact, a.mesh.contact).unwrap();
        assert!(valid_at(&mut sim, &down));
        let _ = b;
    }

    /// Newton's `use_definite_hessian` switch: on (far from the solution), a pair whose distance
    /// curves assembles a positive semi-definite Hessian; off (near it), the exact one, whose
    /// negative curvature across the pair the inertia carries.
    #[test]
    fn barrier_pairs_take_their_exact_hessian_when_newton_asks() {
        use crate::energy::psd::symmetric_eigen;
        use crate::energy::EvalMode;
        let mut settings = Settings::default();
        settings.contact.default_thickness_m = Some(1e-3);
        let mut sim = Simulation::new(settings).unwrap();
        // Two triangles whose corners face each other 0.4 mm apart: one point–point pair.
        let lower = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(-1.0, 0.0, -1.0),
            Vector3::new(0.0, -1.0, -1.0),
        ];
        let upper = lower.map(|p| Vector3::new(-p.x, -p.y, 4e-4 - p.z));
        sim.add_prescribed_surface("lower", &lower, &[[0, 1, 2]], 1e-3, 1e4)
            .unwrap();
        sim.add_prescribed_surface("upper", &upper, &[[0, 1, 2]], 1e-3, 1e4)
            .unwrap();
        let masses_kg = vec![1e-3; sim.nodes.len()];
        sim.contact.initialize_stiffness(&masses_kg, 0.01, 9.81);
        let x = sim.nodes.x.clone();
        assert!(valid_at(&mut sim, &x));
        at_rest(&mut sim, |contact, state| {
            contact.prepare_evaluation(state);
            // The corners' point–point pair, and the edges that meet there (edge–edge, the same
            // closest points).
            let pairs = contact.pairs().len();
            assert!(pairs >= 1);
            let mut smallest_eigenvalue = |e: usize, definite: bool| {
                contact.use_definite_hessian(definite);
                let mut out = vec![0.0; crate::energy::term::element_stride(4)];
                contact.evaluate_element(e, state, EvalMode::ExactHessian, &mut out);
                // The 12×12 Hessian from its 3×3 blocks.
                let mut h = [0.0; 144];
                for (a, b, i, j) in hessian_block_entries() {
                    h[(3 * a + i) * 12 + 3 * b + j] = out[13 + 9 * (a * 4 + b) + 3 * i + j];
                }
                let (mut w, mut v) = ([0.0; 12], [0.0; 144]);
                symmetric_eigen(&h, 12, &mut w, &mut v);
                let scale = w.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                w.iter().copied().fold(f64::INFINITY, f64::min) / scale
            };
            for e in 0..pairs {
                let l = smallest_eigenvalue(e, true);
                assert!(l > -1e-12, "definite form: pair {e}: {l}");
            }
            let exact = (0..pairs).map(|e| smallest_eigenvalue(e, false));
            assert!(
                exact.fold(f64::INFINITY, f64::min) < -1e-3,
                "exact: negative curvature across"
            );
        });
    }

    /// (block row, block column, row, column) of the 4×4 blocks of 3×3 in an element buffer.
    fn hessian_block_entries() -> impl Iterator<Item = (usize, usize, usize, usize)> {
        (0..4).flat_map(|a| (0..4).flat_map(move |b| (0..3).flat_map(move |i| (0..3).map(move |j| (a, b, i, j)))))
    }

    #[test]
    fn deformable_crossings_are_left_to_ccd_and_scenes_without_bodies_pay_nothing() {
        let mut settings = Settings::default();
        settings.contact.default_thickness_m = Some(1e-3);
        let mut sim = Simulation::new(settings).unwrap();
        sim.add_prescribed_surface("lower", &square(0.0, 1.0), &[[0, 1, 2], [0, 2, 3]], 1e-3, 1e4)
            .unwrap();
        sim.add_prescribed_surface("upper", &square(0.5, 0.5), &[[0, 1, 2], [0, 2, 3]], 1e-3, 1e4)
            .unwrap();
        let mut x = sim.nodes.x.clone();
        // The upper sheet tilted through the lower one.
        x[4].z = -0.5;
        x[5].z = -0.5;
        assert!(!sim.contact.find_intersections(&x).is_empty());
        assert!(valid_at(&mut sim, &x), "deformable pairs are CCD's business");
        assert!(sim.contact.rigid_split.is_empty());
        assert_eq!(sim.contact.validity_record.lock().unwrap().0, 0, "no test ran");
    }
}
