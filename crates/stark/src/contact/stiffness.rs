//! Barrier stiffness `κ` per pair of contact objects.
//!
//! The barrier is a spring whose force law is `κ·|b′(d)|`; how stiff `κ` must be depends on what
//! the pair carries. IPC chooses one `κ` from the mean nodal mass `m̄` as `m̄/dt²`, which balances
//! the barrier's curvature against inertia. One global value is too soft for a rigid box (its
//! contact points carry the whole body) and too stiff for cloth resting on it, and inertia alone
//! ignores the static load: a 1 kg box on four corners at dt = 1/30 s got `κ` ≈ 110 N/m, sank
//! to a tenth of `d̂` over its first steps and slid while its lagged normal force was still a
//! fraction of its weight. So each pair of objects `(a, b)` gets its own
//!
//! `κ_ab = m_ab · (1/dt² + |g| / (c·d̂_ab))`,   `c = |b′(d̂/2)| / d̂`  (1.19 for the log barrier),
//!
//! with `m_ab` the larger of the two objects' mean contact-point masses: for a deformable node its
//! lumped mass; for a point of a rigid body the body's effective mass at that point,
//! `1/m = 1/M + ⟨(r×n)ᵀ I⁻¹ (r×n)⟩` averaged over contact normals `n`
//! (`= 1/M + (|r|² tr I⁻¹ − rᵀ I⁻¹ r)/3`, `r` the lever arm from the centre of mass). The first
//! term is IPC's inertia balance; the second makes the barrier carry the weight of that mass at
//! half the activation distance, where its curvature is moderate, so a body put down anywhere in
//! `(0, d̂)` starts near equilibrium and does not rock. Kinematic objects (prescribed surfaces)
//! have no mass and do not count. Loads beyond the weight (stacks, grippers, a robot on a towel)
//! raise `κ_ab` as they build: it doubles after a step in which a pair of `(a, b)` came closer
//! than `min_distance_fraction·d̂` (IPC's adaptive rule, per object pair), bounded by
//! `max_stiffness_factor` times its initial value. A user-set stiffness applies to every pair.

use super::barrier::{barrier, BarrierKind};
use super::objects::sorted_objects;
use super::term::node_maps;
use super::Contact;
use crate::energy::kinematics::element_blocks;
use crate::energy::term::{element_stride, NO_DOF};
use crate::energy::{EnergyTerm, EvalMode};
use crate::state::EvalState;
use nalgebra::Vector3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// `κ` of every pair of contact objects (symmetric), 0 until chosen.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct PairStiffness {
    objects: usize,
    kappa: Vec<f64>,
    initial: Vec<f64>,
    /// The inertial part `m_ab/dt²`, below which a measured load never lowers `κ`.
    floor: Vec<f64>,
    /// The pair's load was measured once ([`PairStiffness::raise`]).
    balanced: Vec<bool>,
}

impl PairStiffness {
    /// Make room for `objects` objects, keeping the values of the existing pairs.
    pub fn resize(&mut self, objects: usize) {
        let old = self.objects;
        let mut kappa = vec![0.0; objects * objects];
        let mut initial = vec![0.0; objects * objects];
        let mut balanced = vec![false; objects * objects];
        let mut floor = vec![0.0; objects * objects];
        for a in 0..old.min(objects) {
            for b in 0..old.min(objects) {
                floor[a * objects + b] = self.floor[a * old + b];
                kappa[a * objects + b] = self.kappa[a * old + b];
                initial[a * objects + b] = self.initial[a * old + b];
                balanced[a * objects + b] = self.balanced[a * old + b];
            }
        }
        self.objects = objects;
        self.kappa = kappa;
        self.initial = initial;
        self.balanced = balanced;
        self.floor = floor;
    }

    /// Number of objects.
    pub fn objects(&self) -> usize {
        self.objects
    }

    /// `κ` of objects `a` and `b`, N/m (0 before it is chosen).
    pub fn get(&self, a: usize, b: usize) -> f64 {
        self.kappa[a * self.objects + b]
    }

    /// Some pair has no stiffness yet.
    pub fn needs_initialization(&self) -> bool {
        self.kappa.contains(&0.0)
    }

