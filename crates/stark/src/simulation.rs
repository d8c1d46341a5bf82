//! The simulation: state, models, the step loop with adaptive time stepping, events and output.

use crate::contact::{Contact, ContactStats};
use crate::deformables::{Deformables, NodeSetHandle};
use crate::energy::kinematics::{apply_kinematic_map, BodyPose};
use crate::energy::user_energy::{self, UserEnergyTerm};
use crate::energy::{EnergyTerm, Node, StepCheck};
use crate::error::{Result, StarkError};
// Upward on purpose: the simulation owns its frame/log writer and its checkpoints, and
// io::output and io::checkpoint read `&Simulation` (a pair that is one unit in two files).
use crate::io::output::Output;
use crate::rigidbodies::{commit_bodies, RigidBodies};
use crate::settings::Settings;
use crate::solver::newton::{self, ConvergedBy, NewtonFailure, NewtonReport, NewtonWorkspace, PhaseTimes, StepProblem};
use crate::state::{dof_blocks, BodyArrays, EvalState, NodeArrays, NO_BODY};
use nalgebra::Vector3;
use serde::Serialize;
use std::time::Instant;

/// A scripted action run before every step whose end time lies in `[start_s, end_s)`.
type EventAction = Box<dyn FnMut(&mut Simulation, f64) -> Result<()> + Send>;

struct TimeEvent {
    start_s: f64,
    end_s: f64,
    action: EventAction,
}

/// What a spawn does once: add objects (rigid bodies, deformables) and their interactions.
type SpawnAction = Box<dyn FnOnce(&mut Simulation) -> Result<()> + Send>;

/// Objects added when the simulated time reaches `time_s` ([`Simulation::add_spawn`]).
struct Spawn {
    time_s: f64,
    label: String,
    /// `None` once fired.
    action: Option<SpawnAction>,
}

/// A spawn is due when the simulated time is within this of its time (repeated additions of dt
/// round), s.
const SPAWN_TIME_TOLERANCE_S: f64 = 1e-9;

/// Handle to a user energy of a simulation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, serde::Deserialize)]
pub struct UserEnergyHandle(pub u32);

/// What one accepted time step did (one line of the step log).
#[derive(Clone, Debug, Serialize)]
pub struct StepReport {
    /// Index of the step (from 0).
    pub step: u64,
    /// Time at the end of the step, s.
    pub time_s: f64,
    /// Step size, s.
    pub dt_s: f64,
    /// Newton iterations of the accepted attempt.
    pub newton_iterations: usize,
    /// Force residual reached, N.
    pub residual_n: f64,
    /// Criterion that ended the Newton solve.
    pub converged_by: ConvergedBy,
    /// Line-search energy evaluations.
    pub line_search_evaluations: usize,
    /// CG iterations.
    pub cg_iterations: usize,
    /// Smallest valid step fraction met in the line searches (below 1: CCD limited a step).
    pub min_step_fraction: f64,
    /// Element Hessians were projected (always, or because the exact one was indefinite).
    pub projected: bool,
    /// Attempts repeated because a model hardened a stiffness.
    pub hardening_retries: usize,
    /// Attempts that failed and halved dt.
    pub failed_attempts: usize,
    /// Why each failed attempt failed (empty when none did).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub failure_reasons: Vec<String>,
    /// Newton iterations over all attempts.
    pub total_newton_iterations: usize,
    /// Wall time of the step, s.
    pub wall_time_s: f64,
    /// Wall time per phase over all attempts.
    pub times: PhaseTimes,
    /// Contact statistics (when the scene has contact objects).
    pub contact: Option<ContactStats>,
    /// The accepted attempt's force residual at each Newton iterate, N (not logged).
    #[serde(skip)]
    pub newton_residuals_n: Vec<f64>,
}

