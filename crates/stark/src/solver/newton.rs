//! Newton's method on the end-of-step velocities (DESIGN §2).
//!
//! Each iteration: let terms update their active sets, assemble `E`, `∇E` and the projected
//! Hessian `H`, stop if the force residual `‖∇E‖∞/dt` is below tolerance, solve `H Δv = −∇E`,
//! then line search: the largest step the terms allow (CCD), halved until the Armijo condition
//! holds. The initial guess is the previous velocity, shortened to the largest valid fraction
//! and scaled by the factor that would have fitted the last step best
//! (`StepProblem::guess_scale`).

use super::linear::amg::{Amg, BlockMotion, Interpolation, NearNullSpace};
use super::linear::block_sparse::{dot, norm_inf, Block, BlockSparseMatrix, UpperScratch, UpperTriangle};
use super::linear::cholesky::CholeskySolver;
use super::linear::pcg;
use super::settings::{LinearSolver, NewtonSettings, Projection};
use super::trace;
use crate::energy::assembly::{Assembled, Assembler};
use crate::energy::kinematics::{apply_kinematic_map, BodyPose};
use crate::energy::{EnergyTerm, EvalMode};
use crate::state::{block_kind, dof_blocks, start_velocities, BlockKind, BodyArrays, DofMap, EvalState, NodeArrays};
use nalgebra::Vector3;
use serde::Serialize;
use std::time::Instant;

/// Halvings of the initial guess before it falls back to rest (`v = 0`, always valid).
const MAX_GUESS_HALVINGS: usize = 30;

/// Which criterion ended a Newton solve.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ConvergedBy {
    /// The force residual fell below `residual_tolerance_n`.
    Residual,
    /// The Newton step fell below `step_tolerance_m_s`.
    Step,
    /// The force residual is above `residual_tolerance_n` but within the rounding error of the
    /// forces (positions are known to machine precision times their magnitude, which moves each
    /// force by the stiffness times that much), and no step lowered it further.
    Rounding,
}

/// Wall time spent per phase, s.
#[derive(Clone, Copy, Debug, Default, Serialize, serde::Deserialize)]
pub struct PhaseTimes {
    /// Active-set updates (contact detection) before evaluations.
    pub prepare_s: f64,
    /// Element evaluation, projection and assembly (with the direct solver, the ordering and
    /// symbolic analysis of a new pattern too: they run beside the assembly).
    pub evaluation_s: f64,
    /// Linear solves.
    pub linear_solve_s: f64,
    /// Line search energy evaluations (with the contact narrow phase at each trial state).
    pub line_search_s: f64,
    /// Largest safe step fractions: continuous collision detection (and its broad phase when the
    /// cached candidates no longer cover the step).
    pub ccd_s: f64,
    /// The terms' quantities lagged at the start of each attempt (friction's contact detection
    /// and normal forces), outside Newton.
    #[serde(default)]
    pub step_start_s: f64,
    /// After Newton: the terms' checks of the converged attempt (friction re-lagging), the
    /// commit and the terms' end-of-step updates (not the logs and frames written).
    #[serde(default)]
    pub step_end_s: f64,
}

impl PhaseTimes {
    /// Add another record.
    pub fn add(&mut self, o: &PhaseTimes) {
        self.prepare_s += o.prepare_s;
        self.evaluation_s += o.evaluation_s;
        self.linear_solve_s += o.linear_solve_s;
        self.line_search_s += o.line_search_s;
        self.ccd_s += o.ccd_s;
        self.step_start_s += o.step_start_s;
        self.step_end_s += o.step_end_s;
    }

    /// Sum of all phases, s.
    pub fn total_s(&self) -> f64 {
        self.prepare_s
            + self.evaluation_s
            + self.linear_solve_s
            + self.line_search_s
            + self.ccd_s
            + self.step_start_s
            + self.step_end_s
    }
}

/// What one Newton solve did.
#[derive(Clone, Debug, Serialize)]
pub struct NewtonReport {
    /// Newton iterations (linear solves).
    pub iterations: usize,
    /// Force residual `‖∇E‖∞/dt` at the last evaluation, N.
    pub residual_n: f64,
    /// The criterion that ended the solve.
    pub converged_by: ConvergedBy,
    /// Energy evaluations in line searches.
    pub line_search_evaluations: usize,
    /// Total CG iterations.
    pub cg_iterations: usize,
    /// Smallest step fraction allowed by the terms (CCD) over the solve.
    pub min_step_fraction: f64,
    /// The exact Hessian was not positive definite and projection was switched on.
    pub projected: bool,
    /// Time per phase.
    pub times: PhaseTimes,
    /// The force residual at each iterate, N (convergence order in tests; not logged).
    #[serde(skip)]
    pub residuals_n: Vec<f64>,
}

/// Why a Newton solve failed.
#[derive(Clone, Debug, thiserror::Error)]
pub enum NewtonFailure {
    /// No convergence within the iteration limit.
    #[error("no convergence in {iterations} Newton iterations (residual {residual_n:.3e} N)")]
    MaxIterations {
        /// Iterations performed.
        iterations: usize,
        /// Last residual, N.
        residual_n: f64,
    },
    /// The energy or its gradient is not finite.
    #[error("non-finite energy or gradient in '{0}'")]
    NonFinite(String),
    /// The line search found no acceptable step.
    #[error("line search failed after {evaluations} evaluations (residual {residual_n:.3e} N): {why}")]
    LineSearch {
        /// Energy evaluations.
        evaluations: usize,
        /// Residual, N.
        residual_n: f64,
        /// What the trials showed.
        why: String,
    },
}

/// Memory reused across Newton solves.
#[derive(Default)]
pub struct NewtonWorkspace {
    /// Assembly layout and the global Hessian.
    pub assembler: Assembler,
    cholesky: CholeskySolver,
    /// The multigrid hierarchy (`LinearSolver::Amg`) and its CG counts (see [`amg_solve`]).
    amg: Option<KeptAmg>,
    /// The Hessian's upper block triangle for multigrid CG's products (half the bytes of the
    /// whole matrix: they are memory-bound on the meshes multigrid is for).
    upper: (UpperTriangle<Block>, UpperScratch),
    gradient: Vec<f64>,
    rhs: Vec<f64>,
    step: Vec<f64>,
    x: Vec<Vector3<f64>>,
    poses: Vec<BodyPose>,
    trial_v: Vec<Vector3<f64>>,
    trial_x: Vec<Vector3<f64>>,
    trial_poses: Vec<BodyPose>,
}

/// The fixed data of one step.
pub struct StepProblem<'a> {
    /// Start-of-step nodes.
    pub nodes: &'a NodeArrays,
    /// Start-of-step rigid bodies.
    pub bodies: &'a BodyArrays,
    /// Time step, s.
    pub dt: f64,
    /// End-of-step time, s.
    pub time: f64,
    /// Gravity, m/s².
    pub gravity: Vector3<f64>,
    /// Newton's initial guess is the start-of-step velocities shortened to the largest valid
    /// fraction, times this factor in `[0, 1]`.
    pub guess_scale: f64,
}

impl StepProblem<'_> {
    fn state<'s>(&'s self, v: &'s [Vector3<f64>], x: &'s [Vector3<f64>], poses: &'s [BodyPose]) -> EvalState<'s> {
        EvalState {
            dt: self.dt,
            time: self.time,
            gravity: self.gravity,
            nodes: self.nodes,
            v,
            x,
            bodies: self.bodies,
            poses,
        }
    }

    fn place(&self, v: &[Vector3<f64>], x: &mut Vec<Vector3<f64>>, poses: &mut Vec<BodyPose>) {
        apply_kinematic_map(self.nodes, self.bodies, v, self.dt, x, poses);
    }
}

/// The force residual (N) that rounding alone can leave: positions are known to about
/// `1e-14·extent_m` (machine precision times their magnitude, a few operations deep), which moves
/// the gradient (DOF space) by the matrix (`∂²E/∂v²`, so the position error divided by dt) times
/// that much, and the residual is the gradient over dt. Takes the largest absolute row sum.
fn residual_rounding_floor(matrix: &crate::solver::linear::BlockSparseMatrix, extent_m: f64, dt: f64) -> f64 {
    let mut row_max = 0.0f64;
    for r in 0..matrix.n_blocks {
        let mut sums = [0.0f64; 3];
        for b in &matrix.values[matrix.row_start[r]..matrix.row_start[r + 1]] {
            for (i, sum) in sums.iter_mut().enumerate() {
                *sum += b[3 * i].abs() + b[3 * i + 1].abs() + b[3 * i + 2].abs();
            }
        }
        row_max = sums.iter().copied().fold(row_max, f64::max);
    }
    1e-14 * extent_m * row_max / (dt * dt)
}