    /// Choose `κ` for every pair that has none: `fixed` if the user set one, else the rule of the
    /// module documentation from the objects' mean contact masses (kg, 0 for kinematic objects),
    /// `dhat(a, b)` (m), the time step (s) and the magnitude of gravity (m/s²).
    pub fn initialize(
        &mut self,
        fixed: Option<f64>,
        object_masses_kg: &[f64],
        dhat: impl Fn(usize, usize) -> f64,
        dt: f64,
        gravity_m_s2: f64,
        kind: BarrierKind,
    ) {
        let n = self.objects;
        for a in 0..n {
            for b in a..n {
                if self.kappa[a * n + b] > 0.0 {
                    continue;
                }
                let d = dhat(a, b);
                let m = object_masses_kg[a].max(object_masses_kg[b]);
                // Both kinematic: they never move against each other; any value serves.
                let m = if m > 0.0 { m } else { 1.0 };
                let c = barrier(kind, 0.5 * d, d).1.abs() / d;
                let inertial = m / (dt * dt);
                let k = fixed.unwrap_or(inertial + m * gravity_m_s2 / (c * d));
                for (i, j) in [(a, b), (b, a)] {
                    self.kappa[i * n + j] = k;
                    self.initial[i * n + j] = k;
                    self.floor[i * n + j] = fixed.unwrap_or(inertial);
                }
            }
        }
    }

    /// Double `κ` of objects `a` and `b`, up to `max_factor` times its initial value.
    pub fn stiffen(&mut self, a: usize, b: usize, max_factor: f64) {
        let n = self.objects;
        let k = (2.0 * self.kappa[a * n + b]).min(max_factor * self.initial[a * n + b]);
        self.kappa[a * n + b] = k;
        self.kappa[b * n + a] = k;
    }

    /// Whether the load of objects `a` and `b` was measured.
    pub fn balanced(&self, a: usize, b: usize) -> bool {
        self.balanced[a * self.objects + b]
    }

    /// Set `κ` of objects `a` and `b` from a measured load: to `target`, bounded by
    /// `max_factor` times its initial value. The first measurement may lower it to its inertial
    /// part (the rule's weight term guessed the load); later ones only raise it. Whether it
    /// changed by more than 1%, and marks the pair measured.
    pub fn set_from_load(&mut self, a: usize, b: usize, target: f64, max_factor: f64) -> bool {
        let n = self.objects;
        let old = self.kappa[a * n + b];
        let lowest = if self.balanced[a * n + b] {
            old
        } else {
            self.floor[a * n + b]
        };
        let k = target.min(max_factor * self.initial[a * n + b]).max(lowest);
        self.kappa[a * n + b] = k;
        self.kappa[b * n + a] = k;
        self.balanced[a * n + b] = true;
        self.balanced[b * n + a] = true;
        (k - old).abs() > 0.01 * old
    }

    /// The largest `κ`, N/m (0 without objects).
    pub fn max(&self) -> f64 {
        self.kappa.iter().copied().fold(0.0, f64::max)
    }
}

/// Mean contact mass of each object (kg): the mean over its contact points of `node_masses_kg`
/// (effective masses, 0 for kinematic nodes), counting only points with mass.
pub fn object_contact_masses(objects: usize, points: &[u32], point_obj: &[u16], node_masses_kg: &[f64]) -> Vec<f64> {
    let mut sum = vec![0.0; objects];
    let mut count = vec![0usize; objects];
    for (&p, &o) in points.iter().zip(point_obj) {
        let m = node_masses_kg[p as usize];
        if m > 0.0 {
            sum[o as usize] += m;
            count[o as usize] += 1;
        }
    }
    sum.iter()
        .zip(&count)
        .map(|(&s, &c)| if c > 0 { s / c as f64 } else { 0.0 })
        .collect()
}

impl Contact {
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