/// Totals of a run.
#[derive(Clone, Debug, Default, Serialize, serde::Deserialize)]
#[serde(default)]
pub struct RunSummary {
    /// Simulation name.
    pub scene: String,
    /// Simulated time, s.
    pub simulated_time_s: f64,
    /// Accepted steps.
    pub steps: u64,
    /// Failed attempts (each halved dt).
    pub failed_steps: u64,
    /// Attempts repeated after a stiffness hardening.
    pub hardening_retries: u64,
    /// Newton iterations over all attempts.
    pub newton_iterations: u64,
    /// Newton iterations per accepted step.
    pub newton_iterations_per_step: f64,
    /// CG iterations.
    pub cg_iterations: u64,
    /// Largest residual at which a step was accepted, N.
    pub max_residual_n: f64,
    /// Steps that ended by the step-size criterion rather than the residual.
    pub steps_converged_by_step_size: u64,
    /// Steps that ended above the residual tolerance but within the forces' rounding error
    /// ([`ConvergedBy::Rounding`]).
    #[serde(default)]
    pub steps_at_rounding_floor: u64,
    /// Wall time, s.
    pub wall_time_s: f64,
    /// Wall time per simulated second.
    pub wall_time_per_simulated_s: f64,
    /// Wall time per phase.
    pub times: PhaseTimes,
    /// Frames written.
    pub frames: usize,
    /// Number of nodes (deformable nodes and rigid collision-mesh vertices).
    pub nodes: usize,
    /// Scalar unknowns of the Newton solve: 3 per deformable node, 6 per rigid body (rigid
    /// collision-mesh vertices follow their body and have none).
    #[serde(default)]
    pub unknowns: usize,
    /// Active contact pairs, averaged over the accepted steps.
    pub mean_active_pairs: f64,
    /// Most active contact pairs in an accepted step.
    pub max_active_pairs: usize,
    /// Number of rigid bodies.
    pub rigid_bodies: usize,
    /// Number of joints.
    pub joints: usize,
    /// Largest violation of a hard joint constraint at an accepted step, m.
    pub max_joint_violation_m: f64,
    /// Largest angular violation of a hard joint constraint at an accepted step, rad.
    pub max_joint_violation_rad: f64,
}

/// Result of [`Simulation::state_check`].
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct StateCheck {
    /// The intersecting edge–triangle pairs, described.
    pub intersections: Vec<String>,
    /// Inverted tets.
    pub inverted_tets: usize,
}

/// A simulation: nodes, energies, settings and the time loop.
pub struct Simulation {
    /// Settings (may be changed between steps).
    pub settings: Settings,
    /// All deformable nodes.
    pub nodes: NodeArrays,
    /// Deformable energy models.
    pub deformables: Deformables,
    /// All rigid bodies (start-of-step state).
    pub bodies: BodyArrays,
    /// Rigid-body models: inertia and joints.
    pub rigid_bodies: RigidBodies,
    /// Contact objects, barrier, CCD and friction.
    pub contact: Contact,
    /// Frames and logs.
    pub output: Output,
    custom: Vec<Box<dyn EnergyTerm>>,
    user_energies: Vec<Box<dyn UserEnergyTerm>>,
    time: f64,
    dt: f64,
    events: Vec<TimeEvent>,
    /// In the order added; each fires once.
    spawns: Vec<Spawn>,
    pub(crate) newton: NewtonWorkspace,
    velocities: Vec<Vector3<f64>>,
    scratch_x: Vec<Vector3<f64>>,
    scratch_poses: Vec<BodyPose>,
    pool: Option<rayon::ThreadPool>,
    summary: RunSummary,
    started: bool,
    /// While `run` runs: its end time, so that the last step is shortened to land on it.
    step_end_limit: Option<f64>,
    /// Restored from a checkpoint taken after this many steps: the logs keep their first lines
    /// and the initial frame is not written again.
    resumed_at_step: Option<u64>,
    origin: crate::io::SceneOrigin,
}

