//! The time step: attempts prepared, solved by Newton, checked, committed and recorded.

use super::*;

/// One attempt at a time step: its size, end time and gravity, and whether it is a run's
/// shortened last step.
pub(super) struct Attempt {
    dt: f64,
    t_end: f64,
    gravity: Vector3<f64>,
    shortened: bool,
}

impl Attempt {
    /// The state the terms evaluate in this attempt, at DOF velocities `v`, node positions `x`
    /// and body poses `poses`.
    fn state<'a>(
        &self,
        nodes: &'a NodeArrays,
        bodies: &'a BodyArrays,
        v: &'a [Vector3<f64>],
        x: &'a [Vector3<f64>],
        poses: &'a [BodyPose],
    ) -> EvalState<'a> {
        EvalState {
            dt: self.dt,
            time: self.t_end,
            gravity: self.gravity,
            nodes,
            v,
            x,
            bodies,
            poses,
        }
    }
}

/// What the attempts of one step add up to, for its report.
#[derive(Default)]
pub(super) struct StepTally {
    times: PhaseTimes,
    hardening_retries: usize,
    failed_attempts: usize,
    failure_reasons: Vec<String>,
    newton_iterations: usize,
}

/// Every body at rest at its pose in `bodies` (v = ω = 0): the poses the start- and end-of-step
/// hooks see.
pub(super) fn rest_poses(bodies: &BodyArrays, dt: f64) -> Vec<BodyPose> {
    (0..bodies.len())
        .map(|b| BodyPose::at_rest(bodies.position[b], &bodies.orientation[b], dt))
        .collect()
}

/// The simulation borrowed apart: the energy terms of all models, and the state, scratch
/// buffers and workspaces they are evaluated with (each phase of a step takes what it needs).
pub(super) struct StepParts<'a> {
    terms: Vec<&'a mut dyn EnergyTerm>,
    settings: &'a Settings,
    nodes: &'a NodeArrays,
    bodies: &'a BodyArrays,
    velocities: &'a mut Vec<Vector3<f64>>,
    scratch_x: &'a mut Vec<Vector3<f64>>,
    scratch_poses: &'a mut Vec<BodyPose>,
    newton: &'a mut NewtonWorkspace,
}

