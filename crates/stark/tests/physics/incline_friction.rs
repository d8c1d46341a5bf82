//! Coulomb friction on an incline: a soft block sticks when `tan θ < μ` and slides when
//! `tan θ > μ` with the acceleration `a = g (sin θ − μ cos θ)` (within 5%).
//!
//! This checks the whole frictional-contact path against the one analytic answer every friction
//! model must reproduce: the lagged normal force `λ = κ|b′(d)|` of each barrier pair, the tangent
//! basis, the ε_v smoothing, the `dt` scaling between the velocity DOFs and the positions the
//! friction energy sees, and the re-lagging of `friction_iterations` > 1.
//!
//! Setup: a 0.1 m cube of soft rubber made stiffer (E = 1e6 Pa, so the block barely wobbles;
//! 2×2×2 cells of 12 tets, 35 nodes, 1 kg; no inertial damping, which would act as a drag
//! `0.1/s · v`, ~10% of `a` at the speeds reached) rests 1 mm above a kinematic floor (a
//! prescribed 2-triangle square; contact thickness 1 mm each, so `d̂` = 2 mm and the block starts
//! inside the barrier's range without touching). μ = 0.5. The incline is emulated by tilting
//! gravity by θ, `g (sin θ, 0, −cos θ)`, which is the same physics on a flat floor. The block first
//! settles 0.3 s under vertical gravity, then gravity tilts and the mass-weighted centroid is
//! followed for 1 s along the slope. dt = 0.01 s; Newton to a force residual of 1e-6 N (the
//! default criterion; `scenes::stark_tolerances` also passes here, but its 1 mm/s step criterion
//! is coarser than the 0.06 mm/s creep measured below); every step is also checked for
//! intersections with the exact test.
//!
//! - Sticking, `tan θ = 0.8 μ`: the block shears elastically by ~0.3 mm, then creeps. The
//!   smoothed friction force is `μλ f₁(u/ε)`, `ε = ε_v dt`, which reaches `μλ` only at a slip of
//!   `ε` per step; holding a tangential load `r μλ` (here `r = tan θ / μ = 0.8`) takes a slip
//!   `u = (1 − √(1 − r)) ε` per step, i.e. a creep at `(1 − √(1 − r)) ε_v` = 0.553 ε_v. The test
//!   uses ε_v = 1e-4 m/s (default 1e-2 m/s: the same block would creep 5.5 mm/s, 5.8 mm in the
//!   second) and asserts a total displacement below 1 mm (sliding freely it would be
//!   `½ g sin θ` = 1.8 m) and a creep speed within 10% of the model. Measured: 0.376 mm, creep
//!   5.60e-5 m/s against 5.53e-5 m/s (+1.3%; +0.1% at ε_v = 1e-3 m/s, where the elastic
//!   settling matters less).
//! - Sliding, `tan θ = 1.25 μ` (θ = 32.0°, a = 1.0399 m/s²): a least-squares parabola through the
//!   centroid positions over 0.2–1.0 s after the tilt gives the acceleration; backward Euler
//!   reproduces a constant acceleration exactly, so the only errors are the model's. Measured
//!   relative error ~1e-6 (the assertion is the claim's 5%); likewise at dt = 1/30 s, 3×3×3 cells,
//!   E = 1e5 Pa or ε_v up to 1e-2 m/s.
//!
//! Both run with `friction_iterations` = 1 and 3. Re-lagging used to measure the slip of the next
//! solve from the converged end of the step instead of its start, so each extra iteration let the
//! block slip about another ε per step: at ε_v = 1e-3 m/s the sliding acceleration came out +5.4%
//! with 2 iterations and +10.6% with 3; at the ε_v used here the error is ~1% but the creep
//! triples with 3 iterations (1.66e-4 m/s), which the sticking assertion catches (fixed in
//! `Contact::lag_friction`; unit test
//! `contact::friction::tests::relag_keeps_the_start_of_step_as_slip_origin`).
//!
//! Why a 2-triangle floor whose diagonal stays away from the block's path: then only the block's
//! bottom vertices meet the floor, as point–triangle pairs, and the test isolates friction. On a
//! triangulated floor (spacing 3–7 cm) the block's vertices and edges cross floor edges; IPC sums
//! the barrier over all pairs, so near a floor edge a vertex also meets the neighbouring triangle
//! through that edge (a point–edge pair whose force is not vertical), which makes the floor feel
//! bumpy at the scale of `d̂` and makes `Σλ` exceed the weight there. The fitted acceleration then
//! wanders by ±10% over 0.1 s windows and by −4%…+2% over the whole second: a discretisation effect
//! of the barrier, not of friction, so it is not asserted here.
//!
//! Runtime (`--release`, one thread per simulation): 0.1–0.4 s per simulation, 1.6 s for the file.