/// A line search's assembly at its trial `state` (the next iteration's if the trial is accepted):
/// first the forces' rounding floor of the current iterate's matrix, which it overwrites. Its
/// time counts as evaluation (`in_line_search_s` keeps it out of the line search's).
#[allow(clippy::too_many_arguments)]
fn assemble_trial(
    assembler: &mut Assembler,
    cholesky: Option<&mut CholeskySolver>,
    gradient: &mut [f64],
    terms: &[&mut dyn EnergyTerm],
    state: &EvalState,
    dofs: &DofMap,
    mode: EvalMode,
    floor: &mut Option<f64>,
    extent_m: f64,
    times: &mut PhaseTimes,
    in_line_search_s: &mut f64,
) -> Assembled {
    floor.get_or_insert_with(|| residual_rounding_floor(&assembler.matrix, extent_m, state.dt));
    let t = Instant::now();
    let shared: Vec<&dyn EnergyTerm> = terms.iter().map(|t| &**t as &dyn EnergyTerm).collect();
    let done = assemble_beside_analysis(assembler, cholesky, &shared, state, dofs, mode, gradient);
    let seconds = t.elapsed().as_secs_f64();
    times.evaluation_s += seconds;
    *in_line_search_s += seconds;
    done
}

/// Assemble all terms at `state`. With a Cholesky solver whose next solve must order or analyse
/// the assembly's pattern first, that runs beside the assembly (it reads the pattern alone):
/// serial work that a second thread absorbs (a folded towel's pattern grows about five times a
/// step, ~30 ms of analysis each). At one thread the analysis simply comes first; its result is
/// the same at any thread count.
fn assemble_beside_analysis(
    assembler: &mut Assembler,
    cholesky: Option<&mut CholeskySolver>,
    terms: &[&dyn EnergyTerm],
    state: &EvalState,
    dofs: &DofMap,
    mode: EvalMode,
    gradient: &mut [f64],
) -> Assembled {
    if let Some(cholesky) = cholesky {
        assembler.prepare_layout(terms, state, dofs);
        let id = assembler.pattern_id;
        if cholesky.needs_analysis(id) {
            let pattern = assembler.matrix.pattern_only();
            let (_, done) = rayon::join(
                // An analysis that fails here fails again in the solve, which reports it.
                || cholesky.prepare(&pattern, id),
                || assembler.assemble(terms, state, dofs, mode, gradient),
            );
            return done;
        }
    }
    assembler.assemble(terms, state, dofs, mode, gradient)
}

fn total_energy(terms: &[&mut dyn EnergyTerm], state: &EvalState) -> f64 {
    terms.iter().map(|t| t.energy(state)).sum()
}

fn max_step(terms: &mut [&mut dyn EnergyTerm], from: &EvalState, to: &EvalState) -> f64 {
    terms
        .iter_mut()
        .map(|t| t.max_step_fraction(from, to))
        .fold(1.0, f64::min)
}

/// `out = base + alpha·step`: `step` is over the unknowns, `base` and `out` over all DOF blocks
/// (the blocks that are not unknowns keep their value, zero).
fn axpy_velocities(dofs: &DofMap, base: &[Vector3<f64>], step: &[f64], alpha: f64, out: &mut Vec<Vector3<f64>>) {
    out.clear();
    out.extend_from_slice(base);
    for (d, &block) in dofs.block_of_dof.iter().enumerate() {
        out[block as usize] += Vector3::new(step[3 * d], step[3 * d + 1], step[3 * d + 2]) * alpha;
    }
}

impl NewtonWorkspace {
    /// What the linear solver keeps from step to step (a multigrid hierarchy's interpolation
    /// and CG counts), for a checkpoint: empty when nothing is kept.
    pub fn save_kept_preconditioner(&self) -> Vec<u8> {
        let Some(k) = &self.amg else {
            return Vec::new();
        };
        let saved = SavedAmg {
            interpolation: k.amg.interpolation(),
            first_cg: k.first_cg as u64,
            last_cg: k.last_cg as u64,
            age_steps: k.age_steps as u64,
        };
        postcard::to_allocvec(&saved).expect("a multigrid interpolation encodes")
    }

    /// Restore what [`NewtonWorkspace::save_kept_preconditioner`] saved (nothing when empty):
    /// the next solves then decide and compute as the run that saved it.
    pub fn restore_kept_preconditioner(&mut self, bytes: &[u8]) -> Result<(), String> {
        self.amg = None;
        if bytes.is_empty() {
            return Ok(());
        }
        let saved: SavedAmg =
            postcard::from_bytes(bytes).map_err(|e| format!("the multigrid hierarchy does not decode: {e}"))?;
        self.amg = Some(KeptAmg {
            amg: Amg::from_interpolation(saved.interpolation)?,
            first_cg: saved.first_cg as usize,
            last_cg: saved.last_cg as usize,
            age_steps: saved.age_steps as usize,
        });
        Ok(())
    }

    /// The trial state `v + alpha·step` (velocities, positions, poses).
    fn place_trial(&mut self, problem: &StepProblem, dofs: &DofMap, v: &[Vector3<f64>], alpha: f64) {
        axpy_velocities(dofs, v, &self.step, alpha, &mut self.trial_v);
        problem.place(&self.trial_v, &mut self.trial_x, &mut self.trial_poses);
    }
}

/// Newton's globalisation switch for the barriers' definite Hessian form, with its hysteresis:
/// on far from the solution; off once a step is taken in full (the quadratic model is trusted
/// there) and the residual is below where the switch was last forced on; on again after a step
/// cut below a quarter (it jumped across a regime change).
struct FarFromSolution {
    on: bool,
    /// Residual above which the switch stays on, N (infinite: no such bound).
    hold_above_n: f64,
    /// Full steps taken since the switch was forced on.
    held_full_steps: usize,
}

/// Full steps after which a forced definite form is given up even above its residual bound: the
/// definite form only bounds the barriers' negative curvature, and where the solution needs it
/// Newton on the definite model circles at a constant residual (a soft box under a block: 38
/// iterations between 0.3 and 1.3 N, two nodes taking turns).
const MAX_HELD_FULL_STEPS: usize = 3;

impl FarFromSolution {
    fn new(on: bool) -> Self {
        Self {
            on,
            hold_above_n: f64::INFINITY,
            held_full_steps: 0,
        }
    }

    /// On, until a full step at a residual below `residual_n` (or a few full steps).
    fn hold_until_residual(&mut self, residual_n: f64) {
        self.on = true;
        self.hold_above_n = residual_n;
        self.held_full_steps = 0;
    }

    /// After a step of fraction `alpha` accepted at `residual_n`: whether the switch flipped.
    fn after_step(&mut self, alpha: f64, residual_n: f64) -> bool {
        let next = self.next(alpha, residual_n);
        if self.on && alpha >= 1.0 && self.hold_above_n.is_finite() {
            self.held_full_steps += 1;
        }
        let flipped = next != self.on;
        self.on = next;
        flipped
    }

    /// The switch after a step of fraction `alpha` accepted at `residual_n`.
    fn next(&self, alpha: f64, residual_n: f64) -> bool {
        if self.on {
            let held = self.held_full_steps + (alpha >= 1.0 && self.hold_above_n.is_finite()) as usize;
            alpha < 1.0 || (residual_n >= self.hold_above_n && held < MAX_HELD_FULL_STEPS)
        } else {
            alpha < 0.25
        }
    }
}

/// The longest multiple of the Newton step an extrapolation along a concave direction tries (10
/// folded-towel steps: 145, 139, 138, 140 Newton iterations with 4, 16, 64, 1024).
const MAX_EXTRAPOLATION: f64 = 16.0;