    /// IPC's gradient balance per pair of objects (`EnergyTerm::rebalance`): stiffen the pairs whose
    /// barrier is too soft for the load they carry; whether any `κ` changed.
    pub(super) fn rebalance_stiffness(&mut self, state: &EvalState, gradient: &[f64]) -> bool {
        if self.settings.stiffness.is_some() || self.pairs.is_empty() {
            return false;
        }
        let distances: Vec<f64> = self
            .pairs
            .par_iter()
            .with_min_len(1024)
            .map(|p| Self::pair_distance(p, state.x))
            .collect();
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
        // The pairs' DOF-space gradients, in parallel (the Hessian form does not change them:
        // the exact one spares the projections).
        let mut gradients = vec![0.0; self.pairs.len() * 3 * w];
        {
            let this = &*self;
            gradients.par_chunks_mut(3 * w).enumerate().for_each_init(
                || vec![0.0; element_stride(w)],
                |out, (e, g)| {
                    this.evaluate_contact_element(e, state, EvalMode::ExactHessian, false, out);
                    g.copy_from_slice(&out[1..1 + 3 * w]);
                },
            );
        }
        // Kinematic nodes (prescribed obstacles) take any reaction: they are not balanced.
        let kinematic: std::collections::BTreeSet<u32> = self
            .points
            .iter()
            .zip(&self.point_obj)
            .filter(|(_, &o)| self.object_masses_kg.get(o as usize).is_some_and(|&m| m == 0.0))
            .map(|(&p, _)| p)
            .collect();
        // The barrier's DOF-space gradient, in total and per unit κ of each measured key, per
        // DOF block (`None`: no pair reaches the block).
        let n_blocks = gradient.len() / 3;
        let mut barrier_total: Vec<Option<Vector3<f64>>> = vec![None; n_blocks];
        let mut per_unit: Vec<Vec<Option<Vector3<f64>>>> = vec![vec![None; n_blocks]; keys.len()];
        let mut slope_sum = vec![0.0; keys.len()];
        let mut slope_count = vec![0usize; keys.len()];
        for (e, (p, &d)) in self.pairs.iter().zip(&distances).enumerate() {
            if w == 4 {
                blocks.copy_from_slice(&p.nodes);
            } else {
                element_blocks(&node_maps(&p.nodes, state), &mut blocks);
            }
            let out = &gradients[3 * w * e..3 * w * (e + 1)];
            let key = keys
                .binary_search(&sorted_objects(p.objects))
                .ok()
                .filter(|_| d < 0.9 * p.dhat);
            for (k, &b) in blocks.iter().enumerate() {
                if b == NO_DOF {
                    continue;
                }
                let g = Vector3::new(out[3 * k], out[1 + 3 * k], out[2 + 3 * k]);
                *barrier_total[b as usize].get_or_insert_with(Vector3::zeros) += g;
                if kinematic.contains(&b) {
                    continue;
                }
                if let Some(i) = key {
                    *per_unit[i][b as usize].get_or_insert_with(Vector3::zeros) += g / p.kappa;
                }
            }
            if let Some(i) = key {
                slope_sum[i] += barrier(kind, d, p.dhat).1.abs();
                slope_count[i] += 1;
            }
        }
        let other = |b: u32| {
            let i = 3 * b as usize;
            Vector3::new(gradient[i], gradient[i + 1], gradient[i + 2])
                - barrier_total[b as usize].expect("a pair's block")
        };
        // Least squares: the stiffnesses whose barrier forces best cancel everything else.
        let n = keys.len();
        let mut a = nalgebra::DMatrix::<f64>::zeros(n, n);
        let mut r = nalgebra::DVector::<f64>::zeros(n);
        for i in 0..n {
            for (b, g) in per_unit[i].iter().enumerate() {
                let Some(g) = g else { continue };
                r[i] -= g.dot(&other(b as u32));
                for j in 0..n {
                    if let Some(h) = &per_unit[j][b] {
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
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_box_corner_carries_its_weight_at_half_the_activation_distance() {
        // A 1 kg cube of side 0.1 m: the effective mass at a corner, averaged over normals, is
        // 1/(1 + 3) kg (I = m s²/6); four corners carry the weight. With the gravity term alone
        // the barrier force at d̂/2 is the corner mass times g.
        let mut s = PairStiffness::default();
        s.resize(2);
        let dhat = 2e-3;
        s.initialize(None, &[0.25, 0.0], |_, _| dhat, 1e9, 9.81, BarrierKind::Log);
        let k = s.get(0, 1);
        assert_eq!(k, s.get(1, 0));
        let force = k * barrier(BarrierKind::Log, 0.5 * dhat, dhat).1.abs();
        assert!((force / (0.25 * 9.81) - 1.0).abs() < 1e-6, "{force}");
        // Kinematic pairs get a value; set pairs keep theirs; stiffening is bounded.
        assert!(s.get(1, 1) > 0.0 && !s.needs_initialization());
        s.stiffen(0, 1, 3.0);
        s.stiffen(0, 1, 3.0);
        assert!((s.get(1, 0) / k - 3.0).abs() < 1e-12);
        s.resize(3);
        assert_eq!(s.get(0, 1), 3.0 * k);
        assert!(s.needs_initialization());
        s.initialize(Some(7.0), &[0.25, 0.0, 1.0], |_, _| dhat, 1e9, 9.81, BarrierKind::Log);
        assert_eq!((s.get(0, 1), s.get(2, 0), s.get(2, 2)), (3.0 * k, 7.0, 7.0));
    }

    #[test]
    fn object_masses_ignore_kinematic_points() {
        let m = object_contact_masses(2, &[0, 1, 2, 3], &[0, 0, 1, 1], &[1.0, 3.0, 0.0, 0.0]);
        assert_eq!(m, vec![2.0, 0.0]);
    }
}