use nalgebra::{Matrix3, Vector3};
use stark::presets::VolumeMaterial;
use stark::solver::LinearSolver;
use stark::{Settings, Simulation};

const G_M_S2: f64 = 9.81;
const MU: f64 = 0.5;
const SIDE_M: f64 = 0.1;
const CELLS: usize = 2;
const YOUNGS_MODULUS_PA: f64 = 1e6;
const THICKNESS_M: f64 = 1e-3;
const INITIAL_GAP_M: f64 = 1e-3;
const DT_S: f64 = 0.01;
/// The smoothing velocity ε_v, m/s.
const EPS_V_M_S: f64 = 1e-4;
const SETTLE_S: f64 = 0.3;
const DURATION_S: f64 = 1.0;

/// Centroid positions along the slope (relative to the tilt) against the time since the tilt.
struct Trace {
    samples: Vec<(f64, f64)>,
}

impl Trace {
    fn at(&self, t: f64) -> f64 {
        self.samples
            .iter()
            .find(|s| (s.0 - t).abs() < 1e-6)
            .unwrap_or_else(|| panic!("no sample at t = {t}"))
            .1
    }

    fn window(&self, from: f64, to: f64) -> Vec<(f64, f64)> {
        self.samples
            .iter()
            .copied()
            .filter(|s| s.0 >= from - 1e-9 && s.0 <= to + 1e-9)
            .collect()
    }
}

/// Settle the block on the floor under vertical gravity, tilt gravity to `tan θ`, and follow the
/// centroid for `DURATION_S`. Every step: no failure, no intersection, contact with friction.
fn slide_block(tan_theta: f64, friction_iterations: usize) -> Trace {
    let mut settings = Settings::default();
    settings.output.frames = false;
    settings.output.step_log = false;
    settings.threads = 1;
    settings.time_step_s = DT_S;
    settings.newton.linear_solver = LinearSolver::Cholesky;
    settings.newton.residual_tolerance_n = 1e-6;
    settings.contact.friction_stick_slide_threshold_m_s = EPS_V_M_S;
    settings.contact.friction_iterations = friction_iterations;
    settings.gravity_m_s2 = [0.0, 0.0, -G_M_S2];
    let mut sim = Simulation::new(settings).unwrap();
    let mut material = VolumeMaterial::soft_rubber();
    material.strain.youngs_modulus = YOUNGS_MODULUS_PA;
    material.inertia.damping = 0.0;
    material.contact_thickness_m = Some(THICKNESS_M);
    let block = sim
        .add_volume_grid("block", [SIDE_M; 3], [CELLS; 3], &material)
        .unwrap();
    // The block spans z ∈ [−0.05, 0.05] m. The floor's diagonal (0–2) passes 3 m and more from
    // the block's path along +x at y = 0.
    let z = -0.5 * SIDE_M - INITIAL_GAP_M;
    let floor_vertices = [
        Vector3::new(-1.0, -5.0, z),
        Vector3::new(9.0, -5.0, z),
        Vector3::new(9.0, 5.0, z),
        Vector3::new(-1.0, 5.0, z),
    ];
    let floor = sim
        .add_prescribed_surface("floor", &floor_vertices, &[[0, 1, 2], [0, 2, 3]], THICKNESS_M, 1e7)
        .unwrap();
    sim.contact
        .set_friction(block.contact.expect("the block has contact"), floor.contact, MU)
        .unwrap();

    let masses = sim.deformables.inertia.node_masses(sim.nodes.len());
    let range = block.nodes.range();
    let total: f64 = masses[range.clone()].iter().sum();
    let centroid = |sim: &Simulation| -> Vector3<f64> {
        range.clone().map(|i| sim.nodes.x[i] * masses[i]).sum::<Vector3<f64>>() / total
    };
    let step = |sim: &mut Simulation| {
        let r = sim.step().unwrap();
        assert_eq!(r.failed_attempts, 0, "step {} failed: {:?}", r.step, r.failure_reasons);
        let crossings = sim.contact.find_intersections(&sim.nodes.x);
        assert!(crossings.is_empty(), "t = {}: {crossings:?}", sim.time());
        let friction_pairs = r.contact.expect("contact statistics").friction_pairs;
        assert!(friction_pairs > 0, "t = {}: the block lost contact", sim.time());
    };

    while sim.time() < SETTLE_S - 1e-9 {
        step(&mut sim);
    }
    let theta = tan_theta.atan();
    sim.set_gravity(G_M_S2 * Vector3::new(theta.sin(), 0.0, -theta.cos()));
    let (t0, c0) = (sim.time(), centroid(&sim));
    let mut samples = vec![(0.0, 0.0)];
    while sim.time() < t0 + DURATION_S - 1e-9 {
        step(&mut sim);
        samples.push((sim.time() - t0, centroid(&sim).x - c0.x));
    }
    Trace { samples }
}