/// A Newton step cut below this fraction (by CCD or the line search) counts as cut short.
const CUT_STEP_FRACTION: f64 = 0.25;
/// After this many steps under the definite form cut short in one time step, the terms take
/// their closer definite form (`EnergyTerm::tighten_definite_form`) for the rest of it. The
/// barriers' Gauss–Newton form drops the distance's curvature term `κ b' ∇²d`, negligible
/// against the normal stiffness but not against a soft body's: a heavy box landing on a soft one
/// (deformable_and_rigid_collisions, ~3e3 N on a corner node) has a geometric stiffness ~F/L far
/// above the rubber's, and the directions it gives overshoot into CCD cuts step after step (67
/// Newton iterations in one step, 690 in the scene; 17 and 620 with this. spinning_box_cloth
/// 2084 → 2076; twisting_cloth, simple_grasp, franka_cup and the towel cases unchanged).
/// Not after full steps that raised the residual (a folded towel's layers leaving an unstable
/// configuration): the projected form saves a few iterations there (156 → 146 in 10 fold steps)
/// but costs ~57k eigen-decompositions per assembly, 7% of the wall time (BENCHMARKS.md).
const TIGHTEN_AFTER_CUT_STEPS: usize = 2;

/// Ask the terms for their closer definite form (`EnergyTerm::tighten_definite_form`); whether
/// any assembles something different now.
fn tighten_definite_forms(terms: &mut [&mut dyn EnergyTerm]) -> bool {
    let mut changed = false;
    for t in terms.iter_mut() {
        changed |= t.tighten_definite_form();
    }
    changed
}

/// Relative tolerance of CG preconditioned by the step's factorisation, and of a fresh
/// single-precision factor's refinement (tightening as `min(this, r/r₀)`: the Newton iterations
/// keep converging as with exact directions).
const REUSE_RELATIVE_TOLERANCE: f64 = 1e-3;

/// The residual norm at which the direct solver's CG (a reuse of the step's factor, or a fresh
/// factor's refinement) may stop: Newton's forcing term `min(1e-3, r/r₀)` of the gradient's norm,
/// not below a tenth of the force tolerance (`residual_n` and `first_residual_n` in N).
fn direct_solve_tolerance(
    gradient: &[f64],
    residual_n: f64,
    first_residual_n: f64,
    settings: &NewtonSettings,
    dt: f64,
) -> f64 {
    let eta = REUSE_RELATIVE_TOLERANCE.min(residual_n / first_residual_n);
    (eta * dot(gradient, gradient).sqrt()).max(0.1 * settings.residual_tolerance_n * dt)
}
/// CG iterations preconditioned by the step's factorisation before it is refreshed. Each costs
/// two triangular solves, which stream the whole factor; a factorisation costs about seven of
/// them (17k unknowns, 3.3M factor entries: ~12 ms against ~87 ms), so beyond this a fresh
/// factor is cheaper (with 25, a folded towel's solves spent 30% of the run in triangular
/// solves, most in reuses that then failed).
const REUSE_MAX_CG: usize = 8;
/// The factor is reused only once the residual fell below this fraction of the step's first:
/// before, the Hessian still moves too much (on a folded towel under the robot, 10 steps: 20 of
/// 21 attempts above it failed after 8 CG iterations each, 28 of 31 below it succeeded).
const REUSE_BELOW_RELATIVE_RESIDUAL: f64 = 1e-2;

/// CG iterations a kept multigrid hierarchy is always allowed (beyond twice what it needed
/// fresh).
const AMG_KEPT_MIN_CG: usize = 20;

/// Steps after the one that built a multigrid hierarchy whose first solves keep its
/// interpolation (aggregates and prolongators) and recompute only what depends on the matrix
/// (the levels' Galerkin matrices and smoothers): ~30 ms instead of ~90 on a 128² cloth. The
/// interpolation follows the cloth's rotations only where it was built: after more steps it
/// preconditions worse than a new one costs (on the whole hanging_cloth_128 run, kept for ever:
/// 6930 CG iterations against 5886 with a new hierarchy each step; kept three steps: 5857).
const AMG_RELEVEL_STEPS: usize = 3;

/// A kept hierarchy whose last solve needed more than this factor times the CG iterations of
/// its first (after it was built or its levels recomputed) has its levels recomputed before the
/// next solve: its coarse matrices are those of a Hessian that has since moved (on a 128² cloth
/// the count climbs from 7 to 20 within a step; recomputed, back to 7–10).
const AMG_RELEVEL_GROWTH: f64 = 1.25;

/// The near-null space of the unknowns for multigrid: their rigid motions at the iterate
/// (nodes, bodies' centres of mass and spins).
fn rigid_motions_of_unknowns(dofs: &DofMap, n_nodes: usize, x: &[Vector3<f64>], poses: &[BodyPose]) -> NearNullSpace {
    let motions: Vec<BlockMotion> = dofs
        .block_of_dof
        .iter()
        .map(|&b| match block_kind(n_nodes, b as usize) {
            BlockKind::Node(i) => BlockMotion::Point(x[i].into()),
            BlockKind::Linear(body) => BlockMotion::Point(poses[body].t.into()),
            BlockKind::Angular(_) => BlockMotion::Angular,
        })
        .collect();
    NearNullSpace::rigid_motions(&motions)
}

/// A multigrid-preconditioned CG solve, and the CG iterations of an attempt with a kept
/// hierarchy that was given up.
struct AmgSolve {
    cg: pcg::CgInfo,
    retried_cg: usize,
}

/// What a multigrid solve does to the hierarchy before CG.
#[derive(Clone, Copy, PartialEq, Eq)]
enum AmgRefresh {
    /// Keep it, refit the finest smoother to the matrix.
    Finest,
    /// Keep the interpolation, recompute the levels' matrices and smoothers.
    Levels,
    /// Build a new one.
    New,
}

/// CG preconditioned by multigrid. A hierarchy serves later Hessians of the same unknowns: at
/// later Newton iterations of a step with its finest smoother refitted, at the first solves of
/// the next [`AMG_RELEVEL_STEPS`] steps (and when CG's count has grown by
/// [`AMG_RELEVEL_GROWTH`]) with its levels recomputed, else anew; a kept one that needs more than
/// twice the iterations of its first solve is replaced at once. Every decision depends on the
/// CG counts alone (the same at any thread count), and checkpoints hold the interpolation and
/// the counts ([`NewtonWorkspace::save_kept_preconditioner`]), so a resumed run is the same run.
#[allow(clippy::too_many_arguments)]
fn amg_solve(
    kept: &mut Option<KeptAmg>,
    upper: &mut (UpperTriangle<Block>, UpperScratch),
    matrix: &BlockSparseMatrix,
    rhs: &[f64],
    step: &mut [f64],
    tol: f64,
    new_step: bool,
    settings: &NewtonSettings,
    motions: impl Fn() -> NearNullSpace,
    trace: bool,
) -> AmgSolve {
    let mut refresh = match kept.as_ref().filter(|k| k.amg.fits(matrix)) {
        None => AmgRefresh::New,
        Some(k) if new_step && k.age_steps >= AMG_RELEVEL_STEPS => AmgRefresh::New,
        Some(k) if new_step || k.last_cg as f64 > AMG_RELEVEL_GROWTH * k.first_cg as f64 => AmgRefresh::Levels,
        Some(_) => AmgRefresh::Finest,
    };
    let mut retried_cg = 0;
    let (upper, scratch) = upper;
    upper.refill(matrix);
    loop {
        let t_build = Instant::now();
        if refresh == AmgRefresh::New {
            *kept = Some(KeptAmg {
                amg: Amg::with_near_null_space(matrix, motions()),
                first_cg: 0,
                last_cg: 0,
                age_steps: 0,
            });
        }
        let k = kept.as_mut().expect("hierarchy built");
        match refresh {
            AmgRefresh::Levels => k.amg.refresh_levels(matrix),
            AmgRefresh::Finest => k.amg.refresh_finest(matrix),
            AmgRefresh::New => {}
        }
        if new_step && refresh == AmgRefresh::Levels {
            k.age_steps += 1;
        }
        let build_s = t_build.elapsed().as_secs_f64();
        let t_cg = Instant::now();
        let max_cg = if refresh == AmgRefresh::New {
            settings.cg_max_iterations
        } else {
            settings.cg_max_iterations.min((2 * k.first_cg).max(AMG_KEPT_MIN_CG))
        };
        let amg = &mut k.amg;
        let cg = pcg::solve_with_product(
            &mut |p, ap| upper.product_dot(p, ap, scratch),
            rhs,
            step,
            tol,
            max_cg,
            &mut |r, z| amg.precondition(matrix, r, z),
        );
        if refresh != AmgRefresh::Finest {
            k.first_cg = cg.iterations;
        }
        k.last_cg = cg.iterations;
        if trace {
            eprintln!(
                "  amg ({} hierarchy, levels {:?}, {build_s:.4} s): {} CG iterations in {:.4} s",
                match refresh {
                    AmgRefresh::New => "new",
                    AmgRefresh::Levels => "relevelled",
                    AmgRefresh::Finest => "kept",
                },
                k.amg.shape(matrix).blocks,
                cg.iterations,
                t_cg.elapsed().as_secs_f64()
            );
        }
        // Negative curvature is the matrix's, whatever the preconditioner.
        if cg.converged || cg.indefinite || refresh == AmgRefresh::New {
            return AmgSolve { cg, retried_cg };
        }
        retried_cg += cg.iterations;
        refresh = AmgRefresh::New;
    }
}