impl Simulation {
    pub(super) fn parts(&mut self) -> StepParts<'_> {
        let Simulation {
            settings,
            nodes,
            bodies,
            deformables,
            rigid_bodies,
            contact,
            custom,
            user_energies,
            newton,
            velocities,
            scratch_x,
            scratch_poses,
            ..
        } = self;
        let mut terms = deformables.terms_mut();
        terms.extend(rigid_bodies.terms_mut());
        terms.push(contact);
        terms.extend(custom.iter_mut().map(|t| &mut **t as &mut dyn EnergyTerm));
        terms.extend(user_energies.iter_mut().map(|t| &mut **t as &mut dyn EnergyTerm));
        StepParts {
            terms,
            settings,
            nodes,
            bodies,
            velocities,
            scratch_x,
            scratch_poses,
            newton,
        }
    }

    pub(super) fn terms_mut(&mut self) -> Vec<&mut dyn EnergyTerm> {
        self.parts().terms
    }

    pub(super) fn start(&mut self) -> Result<()> {
        if self.started {
            return Ok(());
        }
        // Spawns due at the start (a resumed run replayed its spawns when restoring).
        self.fire_spawns(self.time, false)?;
        let crossings = self.contact.find_intersections(&self.nodes.x);
        if !crossings.is_empty() {
            let shown: Vec<_> = crossings.iter().take(5).cloned().collect();
            return Err(StarkError::InvalidInput(format!(
                "the initial state has {} intersecting edge–triangle pairs (objects must start apart): {}{}",
                crossings.len(),
                shown.join("; "),
                if crossings.len() > 5 { "; …" } else { "" }
            )));
        }
        self.started = true;
        let dir = self.settings.output.directory.clone();
        // A resumed run continues the logs of the run it came from, cut back to the checkpoint.
        let keep_lines = self.resumed_at_step;
        if self.settings.output.step_log {
            self.output.open_log_keeping(&dir, &self.settings.name, keep_lines)?;
        }
        self.open_rigid_logs(keep_lines)?;
        if keep_lines.is_some() {
            return Ok(());
        }
        if self.settings.output.frames && self.settings.output.fps > 0.0 && !self.output.meshes.is_empty() {
            self.write_frame_now()?;
            self.output.next_frame_time = 1.0 / self.settings.output.fps;
        }
        Ok(())
    }

    /// Advance by one accepted time step (retrying with a smaller dt or hardened stiffness as
    /// needed). Each attempt is prepared, solved and checked; the first that passes is committed
    /// and recorded.
    pub fn step(&mut self) -> Result<StepReport> {
        // Everything parallel in the step (lagged quantities, contact detection, the solve, the
        // checks and end-of-step updates) runs in the simulation's pool, so `threads` bounds it
        // and no work wakes rayon's global pool.
        self.in_pool(Self::step_in_pool)
    }

    /// Run `f` on the simulation's own thread pool, so that the steps it takes start there
    /// directly instead of each handing over to the pool and waiting for it (a thread wake-up
    /// and a wait per step: 7% of rb_point's CPU samples, its wall within the noise). `stark
    /// run` runs a whole run so. Whatever `f` calls back runs on a pool thread.
    pub fn in_pool<R: Send>(&mut self, f: impl FnOnce(&mut Simulation) -> R + Send) -> R {
        match self.pool.clone() {
            Some(pool) if pool.current_thread_index().is_none() => pool.install(|| f(self)),
            // No pool of its own, or already on it.
            _ => f(self),
        }
    }

    fn step_in_pool(&mut self) -> Result<StepReport> {
        self.start()?;
        let wall = Instant::now();
        let mut tally = StepTally::default();
        loop {
            let attempt = self.prepare_attempt()?;
            let report = match self.solve_attempt(&attempt) {
                Ok(report) => report,
                Err(failure) => {
                    self.fail_attempt(&attempt, failure.to_string(), &mut tally)?;
                    continue;
                }
            };
            tally.times.add(&report.times);
            tally.newton_iterations += report.iterations;
            let checked = Instant::now();
            let retry = self.check_attempt(&attempt);
            if !retry.is_empty() {
                tally.times.step_end_s += checked.elapsed().as_secs_f64();
                tally.hardening_retries += 1;
                self.summary.hardening_retries += 1;
                if tally.hardening_retries > self.settings.max_hardening_retries {
                    return Err(StarkError::StepFailed {
                        time_s: self.time,
                        dt_s: attempt.dt,
                        dt_min_s: self.settings.min_time_step_s,
                        reason: format!("still out of tolerance: {}", retry.join("; ")),
                        no_retry: format!("after {} hardenings, the most allowed", tally.hardening_retries),
                    });
                }
                continue;
            }
            self.commit_attempt(&attempt);
            tally.times.step_end_s += checked.elapsed().as_secs_f64();
            self.fire_spawns(self.time, true)?;
            // A shortened last step leaves dt as it was (the run may continue).
            if self.settings.adaptive_time_step && !attempt.shortened {
                self.dt = (attempt.dt * self.settings.time_step_growth).min(self.settings.time_step_s);
            }
            let step_report = self.step_report(&attempt, &report, tally, wall);
            self.record(&step_report)?;
            return Ok(step_report);
        }
    }

    /// The next attempt's step size and end time, after the events due by then and with the
    /// contact settings and stiffness of that time.
    pub(super) fn prepare_attempt(&mut self) -> Result<Attempt> {
        // The last step of a run is shortened to land on its end time (a step within rounding
        // of the remaining time is taken whole, so that runs split at a step boundary repeat
        // the steps of one run bit for bit).
        let (dt, t_end, shortened) = match self.step_end_limit {
            Some(end) if end - self.time < self.dt * (1.0 - 1e-6) => (end - self.time, end, true),
            _ => (self.dt, self.time + self.dt, false),
        };
        self.run_events(t_end)?;
        self.contact.settings = self.settings.contact.clone();
        if self.contact.needs_stiffness() {
            let mut masses = self.deformables.inertia.node_masses(self.nodes.len());
            RigidBodies::set_node_contact_masses(&self.nodes, &self.bodies, &mut masses);
            let g = self.gravity().norm();
            self.contact.initialize_stiffness(&masses, self.settings.time_step_s, g);
        }
        Ok(Attempt {
            dt,
            t_end,
            gravity: self.gravity(),
            shortened,
        })
    }

    /// Lag the terms' quantities at the start of the step and solve for the end-of-step
    /// velocities with Newton, starting from those the last attempt left in `velocities`.
    pub(super) fn solve_attempt(&mut self, attempt: &Attempt) -> std::result::Result<NewtonReport, NewtonFailure> {
        let guess_scale = self.guess_scale;
        let StepParts {
            mut terms,
            settings,
            nodes,
            bodies,
            velocities,
            newton,
            ..
        } = self.parts();
        let problem = StepProblem {
            nodes,
            bodies,
            dt: attempt.dt,
            time: attempt.t_end,
            gravity: attempt.gravity,
            guess_scale,
        };
        // Lagged quantities are taken at the start of the step (v = 0, x = x0).
        let lagged = Instant::now();
        {
            let zeros = vec![Vector3::zeros(); dof_blocks(nodes, bodies)];
            let poses = rest_poses(bodies, attempt.dt);
            let state = attempt.state(nodes, bodies, &zeros, &nodes.x, &poses);
            for t in terms.iter_mut() {
                t.before_step(&state);
            }
        }
        let step_start_s = lagged.elapsed().as_secs_f64();
        let mut report = newton::solve(newton, &mut terms, &problem, velocities, &settings.newton)?;
        report.times.step_start_s = step_start_s;
        Ok(report)
    }

    /// Place the nodes and bodies at the converged velocities (into the scratch positions and
    /// poses) and ask every term whether the step is within its tolerances; returns the reasons
    /// to retry it (none when it passes).
    pub(super) fn check_attempt(&mut self, attempt: &Attempt) -> Vec<String> {
        let p = self.parts();
        apply_kinematic_map(
            p.nodes,
            p.bodies,
            p.velocities,
            attempt.dt,
            p.scratch_x,
            p.scratch_poses,
        );
        let state = attempt.state(p.nodes, p.bodies, p.velocities, p.scratch_x, p.scratch_poses);
        let mut retry = Vec::new();
        for t in p.terms {
            if let StepCheck::Retry(msg) = t.check_converged_step(&state) {
                retry.push(msg);
            }
        }
        retry
    }

    /// Make the checked attempt the start of the next step: positions and velocities of nodes
    /// and bodies, the time, and what the terms carry over (`after_step`).
    pub(super) fn commit_attempt(&mut self, attempt: &Attempt) {
        let dt = attempt.dt;
        self.guess_scale = hindsight_guess_scale(&self.nodes, &self.bodies, &self.velocities);
        std::mem::swap(&mut self.nodes.x, &mut self.scratch_x);
        let n_nodes = self.nodes.len();
        for i in 0..n_nodes {
            self.nodes.v[i] = if self.nodes.body[i] == NO_BODY {
                self.velocities[i]
            } else {
                // A rigid node's velocity, for output (zero for a fixed node).
                (self.nodes.x[i] - self.scratch_x[i]) / dt
            };
        }
        commit_bodies(&mut self.bodies, &self.velocities, n_nodes, dt);
        self.time = attempt.t_end;
        let p = self.parts();
        let poses = rest_poses(p.bodies, dt);
        let state = attempt.state(p.nodes, p.bodies, p.velocities, &p.nodes.x, &poses);
        for t in p.terms {
            t.after_step(&state);
        }
    }

    /// A failed attempt: halve dt for the next one, or fail the step when dt is fixed or its half
    /// would go below the minimum.
    pub(super) fn fail_attempt(&mut self, attempt: &Attempt, failure: String, tally: &mut StepTally) -> Result<()> {
        let dt = attempt.dt;
        tally.failure_reasons.push(format!("dt {dt:.3e} s: {failure}"));
        tally.failed_attempts += 1;
        self.summary.failed_steps += 1;
        let half = dt * 0.5;
        if !self.settings.adaptive_time_step || half < self.settings.min_time_step_s {
            let no_retry = if self.settings.adaptive_time_step {
                format!(
                    "halving dt would go below the minimum {:e} s",
                    self.settings.min_time_step_s
                )
            } else {
                "the time step is fixed: adaptive_time_step is off".to_string()
            };
            return Err(StarkError::StepFailed {
                time_s: self.time,
                dt_s: dt,
                dt_min_s: self.settings.min_time_step_s,
                reason: failure,
                no_retry,
            });
        }
        self.dt = half;
        Ok(())
    }

    /// The log line of the committed attempt.
    pub(super) fn step_report(
        &self,
        attempt: &Attempt,
        report: &NewtonReport,
        tally: StepTally,
        wall: Instant,
    ) -> StepReport {
        StepReport {
            step: self.summary.steps,
            time_s: self.time,
            dt_s: attempt.dt,
            newton_iterations: report.iterations,
            residual_n: report.residual_n,
            converged_by: report.converged_by,
            line_search_evaluations: report.line_search_evaluations,
            cg_iterations: report.cg_iterations,
            min_step_fraction: report.min_step_fraction,
            projected: report.projected,
            hardening_retries: tally.hardening_retries,
            failed_attempts: tally.failed_attempts,
            failure_reasons: tally.failure_reasons,
            total_newton_iterations: tally.newton_iterations,
            wall_time_s: wall.elapsed().as_secs_f64(),
            times: tally.times,
            contact: (!self.contact.objects().is_empty()).then_some(self.contact.stats),
            newton_residuals_n: report.residuals_n.clone(),
        }
    }

    pub(super) fn record(&mut self, r: &StepReport) -> Result<()> {
        let (violation_m, violation_rad) = self.max_joint_violations();
        let s = &mut self.summary;
        s.rigid_bodies = self.bodies.len();
        s.joints = self.rigid_bodies.named_joints.len();
        s.max_joint_violation_m = s.max_joint_violation_m.max(violation_m);
        s.max_joint_violation_rad = s.max_joint_violation_rad.max(violation_rad);
        s.steps += 1;
        s.simulated_time_s = self.time;
        s.newton_iterations += r.total_newton_iterations as u64;
        s.cg_iterations += r.cg_iterations as u64;
        s.max_residual_n = s.max_residual_n.max(r.residual_n);
        match r.converged_by {
            ConvergedBy::Step => s.steps_converged_by_step_size += 1,
            ConvergedBy::Rounding => s.steps_at_rounding_floor += 1,
            ConvergedBy::Residual => {}
        }
        s.wall_time_s += r.wall_time_s;
        s.times.add(&r.times);
        s.newton_iterations_per_step = s.newton_iterations as f64 / s.steps as f64;
        s.wall_time_per_simulated_s = if self.time > 0.0 {
            s.wall_time_s / self.time
        } else {
            0.0
        };
        s.nodes = self.nodes.len();
        s.unknowns = 3 * crate::state::DofMap::new(&self.nodes, &self.bodies).len();
        if let Some(c) = &r.contact {
            s.mean_active_pairs += (c.active_pairs as f64 - s.mean_active_pairs) / s.steps as f64;
            s.max_active_pairs = s.max_active_pairs.max(c.active_pairs);
        }
        self.output.log(r)?;
        self.write_rigid_logs(r.step)?;
        let fps = self.settings.output.fps;
        let frames_on = self.settings.output.frames && fps > 0.0 && !self.output.meshes.is_empty();
        if frames_on && self.time >= self.output.next_frame_time - 1e-9 * self.dt {
            self.write_frame_now()?;
            // One frame per step: frame times the step passed over (a step longer than the frame
            // interval, or a run resumed with frames from a checkpoint written without) are
            // skipped, not written as copies of this state.
            while self.time >= self.output.next_frame_time - 1e-9 * self.dt {
                self.output.next_frame_time += 1.0 / fps;
            }
        }
        self.summary.frames = self.output.frames_written;
        Ok(())
    }
}