/// One attempt at a time step: its size, end time and gravity, and whether it is a run's
/// shortened last step.
struct Attempt {
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
struct StepTally {
    times: PhaseTimes,
    hardening_retries: usize,
    failed_attempts: usize,
    failure_reasons: Vec<String>,
    newton_iterations: usize,
}

/// Every body at rest at its pose in `bodies` (v = ω = 0): the poses the start- and end-of-step
/// hooks see.
fn rest_poses(bodies: &BodyArrays, dt: f64) -> Vec<BodyPose> {
    (0..bodies.len())
        .map(|b| BodyPose::at_rest(bodies.position[b], &bodies.orientation[b], dt))
        .collect()
}

/// The simulation borrowed apart: the energy terms of all models, and the state, scratch
/// buffers and workspaces they are evaluated with (each phase of a step takes what it needs).
struct StepParts<'a> {
    terms: Vec<&'a mut dyn EnergyTerm>,
    settings: &'a Settings,
    nodes: &'a NodeArrays,
    bodies: &'a BodyArrays,
    velocities: &'a mut Vec<Vector3<f64>>,
    scratch_x: &'a mut Vec<Vector3<f64>>,
    scratch_poses: &'a mut Vec<BodyPose>,
    newton: &'a mut NewtonWorkspace,
    pool: &'a Option<rayon::ThreadPool>,
}

impl Simulation {
    /// A new, empty simulation.
    pub fn new(settings: Settings) -> Result<Self> {
        settings.validate()?;
        let pool = if settings.threads > 0 {
            Some(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(settings.threads)
                    .build()
                    .map_err(|e| StarkError::InvalidInput(format!("cannot start {} threads: {e}", settings.threads)))?,
            )
        } else {
            None
        };
        let dt = settings.time_step_s;
        Ok(Simulation {
            summary: RunSummary {
                scene: settings.name.clone(),
                ..Default::default()
            },
            settings,
            nodes: NodeArrays::default(),
            deformables: Deformables::default(),
            bodies: BodyArrays::default(),
            rigid_bodies: RigidBodies::default(),
            contact: Contact::default(),
            output: Output::default(),
            custom: Vec::new(),
            user_energies: Vec::new(),
            time: 0.0,
            dt,
            events: Vec::new(),
            spawns: Vec::new(),
            newton: NewtonWorkspace::default(),
            velocities: Vec::new(),
            scratch_x: Vec::new(),
            scratch_poses: Vec::new(),
            pool,
            started: false,
            step_end_limit: None,
            resumed_at_step: None,
            origin: crate::io::SceneOrigin::Program,
        })
    }

    /// Simulated time, s.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Current time step, s (below `settings.time_step_s` after failures).
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// An independent check of the current state: every edge–triangle intersection among the
    /// contact surfaces (the exact test, not the solver's barrier or CCD) and the number of
    /// inverted tets. `stark run --check` and the tests run it after every step.
    pub fn state_check(&self) -> StateCheck {
        StateCheck {
            intersections: self.contact.find_intersections(&self.nodes.x),
            inverted_tets: self.deformables.tets.potential.count_inverted(&self.nodes.x),
        }
    }

    /// Totals so far.
    pub fn summary(&self) -> &RunSummary {
        &self.summary
    }

    /// Wall time spent in element evaluation and in gathering the global system, s.
    pub fn assembly_timing(&self) -> (f64, f64) {
        self.newton.assembler.timing
    }

    /// Gravity, m/s².
    pub fn gravity(&self) -> Vector3<f64> {
        Vector3::from(self.settings.gravity_m_s2)
    }

    /// Change gravity (takes effect at the next step).
    pub fn set_gravity(&mut self, g: Vector3<f64>) {
        self.settings.gravity_m_s2 = g.into();
    }

