//! Contact as a solver term: elements, their derivatives in the DOF layout, and the step hooks.

use super::friction_lag::NO_FRICTION;
use super::pairs::{pair_derivatives, pair_energy};
use super::Contact;
use super::PairHessian;
use crate::energy::kinematics::{
    element_blocks, map_element, write_deformable_element, write_deformable_element_in_slots, MapProjection, NodeMap,
};
use crate::energy::potential::deterministic_sum;
use crate::energy::term::{element_stride, NO_DOF};
use crate::energy::Node;
use crate::energy::{EnergyTerm, EvalMode, HyperDual, Scalar, StepCheck, Vec3};
use crate::error::Result;
use crate::state::EvalState;
use rayon::prelude::*;

/// How the nodes of a pair (padded with `NO_DOF`) depend on the DOFs.
pub(super) fn node_maps<'s>(nodes: &[u32; 4], state: &'s EvalState) -> [NodeMap<'s>; 4] {
    nodes.map(|i| {
        if i == NO_DOF {
            NodeMap::Fixed
        } else {
            Node::Point(i).map(state)
        }
    })
}

impl EnergyTerm for Contact {
    fn name(&self) -> &str {
        "contact"
    }
    fn num_elements(&self) -> usize {
        // The pairs (each with the friction element on its nodes, if any), then the friction
        // elements no pair carries.
        self.pairs.len() + self.lone_friction.len()
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
        let w = self.stencil_width(state);
        if w == 4 {
            let all = self.pairs.iter().map(|p| p.nodes).chain(
                self.lone_friction
                    .iter()
                    .map(|&f| self.friction_elements[f as usize].nodes),
            );
            for (o, nodes) in out.chunks_exact_mut(w).zip(all) {
                o.copy_from_slice(&nodes);
            }
            return;
        }
        // Through rigid bodies' maps: in parallel (a serial pass over the towel's 114k elements).
        let blocks = |o: &mut [u32], nodes: &[u32; 4]| {
            element_blocks(&node_maps(nodes, state), o);
        };
        let (pair_out, lone_out) = out.split_at_mut(self.pairs.len() * w);
        pair_out
            .par_chunks_exact_mut(w)
            .zip(self.pairs.par_iter())
            .with_min_len(256)
            .for_each(|(o, p)| blocks(o, &p.nodes));
        lone_out
            .par_chunks_exact_mut(w)
            .zip(self.lone_friction.par_iter())
            .with_min_len(256)
            .for_each(|(o, &f)| blocks(o, &self.friction_elements[f as usize].nodes));
    }
    fn topology_version(&self) -> u64 {
        self.version
    }
    fn energy(&self, state: &EvalState) -> f64 {
        let kind = self.settings.barrier;
        // In parallel, in a fixed order (the towel's 55k pairs and friction elements were the
        // line search's one serial sweep).
        let barrier_energy = deterministic_sum(self.pairs.len(), |i| {
            let p = &self.pairs[i];
            pair_energy(
                p,
                &Self::stencil_x(&p.nodes, state.x).map(|q| Vec3::<f64>::constant(&q)),
                p.kappa * p.multiplicity,
                kind,
            )
        });
        let friction_energy = deterministic_sum(self.friction_elements.len(), |i| {
            let f = &self.friction_elements[i];
            f.energy(&Self::stencil_x(&f.nodes, state.x).map(|q| Vec3::<f64>::constant(&q)))
        });
        barrier_energy + friction_energy
    }
    fn evaluate_element(&self, e: usize, state: &EvalState, mode: EvalMode, out: &mut [f64]) {
        self.evaluate_contact_element(e, state, mode, true, out);
    }
    fn before_step(&mut self, state: &EvalState) {
        // The last step's candidates serve while they cover the positions, unless objects,
        // thicknesses or enabled pairs changed since.
        let config = self.candidate_config();
        if config != self.candidate_config {
            self.candidate_cache = None;
            self.candidate_config = config;
        }
        self.rigid_split = self.split_rigid(state);
        self.validity_record = (0, 0, 0.0);
        self.definite_projected = false;
        if self.relag_pending {
            self.relag_pending = false;
        } else {
            self.lag_solves = 1;
            let pairs = self.detect(state.x);
            self.lag_friction(&pairs, state.x, state.x, state.dt);
        }
        self.version += 1;
    }
    fn accept_iterate(&mut self, from: &EvalState, to: &EvalState) {
        // Friction's dual variables follow the step (`friction`'s primal–dual Hessian).
        // In parallel: each element's dual is its own (the towel's 57k were a serial pass).
        self.friction_elements
            .par_iter_mut()
            .with_min_len(256)
            .for_each(|f| f.update_dual(&Self::stencil_x(&f.nodes, from.x), &Self::stencil_x(&f.nodes, to.x)));
    }
    fn save_iterate(&mut self) {
        self.saved_duals.clear();
        self.saved_duals.extend(self.friction_elements.iter().map(|f| f.dual));
    }
    fn restore_iterate(&mut self) {
        for (f, &w) in self.friction_elements.iter_mut().zip(&self.saved_duals) {
            f.dual = w;
        }
    }
    fn use_definite_hessian(&mut self, on: bool) -> bool {
        let changed =
            self.definite_barriers != on && self.settings.hessian != PairHessian::Exact && !self.pairs.is_empty();
        self.definite_barriers = on;
        changed
    }
    fn tighten_definite_form(&mut self) -> bool {
        let changed = !self.definite_projected
            && matches!(self.settings.hessian, PairHessian::Adaptive | PairHessian::GaussNewton)
            && !self.pairs.is_empty();
        self.definite_projected = true;
        changed
    }
    fn has_definite_form(&self) -> bool {
        // Friction elements on rigid bodies map their Hessians with the form too.
        self.settings.hessian != PairHessian::Exact && self.num_elements() > 0
    }
    fn prepare_evaluation(&mut self, state: &EvalState) {
        let pairs = self.detect(state.x);
        // One pass over both lists: whether the stencils (the friction matching's input) and
        // the kinds (with them, the layout's) stayed.
        let (same_stencils, same_kinds) = if pairs.len() == self.pairs.len() {
            pairs
                .iter()
                .zip(&self.pairs)
                .fold((true, true), |(nodes, kinds), (p, q)| {
                    (nodes && p.nodes == q.nodes, kinds && p.kind == q.kind)
                })
        } else {
            (false, false)
        };
        if !(same_stencils && same_kinds) {
            self.version += 1;
        }
        self.pairs = pairs;
        self.stats.active_pairs = self.pairs.len();
        if !same_stencils {
            self.match_friction();
        }
    }
    fn rebalance(&mut self, state: &EvalState, gradient: &[f64]) -> bool {
        self.rebalance_stiffness(state, gradient)
    }
    fn max_step_fraction(&mut self, from: &EvalState, to: &EvalState) -> f64 {
        if self.objects.is_empty() {
            return 1.0;
        }
        let cached = self.candidate_cache.take();
        let candidates = self.candidates_for(cached, from.x, to.x);
        let (alpha, queries) = if self.settings.ccd {
            self.ccd_fraction(&candidates, from.x, to.x)
        } else {
            (1.0, 0)
        };
        self.candidate_cache = Some(candidates);
        self.ccd_record = (alpha, queries);
        alpha
    }
    fn is_valid_state(&mut self, state: &EvalState) -> bool {
        if self.rigid_split.is_empty() {
            return true;
        }
        let t0 = std::time::Instant::now();
        let valid = !self.rigid_pairs_intersect(state.x);
        let r = &mut self.validity_record;
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
        let (fraction, queries) = self.ccd_record;
        self.stats.min_ccd_fraction = fraction;
        self.stats.ccd_queries = queries;
        let (checks, rejected, seconds) = self.validity_record;
        self.stats.validity_checks = checks;
        self.stats.invalid_trials = rejected;
        self.stats.validity_time_s = seconds;
    }
}

