//! A block stretched quasistatically (inertia off, one large step per load increment) converges,
//! and for a small stretch its end force matches linear elasticity: pulling a bar of length L and
//! section A by δ needs F ≈ E_eff·A·δ/L. With the sides free the bar is uniaxially loaded, so
//! E_eff = E (Poisson contraction is free); the grid's discretisation error keeps it within 3%.

use nalgebra::Vector3;
use stark::deformables::PrescribedParams;
use stark::presets::VolumeMaterial;
use stark::{Settings, Simulation};

#[test]
fn quasistatic_stretch_converges() {
    let mut settings = Settings::default();
    settings.output.frames = false;
    settings.output.step_log = false;
    settings.gravity_m_s2 = [0.0; 3];
    settings.time_step_s = 1.0;
    settings.newton.linear_solver = stark::solver::LinearSolver::Cholesky;
    let mut sim = Simulation::new(settings).unwrap();
    let mut material = VolumeMaterial::default();
    material.inertia.quasistatic = true;
    material.strain.youngs_modulus = 1e5;
    material.strain.poissons_ratio = 0.3;
    let (length, side) = (1.0, 0.2);
    let bar = sim
        .add_volume_grid("bar", [length, side, side], [10, 2, 2], &material)
        .unwrap();
    // Clamp the x = −L/2 face in x only at its centre line would under-constrain; clamp the
    // whole face and pull the whole far face: the ends are then not free to contract, which
    // stiffens the bar slightly (accounted for in the tolerance).
    let k = PrescribedParams {
        stiffness: 1e9,
        tolerance_m: 1e-7,
    };
    let face = Vector3::new(1e-6, side * 1.01, side * 1.01);
    sim.prescribe_in_box(bar.nodes, Vector3::new(-length / 2.0, 0.0, 0.0), face, k.clone())
        .unwrap();
    let pull = sim
        .prescribe_in_box(bar.nodes, Vector3::new(length / 2.0, 0.0, 0.0), face, k)
        .unwrap();
    let stretch = 1e-3;
    for step in 1..=5 {
        let delta = stretch * length * step as f64 / 5.0;
        sim.deformables
            .prescribed
            .set_transform(pull, Vector3::new(delta, 0.0, 0.0), nalgebra::Rotation3::identity())
            .unwrap();
        let r = sim.step().unwrap();
        assert!(r.residual_n < 1e-6, "load step {step}: residual {}", r.residual_n);
    }
    // Reaction force: the spring force of the pulled nodes.
    let nodes = sim.deformables.prescribed.nodes_of(pull).unwrap().to_vec();
    let targets = sim.deformables.prescribed.targets(pull).unwrap().to_vec();
    let kk = sim.deformables.prescribed.params(pull).unwrap().stiffness;
    let force: f64 = nodes
        .iter()
        .zip(&targets)
        .map(|(&i, t)| kk * (t.x - sim.nodes.x[i as usize].x))
        .sum();
    let expected = 1e5 * side * side * stretch;
    let rel = (force - expected) / expected;
    println!(
        "end force {force:.4} N, linear elasticity {expected:.4} N ({:+.2}%)",
        100.0 * rel
    );
    assert!(rel.abs() < 0.03, "{force} vs {expected}");
    assert_eq!(sim.deformables.tets.count_inverted(&sim.nodes.x), 0);
}