/// A kept hierarchy as a checkpoint holds it.
#[derive(Serialize, serde::Deserialize)]
struct SavedAmg {
    interpolation: Interpolation,
    first_cg: u64,
    last_cg: u64,
    age_steps: u64,
}

/// A multigrid hierarchy kept across Newton iterations and steps.
struct KeptAmg {
    amg: Amg,
    /// CG iterations of the first solve after the hierarchy was built or its levels recomputed.
    first_cg: usize,
    /// CG iterations of the last solve.
    last_cg: usize,
    /// Steps whose first solve recomputed its levels since it was built.
    age_steps: usize,
}

/// Solve one step: on success `v` holds the end-of-step velocities.
pub fn solve(
    ws: &mut NewtonWorkspace,
    terms: &mut [&mut dyn EnergyTerm],
    problem: &StepProblem,
    v: &mut Vec<Vector3<f64>>,
    settings: &NewtonSettings,
) -> Result<NewtonReport, NewtonFailure> {
    let n = dof_blocks(problem.nodes, problem.bodies);
    let dofs = DofMap::new(problem.nodes, problem.bodies);
    let dt = problem.dt;
    let mut project = settings.projection == Projection::Always;
    ws.gradient.resize(3 * dofs.len(), 0.0);
    ws.rhs.resize(3 * dofs.len(), 0.0);
    ws.step.resize(3 * dofs.len(), 0.0);
    let mut report = NewtonReport {
        iterations: 0,
        residual_n: f64::INFINITY,
        converged_by: ConvergedBy::Residual,
        line_search_evaluations: 0,
        cg_iterations: 0,
        min_step_fraction: 1.0,
        projected: settings.projection == Projection::Always,
        times: PhaseTimes::default(),
        residuals_n: Vec::new(),
    };

    // Initial guess: the previous velocity, as far along it as is valid from rest (v = 0 keeps
    // every node at x0, which is always valid), times the hindsight factor (a shorter guess on
    // the same chord stays valid). CCD checks the chord from x0; rigid points move on arcs, so
    // the guess is also halved until the terms accept it (`is_valid_state`).
    v.clear();
    v.resize(n, Vector3::zeros());
    problem.place(v, &mut ws.x, &mut ws.poses);
    start_velocities(problem.nodes, problem.bodies, &mut ws.trial_v);
    problem.place(&ws.trial_v, &mut ws.trial_x, &mut ws.trial_poses);
    {
        let t0 = Instant::now();
        let from = problem.state(v, &ws.x, &ws.poses);
        let to = problem.state(&ws.trial_v, &ws.trial_x, &ws.trial_poses);
        let mut alpha = max_step(terms, &from, &to) * problem.guess_scale;
        let start = std::mem::take(&mut ws.trial_v);
        for halving in 0..=MAX_GUESS_HALVINGS {
            if halving == MAX_GUESS_HALVINGS {
                alpha = 0.0;
            }
            for (vi, v0) in v.iter_mut().zip(&start) {
                *vi = v0 * alpha;
            }
            if alpha == 0.0 {
                break;
            }
            problem.place(v, &mut ws.trial_x, &mut ws.trial_poses);
            let guess = problem.state(v, &ws.trial_x, &ws.trial_poses);
            if terms.iter_mut().all(|t| t.is_valid_state(&guess)) {
                break;
            }
            alpha *= 0.5;
        }
        ws.trial_v = start;
        report.times.ccd_s += t0.elapsed().as_secs_f64();
    }

    // Far from the solution (until a step is taken in full) the positive semi-definite forms of
    // the Hessians that are indefinite near their active set (contact barriers).
    let mut definite = FarFromSolution::new(settings.definite_far_from_solution);
    // Steps under the definite form cut below `CUT_STEP_FRACTION` in this time step.
    let mut cut_definite_steps = 0usize;
    // The residual before the last step if it was a full one under the definite form, and
    // whether the one after it is higher (the definite model underestimates how far the iterate
    // must go; kept across a re-assembly after a failed factorisation).
    let mut full_definite_step_from: Option<f64> = None;
    let mut rising;
    for t in terms.iter_mut() {
        t.use_definite_hessian(definite.on);
    }
    // Diagnostics on stderr: one line per iteration, and which terms rose at a cut step.
    let trace = std::env::var_os("STARK_NEWTON_TRACE").is_some();
    let mut first_residual: Option<f64> = None;
    let mut rebalanced = false;
    // A Cholesky factorisation of this step's Hessian exists, made with the Hessian forms in use
    // now (a switch of the barriers' form or of projection changes the Hessian far
    // more than an iteration does: a fresh factor then).
    let mut factor_reusable = false;
    // The last attempt to reuse it failed: the Hessian moves fast, factorise directly once.
    let mut reuse_failed = false;
    // The step's Hessian pattern, and so the Cholesky ordering, depends on this step alone.
    ws.assembler.exact_pattern_next = true;
    ws.cholesky.fresh_ordering_next = true;
    // The assembly of the current iterate, when the line search already made it (a step
    // accepted by its residual, below).
    let mut assembled: Option<Assembled> = None;
    // The terms were last prepared (contact pairs detected) at the current iterate: the line
    // search prepares each trial, the accepted one included.
    let mut prepared = false;
    // The line search assembles its first trial (value, gradient and Hessian) instead of only
    // evaluating its energy while the last line search accepted its first trial: an accepted
    // trial's assembly is the next iteration's, which saves the energy evaluation. The trial
    // is accepted tentatively before (friction's duals follow the accepted iterates and enter
    // the Hessian), and restored when the line search goes on.
    let mut speculating = true;
    // Diagnostics: the DOF block of the residual's largest entry.
    let mut residual_at = String::new();
    for iteration in 0..settings.max_iterations {
        problem.place(v, &mut ws.x, &mut ws.poses);
        let t0 = Instant::now();
        if !std::mem::take(&mut prepared) {
            let state = problem.state(v, &ws.x, &ws.poses);
            for t in terms.iter_mut() {
                t.prepare_evaluation(&state);
            }
        }
        report.times.prepare_s += t0.elapsed().as_secs_f64();
        let mut descent;
        let mut residual;
        let mut energy;
        let mut sums: Assembled;
        let mut r0;
        loop {
            let t1 = Instant::now();
            let state = problem.state(v, &ws.x, &ws.poses);
            let shared: Vec<&dyn EnergyTerm> = terms.iter().map(|t| &**t as &dyn EnergyTerm).collect();
            let mode = if project {
                EvalMode::ProjectedHessian
            } else {
                EvalMode::ExactHessian
            };
            sums = match assembled.take() {
                Some(done) => done,
                None => assemble_beside_analysis(
                    &mut ws.assembler,
                    (settings.linear_solver == LinearSolver::Cholesky).then_some(&mut ws.cholesky),
                    &shared,
                    &state,
                    &dofs,
                    mode,
                    &mut ws.gradient,
                ),
            };
            energy = sums.energy;
            report.times.evaluation_s += t1.elapsed().as_secs_f64();
            if !energy.is_finite() || ws.gradient.iter().any(|g| !g.is_finite()) {
                let culprit = shared
                    .iter()
                    .find(|t| !t.energy(&state).is_finite())
                    .map(|t| t.name().to_string());
                return Err(NewtonFailure::NonFinite(culprit.unwrap_or_else(|| "gradient".into())));
            }
            drop(shared);
            if iteration == 0 && !rebalanced {
                // Once per step: terms may re-scale to balance the loads (barrier stiffness).
                rebalanced = true;
                // Terms read the gradient per DOF block.
                let mut block_gradient = vec![0.0; 3 * n];
                for (d, &block) in dofs.block_of_dof.iter().enumerate() {
                    block_gradient[3 * block as usize..][..3].copy_from_slice(&ws.gradient[3 * d..][..3]);
                }
                let mut changed = false;
                for t in terms.iter_mut() {
                    changed |= t.rebalance(&state, &block_gradient);
                }
                if changed {
                    continue;
                }
            }
            residual = norm_inf(&ws.gradient) / dt;
            rising = full_definite_step_from.is_some_and(|before| residual > before);
            report.residual_n = residual;
            report.iterations = iteration;
            if residual < settings.residual_tolerance_n {
                report.residuals_n.push(residual);
                if trace {
                    eprintln!("done it {iteration} res {residual:.3e}");
                }
                report.converged_by = ConvergedBy::Residual;
                return Ok(report);
            }
            r0 = *first_residual.get_or_insert(residual);
            if trace {
                residual_at = trace::largest_entry(&ws.gradient, &dofs, problem.nodes.len());
                if std::env::var_os("STARK_TRACE_TERMS").is_some() {
                    let shared: Vec<&dyn EnergyTerm> = terms.iter().map(|t| &**t as &dyn EnergyTerm).collect();
                    trace::print_term_forces(&shared, &state, &dofs, &ws.gradient, dt);
                }
            }

            // Newton direction.
            let t2 = Instant::now();
            for (r, g) in ws.rhs.iter_mut().zip(&ws.gradient) {
                *r = -g;
            }
            let matrix = &ws.assembler.matrix;
            let mut solved = false;
            let mut indefinite = false;
            if settings.linear_solver == LinearSolver::Cholesky {
                // After the step's first iteration, the step's factorisation preconditions CG: a
                // few triangular solves instead of a factorisation, while the Hessian stays near
                // the factorised one (a fresh factor when CG needs more; every step starts with a
                // fresh one, so a run resumed at a step is the same run).
                if iteration > 0
                    && factor_reusable
                    && !std::mem::take(&mut reuse_failed)
                    && residual < REUSE_BELOW_RELATIVE_RESIDUAL * r0
                {
                    let tol = direct_solve_tolerance(&ws.gradient, residual, r0, settings, dt);
                    let cholesky = &mut ws.cholesky;
                    let info =
                        pcg::solve_preconditioned(matrix, &ws.rhs, &mut ws.step, tol, REUSE_MAX_CG, &mut |r, z| {
                            if !cholesky.apply_last_factor(r, z) {
                                z.copy_from_slice(r);
                            }
                        });
                    report.cg_iterations += info.iterations;
                    solved = info.converged && !info.indefinite;
                    reuse_failed = !solved;
                    if trace {
                        eprintln!(
                            "  reused factor: {} CG iterations, {} in {:.3} s",
                            info.iterations,
                            if solved { "solved" } else { "failed" },
                            t2.elapsed().as_secs_f64()
                        );
                    }
                }
                if !solved {
                    let t_factor = Instant::now();
                    // The single-precision factor's refinement stops where a reuse's CG does:
                    // an inexact Newton direction (Eisenstat–Walker), each refinement iteration
                    // two triangular solves that stream the whole factor.
                    let tol = direct_solve_tolerance(&ws.gradient, residual, r0, settings, dt);
                    solved = ws
                        .cholesky
                        .solve(
                            matrix,
                            ws.assembler.pattern_id,
                            &ws.rhs,
                            &mut ws.step,
                            definite.on || project,
                            tol,
                        )
                        .is_ok();
                    if trace {
                        eprintln!(
                            "  factorised: {} factor entries in {:.3} s ({} refinement iterations)",
                            ws.cholesky.factor_len(),
                            t_factor.elapsed().as_secs_f64(),
                            ws.cholesky.refine_iterations
                        );
                    }
                    report.cg_iterations += ws.cholesky.refine_iterations;
                    indefinite = !solved;
                    factor_reusable = solved;
                }
            }
            // A failed factorisation of an unprojected Hessian means "project"; otherwise use CG.
            if !solved && (!indefinite || project) {
                let g_norm = dot(&ws.gradient, &ws.gradient).sqrt();
                let eta = settings.cg_relative_tolerance.min((residual / r0).sqrt());
                let tol = (eta * g_norm).max(0.1 * settings.residual_tolerance_n * dt);
                let info = if settings.linear_solver == LinearSolver::Amg {
                    let fresh = iteration == 0;
                    let motions = || rigid_motions_of_unknowns(&dofs, problem.nodes.len(), &ws.x, &ws.poses);
                    let info = amg_solve(
                        &mut ws.amg,
                        &mut ws.upper,
                        matrix,
                        &ws.rhs,
                        &mut ws.step,
                        tol,
                        fresh,
                        settings,
                        motions,
                        trace,
                    );
                    report.cg_iterations += info.retried_cg;
                    info.cg
                } else {
                    pcg::solve(matrix, &ws.rhs, &mut ws.step, tol, settings.cg_max_iterations)
                };
                report.cg_iterations += info.iterations;
                indefinite = info.indefinite;
            }
            descent = dot(&ws.gradient, &ws.step);
            let usable = descent < 0.0 && ws.step.iter().all(|s| s.is_finite());
            report.times.linear_solve_s += t2.elapsed().as_secs_f64();
            if !project && (indefinite || !usable) {
                if !definite.on {
                    // The exact barrier Hessians may make it indefinite here (their curvature is
                    // not held by the inertia yet): back to their positive semi-definite form,
                    // and the exact ones again once the residual fell tenfold from here (each
                    // failed attempt costs an assembly and a solve). Only if some term has such
                    // a form; otherwise the indefiniteness is another term's.
                    definite.hold_until_residual(0.1 * residual);
                    let mut changed = false;
                    for t in terms.iter_mut() {
                        changed |= t.use_definite_hessian(true);
                    }
                    if changed {
                        continue;
                    }
                }
                // The Hessian is not positive definite here: project from now on.
                project = true;
                report.projected = true;
                continue;
            }
            if !usable {
                // Not a descent direction even projected (no mass, quasistatic): fall back to
                // block-Jacobi preconditioned steepest descent.
                let inv = pcg::block_jacobi(matrix);
                for (b, m) in inv.iter().enumerate() {
                    for i in 0..3 {
                        ws.step[3 * b + i] = -(0..3).map(|j| m[3 * i + j] * ws.gradient[3 * b + j]).sum::<f64>();
                    }
                }
                descent = dot(&ws.gradient, &ws.step);
            }
            report.residuals_n.push(residual);
            break;
        }
        let t_ccd = Instant::now();

        // Line search.
        ws.place_trial(problem, &dofs, v, 1.0);
        let mut alpha = {
            let from = problem.state(v, &ws.x, &ws.poses);
            let to = problem.state(&ws.trial_v, &ws.trial_x, &ws.trial_poses);
            max_step(terms, &from, &to)
        };
        report.times.ccd_s += t_ccd.elapsed().as_secs_f64();
        let t3 = Instant::now();
        if trace && alpha < 1.0 {
            eprintln!("  CCD bounds the step at {alpha:.3e}");
        }
        // Each term's energy at the iterate, to name the terms that rise at a cut step.
        let term_energies: Vec<f64> = if trace {
            let here = problem.state(v, &ws.x, &ws.poses);
            terms.iter().map(|t| t.energy(&here)).collect()
        } else {
            Vec::new()
        };
        report.min_step_fraction = report.min_step_fraction.min(alpha);
        // Below this the energy difference is rounding noise.
        let noise = 1e-13 * sums.energy_abs;
        // A decrease this small is below what the total energy can resolve: its rounding error
        // grows with the element energies' magnitudes and with the element forces times the
        // positions' rounding (|x| ε), and the line search's energy is summed by other code than
        // the assembly's. There the step is judged by the force residual instead, so that any
        // tolerance stays reachable (stiff joints, small dt).
        let extent_m = ws.x.iter().map(|p| p.amax()).fold(1.0, f64::max);
        let resolvable = 1e-12 * sums.energy_abs + 1e-14 * extent_m * sums.gradient_abs / dt;
        let mode = if project {
            EvalMode::ProjectedHessian
        } else {
            EvalMode::ExactHessian
        };
        let mut accepted = false;
        let mut accepted_energy = f64::NAN;
        let mut first_trial_accepted = false;
        let mut evaluation_in_line_search_s = 0.0;
        // The forces' rounding floor at the current iterate, taken before an assembly in the
        // line search overwrites its matrix.
        let mut floor_n: Option<f64> = None;
        // The terms accepted the current trial tentatively (its assembly was speculative).
        let mut tentative = false;
        // A step this short ends the solve once accepted: nothing would use its assembly.
        let last_step = settings.step_tolerance_m_s > 0.0 && norm_inf(&ws.step) < settings.step_tolerance_m_s;
        // Nor one after which the Hessians change form (the assembly would be stale): the
        // barriers' definite form, or the projection released with it.
        let form_changes = settings.definite_far_from_solution && {
            let next = definite.next(alpha, residual);
            next != definite.on
                && (terms.iter().any(|t| t.has_definite_form())
                    || (!next && project && settings.projection == Projection::OnDemand))
        };
        // Nor the last iteration allowed (nothing would use it).
        let last_allowed = iteration + 1 == settings.max_iterations;
        let mut speculate = speculating && !(last_step || form_changes || last_allowed);
        // The assembly of the trial just evaluated, when it was assembled.
        let mut speculative: Option<Assembled>;
        let mut trial_residual = f64::NAN;
        // The trial energy closest to the current one (how far apart they stay as α → 0).
        let mut closest = f64::INFINITY;
        for trial_index in 0..settings.max_line_search_iterations {
            ws.place_trial(problem, &dofs, v, alpha);
            {
                let trial = problem.state(&ws.trial_v, &ws.trial_x, &ws.trial_poses);
                if !terms.iter_mut().all(|t| t.is_valid_state(&trial)) {
                    // A rigid point left its chord and crossed a surface (see `is_valid_state`).
                    report.line_search_evaluations += 1;
                    alpha *= 0.5;
                    continue;
                }
                for t in terms.iter_mut() {
                    t.prepare_evaluation(&trial);
                }
            }
            let trial = problem.state(&ws.trial_v, &ws.trial_x, &ws.trial_poses);
            let e = if std::mem::take(&mut speculate) {
                let from = problem.state(v, &ws.x, &ws.poses);
                for t in terms.iter_mut() {
                    t.save_iterate();
                    t.accept_iterate(&from, &trial);
                }
                tentative = true;
                let done = assemble_trial(
                    &mut ws.assembler,
                    (settings.linear_solver == LinearSolver::Cholesky).then_some(&mut ws.cholesky),
                    &mut ws.gradient,
                    terms,
                    &trial,
                    &dofs,
                    mode,
                    &mut floor_n,
                    extent_m,
                    &mut report.times,
                    &mut evaluation_in_line_search_s,
                );
                let e = done.energy;
                speculative = Some(done);
                e
            } else {
                speculative = None;
                total_energy(terms, &trial)
            };
            report.line_search_evaluations += 1;
            closest = closest.min((e - energy).abs());
            // The expected decrease is below the energy's rounding error: the energy cannot
            // tell a better state from a worse one (accepting "no increase beyond the noise"
            // lets the iterate wander: by ~1e-9 m along a stiff barrier, i.e. 1e-4 N).
            let unresolvable = -alpha * descent < resolvable;
            let armijo = e <= energy + settings.armijo * alpha * descent + noise;
            if trace && !armijo {
                let here = problem.state(v, &ws.x, &ws.poses);
                let cut = trace::Cut {
                    alpha,
                    energy_change: e - energy,
                    model_change: alpha * descent,
                    term_energies: &term_energies,
                    mode,
                };
                cut.print(terms, &here, &trial, &dofs, &ws.step);
            }
            if e.is_finite() && armijo && (!unresolvable || e < energy - resolvable) {
                accepted_energy = e;
                accepted = true;
                first_trial_accepted = trial_index == 0;
                assembled = speculative.take();
                break;
            }
            if e.is_finite() && unresolvable && e - energy < resolvable {
                // Round-off regime: accept the step if it lowers the force residual. Its
                // assembly is the next iteration's (the direction is solved already, so the
                // gradient and matrix may be overwritten).
                let done = match speculative.take() {
                    Some(done) => done,
                    None => assemble_trial(
                        &mut ws.assembler,
                        (settings.linear_solver == LinearSolver::Cholesky).then_some(&mut ws.cholesky),
                        &mut ws.gradient,
                        terms,
                        &trial,
                        &dofs,
                        mode,
                        &mut floor_n,
                        extent_m,
                        &mut report.times,
                        &mut evaluation_in_line_search_s,
                    ),
                };
                trial_residual = norm_inf(&ws.gradient) / dt;
                if done.energy.is_finite() && trial_residual < residual {
                    assembled = Some(done);
                    accepted = true;
                    first_trial_accepted = trial_index == 0;
                    break;
                }
            }
            if std::mem::take(&mut tentative) {
                for t in terms.iter_mut() {
                    t.restore_iterate();
                }
            }
            alpha *= 0.5;
        }
        report.times.line_search_s += t3.elapsed().as_secs_f64() - evaluation_in_line_search_s;
        // Once a first trial was cut in this step, the step's line searches only evaluate
        // energies (a cut speculative trial costs an assembly for nothing).
        speculating &= first_trial_accepted;
        if !accepted {
            let floor_n = floor_n.unwrap_or_else(|| residual_rounding_floor(&ws.assembler.matrix, extent_m, dt));
            if residual < floor_n {
                report.converged_by = ConvergedBy::Rounding;
                return Ok(report);
            }
            let why = if trial_residual.is_nan() {
                format!(
                    "no step along the Newton direction lowered the energy ({closest:.1e} J from it at best, \
                     more than its rounding error {resolvable:.1e} J: the direction is not a descent direction)"
                )
            } else {
                format!(
                    "in the energy's rounding error the residual did not decrease (last trial {trial_residual:.3e} N), \
                     and it is above the forces' rounding error {floor_n:.1e} N"
                )
            };
            return Err(NewtonFailure::LineSearch {
                evaluations: report.line_search_evaluations,
                residual_n: residual,
                why,
            });
        }
        if accepted && alpha == 1.0 && definite.on && rising && accepted_energy - energy < descent {
            // The full step lowered the energy by more than its slope promised: the energy curves
            // downwards along it, and the last full step raised the residual. The iterate is
            // leaving an unstable configuration (a folded towel's layers), whose negative
            // curvature the definite model does not see: its steps grow only geometrically (by
            // ~1.15 per iteration there). Go further along the step, doubling, while the energy
            // keeps falling and CCD allows the whole segment.
            let t_extrapolate = Instant::now();
            let mut best = (1.0, accepted_energy);
            let mut prepared_elsewhere = false;
            let mut a = 2.0;
            while a <= MAX_EXTRAPOLATION {
                ws.place_trial(problem, &dofs, v, a);
                let from = problem.state(v, &ws.x, &ws.poses);
                let to = problem.state(&ws.trial_v, &ws.trial_x, &ws.trial_poses);
                if max_step(terms, &from, &to) < 1.0 || !terms.iter_mut().all(|t| t.is_valid_state(&to)) {
                    break;
                }
                prepared_elsewhere = true;
                for t in terms.iter_mut() {
                    t.prepare_evaluation(&to);
                }
                let e = total_energy(terms, &to);
                report.line_search_evaluations += 1;
                if !(e.is_finite() && e < best.1 + settings.armijo * (a - best.0) * descent) {
                    break;
                }
                best = (a, e);
                a *= 2.0;
            }
            if trace {
                eprintln!(
                    "  extrapolated to {:.0} × the step (ΔE {:.3e} J at 1, {:.3e} J there)",
                    best.0,
                    accepted_energy - energy,
                    best.1 - energy
                );
            }
            alpha = best.0;
            ws.place_trial(problem, &dofs, v, alpha);
            if prepared_elsewhere {
                let to = problem.state(&ws.trial_v, &ws.trial_x, &ws.trial_poses);
                for t in terms.iter_mut() {
                    t.prepare_evaluation(&to);
                }
            }
            if alpha > 1.0 {
                // The speculative assembly, and the terms' tentative acceptance, were the full
                // step's.
                assembled = None;
                if std::mem::take(&mut tentative) {
                    for t in terms.iter_mut() {
                        t.restore_iterate();
                    }
                }
            }
            report.times.line_search_s += t_extrapolate.elapsed().as_secs_f64();
        }
        prepared = true;
        if !tentative {
            // Terms' own unknowns follow the accepted step (friction's dual variables), unless
            // they did already (a speculative assembly there). An assembly the line search made
            // at `to` to judge it by its residual keeps the duals of before: only its Hessian
            // differs, the gradient is exact.
            let from = problem.state(v, &ws.x, &ws.poses);
            let to = problem.state(&ws.trial_v, &ws.trial_x, &ws.trial_poses);
            for t in terms.iter_mut() {
                t.accept_iterate(&from, &to);
            }
        }
        full_definite_step_from = (definite.on && alpha >= 1.0).then_some(residual);
        if definite.on && alpha < CUT_STEP_FRACTION {
            cut_definite_steps += 1;
            if cut_definite_steps == TIGHTEN_AFTER_CUT_STEPS && tighten_definite_forms(terms) {
                factor_reusable = false;
                assembled = None;
            }
        }
        if settings.definite_far_from_solution {
            // A full step: the model is trusted here; the barriers' exact Hessians, once the
            // residual is also below where they last made the Hessian indefinite. An exact
            // step cut below a quarter jumped across a regime change: back to the definite
            // form. The definite form overestimates the curvature that the other energies
            // carry near the solution, and Newton would converge only linearly there (a folded
            // towel under a robot: by 0.69 per iteration).
            if definite.after_step(alpha, residual) {
                factor_reusable = false;
                let was_projected = project;
                if !definite.on && settings.projection == Projection::OnDemand {
                    // An indefinite Hessian far from here says little about here.
                    project = false;
                }
                let mut changed = project != was_projected || terms.iter().any(|t| t.has_definite_form());
                for t in terms.iter_mut() {
                    changed |= t.use_definite_hessian(definite.on);
                }
                if changed {
                    // An assembly made at the accepted trial holds the Hessians' old form.
                    assembled = None;
                }
            }
        }
        if trace {
            // Diagnostics: one line per iteration on stderr (the residual, the accepted step
            // fraction, the Hessians used, the DOF block of the step's largest entry).
            eprintln!(
                "it {iteration:2} res {residual:.3e} at {residual_at} alpha {alpha:.3e} def {} proj {project} ls {} cg {} step {:.3e} at {}",
                definite.on,
                report.line_search_evaluations,
                report.cg_iterations,
                norm_inf(&ws.step),
                trace::largest_entry(&ws.step, &dofs, problem.nodes.len())
            );
        }
        std::mem::swap(v, &mut ws.trial_v);
        report.iterations = iteration + 1;
        // (An extrapolated step moved further than `ws.step`.)
        if settings.step_tolerance_m_s > 0.0 && alpha <= 1.0 && norm_inf(&ws.step) < settings.step_tolerance_m_s {
            report.converged_by = ConvergedBy::Step;
            return Ok(report);
        }
    }
    Err(NewtonFailure::MaxIterations {
        iterations: settings.max_iterations,
        residual_n: report.residual_n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::term::element_stride;
    use std::sync::Mutex;

    /// `½‖v − target‖²` on one node, admissible only while `v.x ≤ limit`; records the largest
    /// `v.x` of every state it was evaluated or assembled at.
    struct Fenced {
        target: f64,
        limit: f64,
        largest_evaluated: Mutex<f64>,
        rejected: Mutex<usize>,
    }

    impl Fenced {
        fn seen(&self, state: &EvalState) {
            let mut m = self.largest_evaluated.lock().unwrap();
            *m = m.max(state.v[0].x);
        }
    }

    impl EnergyTerm for Fenced {
        fn name(&self) -> &str {
            "fenced"
        }
        fn num_elements(&self) -> usize {
            1
        }
        fn stencil_width(&self, _state: &EvalState) -> usize {
            1
        }
        fn write_stencils(&self, _state: &EvalState, out: &mut [u32]) {
            out[0] = 0;
        }
        fn energy(&self, state: &EvalState) -> f64 {
            self.seen(state);
            0.5 * (state.v[0] - Vector3::new(self.target, 0.0, 0.0)).norm_squared()
        }
        fn evaluate_element(&self, _e: usize, state: &EvalState, _mode: EvalMode, out: &mut [f64]) {
            assert_eq!(out.len(), element_stride(1));
            self.seen(state);
            let g = state.v[0] - Vector3::new(self.target, 0.0, 0.0);
            out[0] = 0.5 * g.norm_squared();
            out[1..4].copy_from_slice(g.as_slice());
            out[4..].iter_mut().for_each(|h| *h = 0.0);
            for i in 0..3 {
                out[4 + 4 * i] = 1.0;
            }
        }
        fn is_valid_state(&mut self, state: &EvalState) -> bool {
            let ok = state.v[0].x <= self.limit;
            if !ok {
                *self.rejected.lock().unwrap() += 1;
            }
            ok
        }
    }

    /// The definite-Hessian switch: on at the start it goes off at the first full step; forced
    /// on, it holds until a full step below its residual bound, or for at most
    /// `MAX_HELD_FULL_STEPS` full steps above it; cut steps neither release it nor count.
    #[test]
    fn a_forced_definite_form_is_released_below_its_bound_or_after_a_few_full_steps() {
        let mut far = FarFromSolution::new(true);
        assert!(!far.after_step(0.5, 10.0) && far.on, "a cut step keeps it");
        assert!(far.after_step(1.0, 10.0) && !far.on, "a full step ends it");
        far.hold_until_residual(1.0);
        assert!(far.on);
        assert!(
            far.after_step(1.0, 0.5) && !far.on,
            "a full step below the bound releases it"
        );
        far.hold_until_residual(1.0);
        for _ in 0..5 {
            far.after_step(0.5, 3.0);
        }
        assert!(far.on, "cut steps do not count");
        for k in 1..MAX_HELD_FULL_STEPS {
            far.after_step(1.0, 3.0);
            assert!(far.on, "held after {k} full steps above the bound");
        }
        assert!(
            far.after_step(1.0, 3.0) && !far.on,
            "released after {MAX_HELD_FULL_STEPS}"
        );
        assert!(
            far.after_step(0.2, 3.0) && far.on,
            "a step cut below a quarter switches it on again"
        );
    }

    /// The shape `f(vₓ)` of [`Counting`]'s energy.
    #[derive(Clone, Copy, PartialEq)]
    enum Well {
        /// A quartic well at 1: Newton's full steps are accepted.
        Quartic,
        /// A pseudo-Huber well at 10: Newton's first full step from 0 overshoots by far.
        Huber,
        /// `¼x⁴ − ½x² + c x`: 0 is near the top of a hill between two wells at ±1.
        Hilltop,
    }

    /// One node, `f(vₓ) + ½(v_y² + v_z²)`; counts energy evaluations, assemblies, and the
    /// iterates it accepted (its own state, saved and restored like friction's duals). With a
    /// definite curvature it has a definite form, `max(f″, that)`, which Newton switches on.
    struct Counting {
        well: Well,
        definite_curvature: Option<f64>,
        definite: bool,
        energies: Mutex<usize>,
        assemblies: Mutex<usize>,
        accepted: usize,
        /// The last accepted iterate's vₓ, and accepted steps that did not start there.
        last_to: f64,
        breaks: usize,
        saved: (usize, f64),
    }

    impl Counting {
        fn new(well: Well) -> Self {
            Self {
                well,
                definite_curvature: None,
                definite: false,
                energies: Mutex::new(0),
                assemblies: Mutex::new(0),
                accepted: 0,
                last_to: 0.0,
                breaks: 0,
                saved: (0, 0.0),
            }
        }
        /// `f`, `f′`, `f″`.
        fn f(&self, x: f64) -> [f64; 3] {
            let m = 0.01;
            match self.well {
                Well::Huber => {
                    let d = x - 10.0;
                    let s = (1.0 + d * d).sqrt();
                    [s + 0.5 * m * x * x, d / s + m * x, 1.0 / (s * s * s) + m]
                }
                Well::Quartic => {
                    let d = x - 1.0;
                    [0.25 * d.powi(4) + 0.5 * m * x * x, d.powi(3) + m * x, 3.0 * d * d + m]
                }
                Well::Hilltop => {
                    let c = -1e-3;
                    [
                        0.25 * x.powi(4) - 0.5 * x * x + c * x,
                        x.powi(3) - x + c,
                        3.0 * x * x - 1.0,
                    ]
                }
            }
        }
    }

    impl EnergyTerm for Counting {
        fn name(&self) -> &str {
            "counting"
        }
        fn num_elements(&self) -> usize {
            1
        }
        fn stencil_width(&self, _state: &EvalState) -> usize {
            1
        }
        fn write_stencils(&self, _state: &EvalState, out: &mut [u32]) {
            out[0] = 0;
        }
        fn energy(&self, state: &EvalState) -> f64 {
            *self.energies.lock().unwrap() += 1;
            let v = state.v[0];
            self.f(v.x)[0] + 0.5 * (v.y * v.y + v.z * v.z)
        }
        fn evaluate_element(&self, _e: usize, state: &EvalState, _mode: EvalMode, out: &mut [f64]) {
            *self.assemblies.lock().unwrap() += 1;
            let v = state.v[0];
            let [f, df, ddf] = self.f(v.x);
            out[0] = f + 0.5 * (v.y * v.y + v.z * v.z);
            out[1..4].copy_from_slice(&[df, v.y, v.z]);
            out[4..].iter_mut().for_each(|h| *h = 0.0);
            out[4] = match self.definite_curvature {
                Some(c) if self.definite => ddf.max(c),
                _ => ddf,
            };
            out[8] = 1.0;
            out[12] = 1.0;
        }
        fn use_definite_hessian(&mut self, on: bool) -> bool {
            let changed = self.definite != on && self.has_definite_form();
            self.definite = on;
            changed
        }
        fn has_definite_form(&self) -> bool {
            self.definite_curvature.is_some()
        }
        fn accept_iterate(&mut self, from: &EvalState, to: &EvalState) {
            self.accepted += 1;
            self.breaks += (from.v[0].x != self.last_to) as usize;
            self.last_to = to.v[0].x;
        }
        fn save_iterate(&mut self) {
            self.saved = (self.accepted, self.last_to);
        }
        fn restore_iterate(&mut self) {
            (self.accepted, self.last_to) = self.saved;
        }
    }

    fn solve_counting(term: &mut Counting) -> (NewtonReport, f64) {
        let mut nodes = NodeArrays::default();
        nodes.push(&[Vector3::zeros()]);
        let bodies = BodyArrays::default();
        let problem = StepProblem {
            nodes: &nodes,
            bodies: &bodies,
            dt: 0.01,
            time: 0.01,
            gravity: Vector3::zeros(),
            guess_scale: 1.0,
        };
        let mut ws = NewtonWorkspace::default();
        let mut v = Vec::new();
        let settings = NewtonSettings {
            linear_solver: LinearSolver::Cholesky,
            ..NewtonSettings::default()
        };
        let mut terms: Vec<&mut dyn EnergyTerm> = vec![term];
        let report = solve(&mut ws, &mut terms, &problem, &mut v, &settings).unwrap();
        (report, v[0].x)
    }

    /// While the line searches accept their first trials, each trial is assembled (value,
    /// gradient, Hessian) and that assembly is the next iteration's: no energy-only
    /// evaluations, and exactly one assembly per iterate.
    #[test]
    fn accepted_trials_are_assembled_once() {
        let mut term = Counting::new(Well::Quartic);
        let (report, x) = solve_counting(&mut term);
        assert!(report.iterations >= 5, "{report:?}");
        assert_eq!(report.min_step_fraction, 1.0);
        let [_, df, _] = term.f(x);
        assert!(df.abs() < 1e-8, "converged: f′ = {df}");
        assert_eq!(*term.energies.lock().unwrap(), 0);
        assert_eq!(*term.assemblies.lock().unwrap(), report.iterations + 1);
        assert_eq!(term.accepted, report.iterations);
    }

    /// A speculative first trial that the line search cuts: the term's iterate state accepted
    /// for it tentatively is restored, so it counts each accepted iterate once; the step's
    /// later line searches evaluate energies only.
    #[test]
    fn a_cut_speculative_trial_is_undone() {
        let mut term = Counting::new(Well::Huber);
        let (report, x) = solve_counting(&mut term);
        assert!(
            report.line_search_evaluations > report.iterations,
            "a step was cut: {report:?}"
        );
        let [_, df, _] = term.f(x);
        assert!(df.abs() < 1e-8, "converged: f′ = {df}");
        assert_eq!(term.accepted, report.iterations);
        assert!(*term.energies.lock().unwrap() > 0);
    }

    /// Where the definite form's full steps keep lowering the energy by more than their slope
    /// and raising the residual, Newton extrapolates along them: from the hilltop into the well
    /// in a few iterations where the definite steps alone would grow by 1.1 per iteration
    /// (over 60 iterations to get from 1e-3 to the well's edge).
    #[test]
    fn concave_definite_steps_are_extrapolated() {
        // The definite form overestimates the hilltop's curvature (−1) as 10, like the
        // projected barriers of a towel's layers leaving an unstable configuration: its steps
        // alone grow by 1.1 per iteration.
        let mut term = Counting::new(Well::Hilltop);
        term.definite_curvature = Some(10.0);
        let (report, x) = solve_counting(&mut term);
        let [_, df, ddf] = term.f(x);
        assert!(
            df.abs() < 1e-6 && ddf > 0.0,
            "converged into a well: x = {x}, f′ = {df}"
        );
        assert!(x > 0.9, "down the slope it started on: x = {x}");
        assert!(report.iterations <= 20, "{report:?}");
        // An extrapolation undoes the full step's tentative acceptance and accepts the step it
        // took: one acceptance per iterate, each from where the last one ended.
        assert_eq!(term.accepted, report.iterations);
        assert_eq!(term.breaks, 0);
        assert_eq!(term.last_to, x);
    }

    #[test]
    fn invalid_states_are_never_used_as_guess_or_iterate() {
        // The start velocity 1 m/s (the initial guess) is beyond the limit 0.3 m/s: it must be
        // halved to 0.25 before anything is evaluated there; the minimiser 0.2 is valid.
        let mut nodes = NodeArrays::default();
        nodes.push(&[Vector3::zeros()]);
        nodes.v[0] = Vector3::new(1.0, 0.0, 0.0);
        let bodies = BodyArrays::default();
        let problem = StepProblem {
            nodes: &nodes,
            bodies: &bodies,
            dt: 0.01,
            time: 0.01,
            gravity: Vector3::zeros(),
            guess_scale: 1.0,
        };
        let mut term = Fenced {
            target: 0.2,
            limit: 0.3,
            largest_evaluated: Mutex::new(f64::NEG_INFINITY),
            rejected: Mutex::new(0),
        };
        let mut ws = NewtonWorkspace::default();
        let mut v = Vec::new();
        let settings = NewtonSettings {
            linear_solver: LinearSolver::Cholesky,
            ..NewtonSettings::default()
        };
        {
            let mut terms: Vec<&mut dyn EnergyTerm> = vec![&mut term];
            solve(&mut ws, &mut terms, &problem, &mut v, &settings).unwrap();
        }
        assert!((v[0].x - 0.2).abs() < 1e-9, "{:?}", v[0]);
        let largest = *term.largest_evaluated.lock().unwrap();
        assert!(largest <= 0.3, "evaluated at an invalid state v = {largest}");
        // 1.0 and 0.5 were rejected as guesses, 0.25 accepted.
        assert_eq!(*term.rejected.lock().unwrap(), 2);
        assert_eq!(largest, 0.25);
    }
}