impl Contact {
    /// Element `e`'s derivatives in the DOF layout (see `EnergyTerm::evaluate_element`); a
    /// pair's with its friction element's only if `with_friction` (the stiffness balance reads
    /// the barriers' gradients alone).
    pub(super) fn evaluate_contact_element(
        &self,
        e: usize,
        state: &EvalState,
        mode: EvalMode,
        with_friction: bool,
        out: &mut [f64],
    ) {
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
        } else if self.definite_projected {
            PairHessian::Projected
        } else {
            self.settings.hessian
        };
        let nodes = if e < self.pairs.len() {
            let p = &self.pairs[e];
            let x = Self::stencil_x(&p.nodes, state.x);
            pair_derivatives(p, &x, p.kappa * p.multiplicity, self.settings.barrier, hessian, &mut d);
            let f = self.pair_friction[e];
            if with_friction && f != NO_FRICTION {
                self.friction_elements[f as usize].add_derivatives(&x, &mut d);
            }
            p.nodes
        } else {
            let f = &self.friction_elements[self.lone_friction[e - self.pairs.len()] as usize];
            f.derivatives(&Self::stencil_x(&f.nodes, state.x), &mut d);
            f.nodes
        };
        if out.len() == element_stride(4) {
            write_deformable_element(&d, state.dt, out);
        } else {
            let maps = node_maps(&nodes, state);
            if maps.iter().all(|m| matches!(m, NodeMap::Free { .. } | NodeMap::Fixed)) {
                // No rigid node (e.g. towel–towel pairs in a scene with bodies): the map is
                // `dt·I` per node, written straight into the wider layout.
                let mut next = 0;
                let slots = maps.map(|m| {
                    matches!(m, NodeMap::Free { .. }).then(|| {
                        next += 1;
                        next - 1
                    })
                });
                write_deformable_element_in_slots(&d, &slots, state.dt, out);
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
}