/// The factor `s ∈ [0, 1]` that would have made `s·v₀` the closest guess to this step's solution
/// `v₁` (least squares over the unknowns: `⟨v₁, v₀⟩ / ‖v₀‖²`), used on the next step's guess:
/// near 1 where the motion is smooth (a swinging box), smaller where it turns from step to step
/// (bodies bouncing on contact, a cloth's folds), where the full last velocity overshoots into the
/// barriers. Newton iterations: simple_grasp 358 → 329, twisting_cloth 665 → 610, hanging_cloth
/// 785 → 740, deformable_and_rigid_collisions 618 → 599; hanging_deformable_box, spinning_box_cloth
/// and ten steps of the folded towel unchanged (BENCHMARKS.md).
fn hindsight_guess_scale(nodes: &NodeArrays, bodies: &BodyArrays, solution: &[Vector3<f64>]) -> f64 {
    let mut start = Vec::with_capacity(solution.len());
    crate::state::start_velocities(nodes, bodies, &mut start);
    if start.len() != solution.len() {
        return 1.0;
    }
    let (along, norm_sq) = start
        .iter()
        .zip(solution)
        .fold((0.0, 0.0), |(a, n), (v0, v1)| (a + v0.dot(v1), n + v0.norm_squared()));
    if norm_sq > 0.0 && along.is_finite() {
        (along / norm_sq).clamp(0.0, 1.0)
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::hindsight_guess_scale;
    use crate::energy::term::{EnergyTerm, EvalMode, StepCheck};
    use crate::presets::SurfaceMaterial;
    use crate::state::{BodyArrays, EvalState, NodeArrays};
    use crate::{Settings, Simulation};
    use nalgebra::Vector3;
    use std::sync::{Arc, Mutex};

    /// A term without elements that records the thread count its hooks run with.
    struct ThreadProbe(Arc<Mutex<Vec<(&'static str, usize)>>>);

    impl ThreadProbe {
        fn note(&self, hook: &'static str) {
            self.0.lock().unwrap().push((hook, rayon::current_num_threads()));
        }
    }

    impl EnergyTerm for ThreadProbe {
        fn name(&self) -> &str {
            "thread probe"
        }
        fn num_elements(&self) -> usize {
            0
        }
        fn stencil_width(&self, _state: &EvalState) -> usize {
            1
        }
        fn write_stencils(&self, _state: &EvalState, _out: &mut [u32]) {}
        fn energy(&self, _state: &EvalState) -> f64 {
            0.0
        }
        fn evaluate_element(&self, _e: usize, _state: &EvalState, _mode: EvalMode, _out: &mut [f64]) {}
        fn before_step(&mut self, _state: &EvalState) {
            self.note("before_step");
        }
        fn check_converged_step(&mut self, _state: &EvalState) -> StepCheck {
            self.note("check_converged_step");
            StepCheck::Accept
        }
        fn after_step(&mut self, _state: &EvalState) {
            self.note("after_step");
        }
    }

    /// Every part of a step runs in the simulation's pool (`threads`), not in rayon's global one
    /// (whose size is the machine's core count): three threads asked, three seen everywhere.
    #[test]
    fn the_whole_step_runs_in_the_simulations_pool() {
        let settings = Settings {
            threads: 3,
            ..Default::default()
        };
        let mut sim = Simulation::new(settings).unwrap();
        sim.add_surface_grid("cloth", [1.0, 1.0], [2, 2], &SurfaceMaterial::cotton_fabric())
            .unwrap();
        let seen = Arc::new(Mutex::new(Vec::new()));
        sim.add_term(Box::new(ThreadProbe(seen.clone())));
        sim.step().unwrap();
        let seen = seen.lock().unwrap();
        let hooks: Vec<_> = seen.iter().map(|&(h, _)| h).collect();
        assert_eq!(hooks, ["before_step", "check_converged_step", "after_step"]);
        assert!(seen.iter().all(|&(_, n)| n == 3), "{seen:?}");
    }

    #[test]
    fn the_hindsight_guess_scale_fits_the_last_step() {
        let mut nodes = NodeArrays::default();
        nodes.push(&[Vector3::zeros(), Vector3::zeros()]);
        nodes.v = vec![Vector3::new(1.0, 0.0, 0.0), Vector3::new(0.0, 2.0, 0.0)];
        let bodies = BodyArrays::default();
        let scale = |solution: &[Vector3<f64>]| hindsight_guess_scale(&nodes, &bodies, solution);
        let half: Vec<_> = nodes.v.iter().map(|v| 0.5 * v).collect();
        assert!((scale(&half) - 0.5).abs() < 1e-15);
        // A turn (reversed velocities) gives no guess along the last velocity; faster motion
        // is capped at the full last velocity.
        let reversed: Vec<_> = nodes.v.iter().map(|v| -v).collect();
        assert_eq!(scale(&reversed), 0.0);
        let faster: Vec<_> = nodes.v.iter().map(|v| 3.0 * v).collect();
        assert_eq!(scale(&faster), 1.0);
        // Orthogonal components do not count: only the part along the last velocity.
        let sideways = vec![Vector3::new(0.5, 7.0, 0.0), Vector3::new(-3.0, 1.0, 0.0)];
        assert!((scale(&sideways) - (0.5 + 2.0) / 5.0).abs() < 1e-15);
        // At rest the full (zero) guess.
        nodes.v = vec![Vector3::zeros(); 2];
        assert_eq!(hindsight_guess_scale(&nodes, &bodies, &half), 1.0);
    }
}