    /// Add deformable nodes at `positions` (their rest positions too) as a labelled object.
    pub fn add_nodes(&mut self, label: &str, positions: &[Vector3<f64>]) -> Result<NodeSetHandle> {
        if label.is_empty() || self.deformables.set_by_label(label).is_some() {
            return Err(StarkError::InvalidInput(format!(
                "object label '{label}' is empty or already used"
            )));
        }
        if let Some(i) = positions.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(StarkError::InvalidInput(format!(
                "node {i} of '{label}' has a non-finite position"
            )));
        }
        if positions.is_empty() {
            return Err(StarkError::InvalidInput(format!("object '{label}' has no nodes")));
        }
        let first = self.nodes.push(positions);
        let handle = NodeSetHandle {
            index: self.deformables.sets.len() as u32,
            first: first as u32,
            len: positions.len() as u32,
        };
        self.deformables.sets.push((label.to_string(), handle));
        Ok(handle)
    }

    /// Positions of an object's nodes, m.
    pub fn positions(&self, set: NodeSetHandle) -> &[Vector3<f64>] {
        &self.nodes.x[set.range()]
    }

    /// Velocities of an object's nodes, m/s.
    pub fn velocities(&self, set: NodeSetHandle) -> &[Vector3<f64>] {
        &self.nodes.v[set.range()]
    }

    /// Set the velocity of every node of an object, m/s.
    pub fn set_velocity(&mut self, set: NodeSetHandle, v: Vector3<f64>) {
        for i in set.range() {
            self.nodes.v[i] = v;
        }
    }

    /// Add a user energy term (e.g. a [`PotentialTerm`](crate::energy::PotentialTerm)).
    pub fn add_term(&mut self, term: Box<dyn EnergyTerm>) {
        self.custom.push(term);
    }

    /// Add a user energy with run-time generated derivatives (README "Your own energy"):
    /// `traced` comes from [`trace_element`](crate::energy::trace_element), every element lists
    /// its nodes (deformable nodes, rigid-body mesh vertices or [`Node::Rigid`] points), and
    /// `params` gives one value per name (shared) or one per name and element.
    pub fn add_user_energy(
        &mut self,
        name: &str,
        elements: &[Vec<Node>],
        param_names: Vec<String>,
        params: &[f64],
        traced: crate::energy::symbolic::TracedEnergy,
    ) -> Result<UserEnergyHandle> {
        for (i, el) in elements.iter().enumerate() {
            for node in el {
                let ok = match *node {
                    Node::Point(k) => (k as usize) < self.nodes.len(),
                    Node::Rigid { body, local } => {
                        (body as usize) < self.bodies.len() && local.iter().all(|c| c.is_finite())
                    }
                    Node::AngularVelocity(body) => (body as usize) < self.bodies.len(),
                    Node::World(p) => p.iter().all(|c| c.is_finite()),
                };
                if !ok {
                    return Err(StarkError::InvalidInput(format!(
                        "energy '{name}': element {i} refers to {node:?}, but the simulation has {} nodes and {} bodies",
                        self.nodes.len(),
                        self.bodies.len()
                    )));
                }
            }
        }
        let term = user_energy::user_energy_term(name, elements, param_names, params, traced)?;
        self.user_energies.push(term);
        Ok(UserEnergyHandle(self.user_energies.len() as u32 - 1))
    }

    /// A user energy added with [`Simulation::add_user_energy`].
    pub fn user_energy(&self, h: UserEnergyHandle) -> Result<&dyn UserEnergyTerm> {
        let len = self.user_energies.len();
        self.user_energies
            .get(h.0 as usize)
            .map(|t| &**t)
            .ok_or(StarkError::InvalidHandle {
                kind: "user energy",
                index: h.0 as usize,
                len,
            })
    }

    /// Change a parameter of a user energy (one value, or one per element); takes effect from
    /// the next step.
    pub fn set_user_energy_param(&mut self, h: UserEnergyHandle, name: &str, values: &[f64]) -> Result<()> {
        let len = self.user_energies.len();
        self.user_energies
            .get_mut(h.0 as usize)
            .ok_or(StarkError::InvalidHandle {
                kind: "user energy",
                index: h.0 as usize,
                len,
            })?
            .set_param(name, values)
    }

    /// Run `action(sim, t)` before every step whose end time `t` lies in `[start_s, end_s)`.
    /// Use it to move prescribed targets, ramp parameters or change gravity; `t` is the time the
    /// step is solved for, so targets set for `t` are met at the end of that step.
    pub fn add_time_event(
        &mut self,
        start_s: f64,
        end_s: f64,
        action: impl FnMut(&mut Simulation, f64) -> Result<()> + Send + 'static,
    ) {
        self.events.push(TimeEvent {
            start_s,
            end_s,
            action: Box::new(action),
        });
    }

    /// Add objects during the run: `action(sim)` runs once, when the simulated time first
    /// reaches `time_s` (before the first step when `time_s <= 0`, else right after the step
    /// that reaches it, so they are in that step's frame and logs; spawns due together fire in
    /// the order of their times, then in the order added). Use it to pour balls into a
    /// cup or drop parts on a conveyor: the action adds rigid bodies, deformables, contact
    /// settings and friction as when building a scene, and sets their initial state.
    ///
    /// What it adds must not intersect anything (checked; the run stops with an error naming
    /// the spawn). Checkpoints taken after a spawn restore into a simulation built from the same
    /// scene with the same spawns added: [`Simulation::restore_checkpoint`] fires the spawns due
    /// by the checkpoint's time first, so the action must add the same objects whatever the
    /// state (their state is then restored).
    pub fn add_spawn(
        &mut self,
        time_s: f64,
        label: &str,
        action: impl FnOnce(&mut Simulation) -> Result<()> + Send + 'static,
    ) -> Result<()> {
        if !time_s.is_finite() {
            return Err(StarkError::InvalidInput(format!(
                "spawn '{label}': time_s = {time_s} must be finite"
            )));
        }
        if self.started && time_s < self.time - SPAWN_TIME_TOLERANCE_S {
            return Err(StarkError::InvalidInput(format!(
                "spawn '{label}' at t = {time_s} s is in the past (the simulation is at t = {} s)",
                self.time
            )));
        }
        self.spawns.push(Spawn {
            time_s,
            label: label.to_string(),
            action: Some(Box::new(action)),
        });
        Ok(())
    }

    /// Spawns added with [`Simulation::add_spawn`]: `(time_s, label, fired)`.
    pub fn spawns(&self) -> Vec<(f64, &str, bool)> {
        self.spawns
            .iter()
            .map(|s| (s.time_s, s.label.as_str(), s.action.is_none()))
            .collect()
    }

    /// Fire every spawn due by time `t`, earliest first. `check` tests the new objects for
    /// intersections (off when replaying spawns into a simulation about to be restored).
    fn fire_spawns(&mut self, t: f64, check: bool) -> Result<()> {
        let due = |s: &Spawn| s.action.is_some() && t >= s.time_s - SPAWN_TIME_TOLERANCE_S;
        if !self.spawns.iter().any(due) {
            return Ok(());
        }
        // By time, then in the order added: a replay fires them as the run did.
        let mut order: Vec<usize> = (0..self.spawns.len()).collect();
        order.sort_by(|&a, &b| self.spawns[a].time_s.total_cmp(&self.spawns[b].time_s).then(a.cmp(&b)));
        for k in order {
            if !due(&self.spawns[k]) {
                continue;
            }
            let action = self.spawns[k].action.take().expect("due spawns have their action");
            let (time_s, label) = (self.spawns[k].time_s, self.spawns[k].label.clone());
            let meshes_before = self.output.meshes.len();
            action(self).map_err(|e| StarkError::InvalidInput(format!("spawn '{label}' at t = {time_s} s: {e}")))?;
            // The frames list its meshes from the spawn's time on.
            for m in &mut self.output.meshes[meshes_before..] {
                m.first_time_s = time_s;
            }
            if check {
                let crossings = self.contact.find_intersections(&self.nodes.x);
                if !crossings.is_empty() {
                    return Err(StarkError::InvalidInput(format!(
                        "spawn '{label}' at t = {time_s} s: the objects it added intersect others ({} edge–triangle \
                         pairs), e.g. {}",
                        crossings.len(),
                        crossings[0]
                    )));
                }
            }
        }
        Ok(())
    }

    fn parts(&mut self) -> StepParts<'_> {
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
            pool,
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
            pool,
        }
    }

    fn terms_mut(&mut self) -> Vec<&mut dyn EnergyTerm> {
        self.parts().terms
    }

    fn run_events(&mut self, t_end: f64) -> Result<()> {
        let mut events = std::mem::take(&mut self.events);
        let mut result = Ok(());
        for e in events.iter_mut() {
            if t_end >= e.start_s && t_end < e.end_s {
                result = (e.action)(self, t_end);
                if result.is_err() {
                    break;
                }
            }
        }
        // Events added by events are kept.
        events.append(&mut self.events);
        self.events = events;
        result
    }

    fn start(&mut self) -> Result<()> {
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
            let retry = self.check_attempt(&attempt);
            if !retry.is_empty() {
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
    fn prepare_attempt(&mut self) -> Result<Attempt> {
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
    fn solve_attempt(&mut self, attempt: &Attempt) -> std::result::Result<NewtonReport, NewtonFailure> {
        let StepParts {
            mut terms,
            settings,
            nodes,
            bodies,
            velocities,
            newton,
            pool,
            ..
        } = self.parts();
        let problem = StepProblem {
            nodes,
            bodies,
            dt: attempt.dt,
            time: attempt.t_end,
            gravity: attempt.gravity,
        };
        // Everything parallel in the step (lagged quantities, contact detection, the solve) runs
        // in the simulation's pool, so `threads` bounds it.
        let mut step = || {
            // Lagged quantities are taken at the start of the step (v = 0, x = x0).
            {
                let zeros = vec![Vector3::zeros(); dof_blocks(nodes, bodies)];
                let poses = rest_poses(bodies, attempt.dt);
                let state = attempt.state(nodes, bodies, &zeros, &nodes.x, &poses);
                for t in terms.iter_mut() {
                    t.before_step(&state);
                }
            }
            newton::solve(newton, &mut terms, &problem, velocities, &settings.newton)
        };
        match pool {
            Some(p) => p.install(step),
            None => step(),
        }
    }

    /// Place the nodes and bodies at the converged velocities (into the scratch positions and
    /// poses) and ask every term whether the step is within its tolerances; returns the reasons
    /// to retry it (none when it passes).
    fn check_attempt(&mut self, attempt: &Attempt) -> Vec<String> {
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
    fn commit_attempt(&mut self, attempt: &Attempt) {
        let dt = attempt.dt;
        std::mem::swap(&mut self.nodes.x, &mut self.scratch_x);
        let n_nodes = self.nodes.len();
        for i in 0..n_nodes {
            self.nodes.v[i] = if self.nodes.body[i] == NO_BODY {
                self.velocities[i]
            } else {
                // A rigid node's velocity, for output.
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
    fn fail_attempt(&mut self, attempt: &Attempt, failure: String, tally: &mut StepTally) -> Result<()> {
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
    fn step_report(&self, attempt: &Attempt, report: &NewtonReport, tally: StepTally, wall: Instant) -> StepReport {
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

    fn record(&mut self, r: &StepReport) -> Result<()> {
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
        if self.settings.output.frames && fps > 0.0 && !self.output.meshes.is_empty() {
            while self.time >= self.output.next_frame_time - 1e-9 * self.dt {
                self.write_frame_now()?;
                self.output.next_frame_time += 1.0 / fps;
            }
        }
        self.summary.frames = self.output.frames_written;
        Ok(())
    }

    fn write_frame_now(&mut self) -> Result<()> {
        self.write_frame().map(|_| ())
    }

    /// Write one frame of the current state now, in the settings' format (with VTU, the
    /// `.pvd` lists it at the current time); returns the files written.
    pub fn write_frame(&mut self) -> Result<Vec<std::path::PathBuf>> {
        let dir = self.settings.output.directory.clone();
        let name = self.settings.name.clone();
        match self.settings.output.frame_format {
            crate::solver::FrameFormat::LegacyVtk => {
                let files = self.output.write_frame(&dir, &name, &self.nodes)?;
                self.output.frame_times.push(self.time);
                Ok(files)
            }
            crate::solver::FrameFormat::Vtu => {
                let fields = self.node_fields();
                let x = &self.nodes.x;
                let cells: Vec<_> = self
                    .output
                    .meshes
                    .iter()
                    .map(|m| match &m.cells {
                        crate::io::output::OutputCells::Tets(_) => {
                            self.deformables.tets.potential.cell_fields(&m.label, x)
                        }
                        crate::io::output::OutputCells::Triangles(_) => {
                            self.deformables.triangles.potential.cell_fields(&m.label, x)
                        }
                        _ => None,
                    })
                    .collect();
                self.output
                    .write_frame_vtu(&dir, &name, &self.nodes, self.time, &fields, &cells)
            }
        }
    }

    /// The per-node output fields of the current state: contact force, prescribed, attached.
    pub fn node_fields(&mut self) -> crate::io::fields::NodeFields {
        let n = self.nodes.len();
        let contact_force_n = if self.contact.objects().is_empty() {
            vec![Vector3::zeros(); n]
        } else {
            self.contact.barrier_forces(&self.nodes.x)
        };
        let mut prescribed = vec![false; n];
        for &i in self.deformables.prescribed.potential.prescribed_nodes() {
            prescribed[i as usize] = true;
        }
        let mut attached = vec![false; n];
        let a = &self.deformables.attachments;
        a.point_point
            .potential
            .attached_nodes()
            .chain(a.point_edge.potential.attached_nodes())
            .chain(a.point_triangle.potential.attached_nodes())
            .chain(self.rigid_bodies.attachments.potential.attached_nodes())
            .for_each(|i| attached[i as usize] = true);
        crate::io::fields::NodeFields {
            contact_force_n,
            prescribed,
            attached,
        }
    }

    /// Simulate `duration_s` more seconds.
    pub fn run(&mut self, duration_s: f64) -> Result<RunSummary> {
        self.run_with(duration_s, |_| Ok(()))
    }

    /// Simulate `duration_s` more seconds, calling `callback` before every step.
    pub fn run_with(
        &mut self,
        duration_s: f64,
        mut callback: impl FnMut(&mut Simulation) -> Result<()>,
    ) -> Result<RunSummary> {
        let end = self.time + duration_s;
        self.step_end_limit = Some(end);
        let mut result = Ok(());
        // Stop when less than a thousandth of a step remains (rounding of repeated additions).
        while self.time < end - 1e-3 * self.dt.min(self.settings.time_step_s) {
            result = callback(self).and_then(|()| self.step().map(|_| ()));
            if result.is_err() {
                break;
            }
        }
        self.step_end_limit = None;
        // The logs are flushed also when a step or the callback failed (or was interrupted),
        // so that they hold every accepted step.
        let flushed = self.output.flush();
        result?;
        flushed?;
        Ok(self.summary.clone())
    }

    /// Where the scene came from (set by the scene loaders; [`SceneOrigin::Program`](crate::io::SceneOrigin::Program)
    /// for simulations built in code), recorded in checkpoints.
    pub fn scene_origin(&self) -> &crate::io::SceneOrigin {
        &self.origin
    }

    /// Record where the scene came from (the CLI does, for `stark resume`).
    pub fn set_scene_origin(&mut self, origin: crate::io::SceneOrigin) {
        self.origin = origin;
    }

    /// A hash of the scene's structure: nodes and their rest positions, bodies and their mass
    /// properties, every term's name and element count (contact's active pairs excluded), the
    /// contact objects and the number of time events. A checkpoint restores only into a
    /// simulation of the same hash.
    pub fn scene_hash(&mut self) -> u64 {
        let mut h = crate::io::checkpoint::Fnv::default();
        h.str("stark scene");
        h.u64(self.nodes.len() as u64);
        for (r, b) in self.nodes.rest.iter().zip(&self.nodes.body) {
            r.iter().for_each(|&c| h.f64(c));
            h.u64(u64::from(*b));
        }
        for (label, set) in &self.deformables.sets {
            h.str(label);
            h.u64(u64::from(set.len));
        }
        h.u64(self.bodies.len() as u64);
        for b in 0..self.bodies.len() {
            h.f64(self.bodies.mass[b]);
            self.bodies.inertia_local[b].iter().for_each(|&c| h.f64(c));
        }
        for label in &self.rigid_bodies.labels {
            h.str(label);
        }
        for o in self.contact.objects() {
            h.str(&o.label);
        }
        h.u64(self.events.len() as u64);
        if !self.spawns.is_empty() {
            h.str("spawns");
            for s in &self.spawns {
                h.f64(s.time_s);
                h.str(&s.label);
            }
        }
        for t in self.terms_mut() {
            h.str(t.name());
            // Contact's elements are its active pairs, which change from step to step; the rigid
            // inertia's are the bodies (hashed above; left out so that older checkpoints, whose
            // rigid inertia also held rigid nodes, still match).
            if t.name() != "contact" && t.name() != "rigid body inertia" {
                h.u64(t.num_elements() as u64);
            }
        }
        h.finish()
    }

    /// Write a checkpoint of the current state to `path` (see [`crate::io::checkpoint`]); a run
    /// continued from it with [`Simulation::restore_checkpoint`] repeats this one bit for bit.
    pub fn save_checkpoint(&mut self, path: impl AsRef<std::path::Path>) -> Result<()> {
        let path = path.as_ref();
        // The logs then hold every step the checkpoint counts, whatever happens to the process.
        self.output.flush()?;
        let terms = self
            .terms_mut()
            .into_iter()
            .map(|t| (t.name().to_string(), t.save_state()))
            .collect();
        let state = crate::io::checkpoint::SimulationState {
            nodes: self.nodes.clone(),
            bodies: self.bodies.clone(),
            settings: self.settings.clone(),
            time_s: self.time,
            dt_s: self.dt,
            summary: self.summary.clone(),
            frames_written: self.output.frames_written,
            next_frame_time_s: self.output.next_frame_time,
            frame_times_s: self.output.frame_times.clone(),
            terms,
        };
        let header = crate::io::checkpoint::header(
            self.scene_hash(),
            &self.settings.name,
            self.origin.clone(),
            &self.settings.output.directory,
            self.time,
            self.summary.steps,
        );
        crate::io::checkpoint::write(path, header, &state)
    }

    /// Restore a checkpoint written by [`Simulation::save_checkpoint`] into this simulation,
    /// which must be freshly built from the same scene (with its time events registered again)
    /// and not yet stepped. The settings come back as saved except `threads` and `output`, which
    /// stay this simulation's (so the caller chooses where the continued run writes); the logs
    /// there are cut back to the checkpoint's step and continued, and frames continue numbering.
    pub fn restore_checkpoint(&mut self, path: impl AsRef<std::path::Path>) -> Result<()> {
        let path = path.as_ref();
        let fail = |message: String| StarkError::Checkpoint {
            path: path.display().to_string(),
            message,
        };
        if self.started {
            return Err(fail(
                "a checkpoint restores only into a freshly built simulation that has not stepped yet".into(),
            ));
        }
        // The objects spawned by the checkpoint's time exist before its state is restored.
        if !self.spawns.is_empty() {
            let header = crate::io::checkpoint::read_header(path)?;
            self.fire_spawns(header.time_s, false)?;
        }
        let hash = self.scene_hash();
        let (_, state) = crate::io::checkpoint::read(path, hash, &self.settings.name)?;
        let mut terms = self.terms_mut();
        if terms.len() != state.terms.len() {
            return Err(fail(format!(
                "{} energy terms saved, {} in this simulation",
                state.terms.len(),
                terms.len()
            )));
        }
        for (t, (name, bytes)) in terms.iter_mut().zip(&state.terms) {
            if t.name() != name {
                return Err(fail(format!(
                    "term '{name}' saved where this simulation has '{}'",
                    t.name()
                )));
            }
            t.restore_state(bytes)
                .map_err(|e| fail(format!("term '{name}': {e}")))?;
        }
        drop(terms);
        let keep_threads = self.settings.threads;
        let keep_output = self.settings.output.clone();
        self.settings = state.settings;
        self.settings.threads = keep_threads;
        self.settings.output = keep_output;
        self.nodes = state.nodes;
        self.bodies = state.bodies;
        self.time = state.time_s;
        self.dt = state.dt_s;
        self.summary = state.summary;
        self.output.frames_written = state.frames_written;
        self.output.next_frame_time = state.next_frame_time_s;
        self.output.frame_times = state.frame_times_s;
        self.resumed_at_step = Some(self.summary.steps);
        Ok(())
    }
}
