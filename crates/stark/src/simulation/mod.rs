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

mod events;
mod objects;
mod run;
mod step;

use events::{Spawn, TimeEvent};

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
    /// The factor on the last velocities that gives Newton's initial guess (see
    /// `StepProblem::guess_scale`); part of the checkpointed state.
    guess_scale: f64,
    velocities: Vec<Vector3<f64>>,
    scratch_x: Vec<Vector3<f64>>,
    scratch_poses: Vec<BodyPose>,
    pool: Option<std::sync::Arc<rayon::ThreadPool>>,
    summary: RunSummary,
    started: bool,
    /// While `run` runs: its end time, so that the last step is shortened to land on it.
    step_end_limit: Option<f64>,
    /// Restored from a checkpoint taken after this many steps: the logs keep their first lines
    /// and the initial frame is not written again.
    resumed_at_step: Option<u64>,
    origin: crate::io::SceneOrigin,
}

impl Simulation {
    /// A new, empty simulation.
    pub fn new(settings: Settings) -> Result<Self> {
        settings.validate()?;
        let pool = if settings.threads > 0 {
            Some(std::sync::Arc::new(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(settings.threads)
                    .build()
                    .map_err(|e| StarkError::InvalidInput(format!("cannot start {} threads: {e}", settings.threads)))?,
            ))
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
            guess_scale: 1.0,
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
}