/// Least-squares parabola `x(t) = c₀ + c₁ t + c₂ t²` through the samples; returns `2 c₂`.
fn fitted_acceleration(samples: &[(f64, f64)]) -> f64 {
    let mean_t = samples.iter().map(|s| s.0).sum::<f64>() / samples.len() as f64;
    let mut normal = Matrix3::<f64>::zeros();
    let mut rhs = Vector3::<f64>::zeros();
    for &(t, x) in samples {
        let tau = t - mean_t;
        let p = Vector3::new(1.0, tau, tau * tau);
        normal += p * p.transpose();
        rhs += p * x;
    }
    2.0 * normal.lu().solve(&rhs).expect("enough samples")[2]
}

#[test]
fn block_sticks_below_the_friction_angle() {
    let ratio = 0.8;
    let theta = (ratio * MU).atan();
    let free_slide_m = 0.5 * G_M_S2 * theta.sin() * DURATION_S * DURATION_S;
    // Steady creep of the smoothed model (see the file's comment).
    let creep_model = (1.0 - (1.0 - ratio).sqrt()) * EPS_V_M_S;
    for iterations in [1, 3] {
        let trace = slide_block(ratio * MU, iterations);
        let displacement = trace.at(DURATION_S);
        let creep = (trace.at(DURATION_S) - trace.at(0.5)) / (DURATION_S - 0.5);
        println!(
            "stick (tan θ = {ratio} μ, {iterations} friction iteration(s)): displacement {displacement:.3e} m \
             after {DURATION_S} s (frictionless: {free_slide_m:.2} m), creep {creep:.4e} m/s \
             (model {creep_model:.4e} m/s)"
        );
        assert!(
            displacement.abs() < 1e-3,
            "{iterations} friction iteration(s): the block moved {displacement:.3e} m down a slope with \
             tan θ = {ratio} μ in {DURATION_S} s; static friction should hold it (< 1 mm; frictionless it \
             would slide {free_slide_m:.2} m)"
        );
        assert!(
            creep > 0.0 && creep < EPS_V_M_S && (creep / creep_model - 1.0).abs() < 0.1,
            "{iterations} friction iteration(s): creep {creep:.4e} m/s, expected \
             (1 − √(1 − {ratio}))·ε_v = {creep_model:.4e} m/s within 10% (and below ε_v = {EPS_V_M_S} m/s)"
        );
    }
}

#[test]
fn block_slides_above_the_friction_angle_at_the_coulomb_acceleration() {
    let ratio = 1.25;
    let theta = (ratio * MU).atan();
    let analytic = G_M_S2 * (theta.sin() - MU * theta.cos());
    for iterations in [1, 3] {
        let trace = slide_block(ratio * MU, iterations);
        let measured = fitted_acceleration(&trace.window(0.2, DURATION_S));
        let error = measured / analytic - 1.0;
        println!(
            "slide (tan θ = {ratio} μ, θ = {:.2}°, {iterations} friction iteration(s)): a = {measured:.6} m/s² \
             vs g(sin θ − μ cos θ) = {analytic:.6} m/s², relative error {error:+.2e}",
            theta.to_degrees()
        );
        assert!(
            error.abs() < 0.05,
            "{iterations} friction iteration(s): sliding acceleration {measured:.5} m/s², \
             g(sin θ − μ cos θ) = {analytic:.5} m/s² (error {:+.2}%, allowed 5%)",
            100.0 * error
        );
    }
}
