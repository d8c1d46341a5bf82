//! Shared set-up for the joint tests (not a claim itself): settings, cube bodies, seeded loads and
//! the checks "violation within tolerance" and "reaction equals minus the load".

use nalgebra::{UnitQuaternion, Vector3};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use stark::rigidbodies::joints::{JointHandle, JointParams, JointState};
use stark::rigidbodies::{MassProperties, RigidBodyHandle};
use stark::solver::LinearSolver;
use stark::{Settings, Simulation};

/// Edge of the test cubes, m.
pub const CUBE_M: f64 = 0.1;

/// Relative error allowed between a joint's reaction and the load it holds (Stark's check).
pub const REACTION_REL: f64 = 1e-3;

/// Joint parameters of the load tests: a soft start (1e4 N/m, 100× below Stark's default) so
/// that hardening has to bring every joint within its tolerance (1 mm, 0.1°).
pub fn soft_params() -> JointParams {
    JointParams {
        stiffness: 1e4,
        tolerance_m: 1e-3,
        tolerance_deg: 0.1,
    }
}

/// No gravity, no output, direct solves, Newton to 1e-6 N.
pub fn settings(name: &str, dt: f64) -> Settings {
    let mut s = Settings::default();
    s.name = name.into();
    s.time_step_s = dt;
    s.output.frames = false;
    s.output.step_log = false;
    s.gravity_m_s2 = [0.0; 3];
    s.threads = 1;
    s.newton.linear_solver = LinearSolver::Cholesky;
    s
}

/// A new simulation with [`settings`].
pub fn simulation(name: &str, dt: f64) -> Simulation {
    Simulation::new(settings(name, dt)).unwrap()
}

/// A seeded generator (one seed per test, so every run sees the same numbers).
pub fn rng(seed: u64) -> StdRng {
    StdRng::seed_from_u64(seed)
}

/// A uniform number in `[lo, hi)`.
pub fn uniform(rng: &mut StdRng, lo: f64, hi: f64) -> f64 {
    rng.random_range(lo..hi)
}

/// A vector with a uniformly random direction and a magnitude in `[lo, hi)`.
pub fn random_vector(rng: &mut StdRng, lo: f64, hi: f64) -> Vector3<f64> {
    loop {
        let v = Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let n = v.norm();
        if n > 0.1 && n <= 1.0 {
            return v / n * uniform(rng, lo, hi);
        }
    }
}

/// A cube of mass `mass_kg` centred at `at`, axis-aligned.
pub fn cube(sim: &mut Simulation, label: &str, mass_kg: f64, at: Vector3<f64>) -> RigidBodyHandle {
    let props = MassProperties::cuboid(mass_kg, Vector3::repeat(CUBE_M));
    sim.add_rigid_body_with(label, &props, at, UnitQuaternion::identity())
        .unwrap()
}

/// Moment of inertia of a test cube about any axis through its centre, kg·m².
pub fn cube_inertia(mass_kg: f64) -> f64 {
    mass_kg * CUBE_M * CUBE_M / 6.0
}

/// Run `steps` steps.
pub fn run_steps(sim: &mut Simulation, steps: usize) {
    for _ in 0..steps {
        sim.step().unwrap();
    }
}

/// What a load check measured.
#[derive(Clone, Copy, Debug)]
pub struct Held {
    /// The joint's state.
    pub state: JointState,
    /// `‖f + F‖ / ‖F‖`.
    pub force_err: f64,
    /// `‖τ_r + τ‖ / max(‖τ‖, ‖F‖·CUBE_M)`.
    pub torque_err: f64,
    /// Largest stiffness after hardening, N/m.
    pub stiffness: f64,
}

/// Assert that `joint` is within its tolerances (`params`) and that its force and torque on body b
/// are minus the load it holds: `force_n` and `torque_n_m` about b's centre of mass (the parts of
/// the applied load that the joint, not free motion, takes up). Torque errors are relative to
/// `max(‖τ‖, ‖F‖·CUBE_M)`, the torque scale of the load.
pub fn assert_holds(
    sim: &Simulation,
    joint: &JointHandle,
    params: &JointParams,
    force_n: Vector3<f64>,
    torque_n_m: Vector3<f64>,
) -> Held {
    let state = sim.joint_state(joint);
    let f = Vector3::from(state.force_on_b_n);
    let t = Vector3::from(state.torque_on_b_n_m);
    let force_scale = force_n.norm().max(1e-300);
    let torque_scale = torque_n_m.norm().max(force_n.norm() * CUBE_M).max(1e-300);
    let held = Held {
        state,
        force_err: if force_n.norm() > 0.0 {
            (f + force_n).norm() / force_scale
        } else {
            f.norm()
        },
        torque_err: (t + torque_n_m).norm() / torque_scale,
        stiffness: sim.joint_stiffness(joint),
    };
    let label = &joint.label;
    assert!(
        state.violation_m <= params.tolerance_m,
        "{label}: violation {:.3e} m > {:.1e} m",
        state.violation_m,
        params.tolerance_m
    );
    assert!(
        state.violation_rad <= params.tolerance_deg.to_radians(),
        "{label}: violation {:.3e}° > {}°",
        state.violation_rad.to_degrees(),
        params.tolerance_deg
    );
    assert!(
        held.force_err < REACTION_REL,
        "{label}: force on b {f:?} vs load {force_n:?} (relative error {:.2e})",
        held.force_err
    );
    assert!(
        held.torque_err < REACTION_REL,
        "{label}: torque on b {t:?} vs load {torque_n_m:?} (relative error {:.2e})",
        held.torque_err
    );
    held
}

/// One line for the test's output.
pub fn report(what: &str, h: &Held) {
    eprintln!(
        "{what:<28} violation {:.2e} m / {:.2e}°, force error {:.1e}, torque error {:.1e}, stiffness {:.3e} N/m",
        h.state.violation_m,
        h.state.violation_rad.to_degrees(),
        h.force_err,
        h.torque_err,
        h.stiffness
    );
}
