//! Near the solution Newton converges quadratically, also where a contact rests on a curved
//! obstacle: the barrier pairs take their exact Hessian there.
//!
//! A barrier pair's Hessian `κ(b″∇d∇dᵀ + b′∇²d)` has negative curvature across the pair where
//! the distance curves (`b′ < 0`, `∇²d` positive across the pair). Its positive semi-definite
//! forms (projected, Gauss–Newton) drop it; near the solution the inertia holds the total
//! positive definite anyway, and the dropped curvature only makes the model too stiff, so Newton
//! contracts at a constant rate instead of squaring the residual (a folded towel under a robot:
//! 0.69 per iteration over 20 iterations, BENCHMARKS.md).
//!
//! Setup: a heavy 2 cm square of cloth (3×3 nodes, 20 kg/m², a lead sheet's areal density) is
//! draped over the apex of a fixed, flat pyramid (slopes 0.1, μ = 0.5; contact thickness 1 mm
//! each, so d̂ = 2 mm) for 0.2 s at dt = 10 ms, its centre 1 mm to the side of the apex. The apex
//! carries ~8 mN, so the pairs' curvature across (force / distance, ~10 N/m) outweighs the
//! membrane's (E·h = 5 N/m) and the nodes' inertia (m/dt², ~1 N/m). Then the cloth is pushed down
//! at 5 cm/s and one step is solved to 1e-9 N. Claim: once the residual is below 1e-4 of the
//! step's first, it reaches 1e-9 N in at most three iterations (a linear contraction of 0.69
//! would take about 30), every iteration divides it by more than 10, and by more than the
//! iteration before did while above 1e-10 N (the forces' rounding floor is a few 1e-11 N).
//! Measured: 5.1e-6, 2.8e-9, 4.1e-11 N (ratios 5.6e-4, 0.014); 9 iterations in all (with the
//! friction majoriser that preceded the primal–dual Hessian, 14: 2.1e-5, 6.8e-7, 8.9e-10 N).
//!
//! Every Hessian projected (`Projection::Always`) converges about as fast here (19 iterations
//! against 17, a tail as steep): the membrane and the friction hold enough curvature; the 0.69
//! contraction of the towel needs its thousands of stacked pairs. This test guards the order of
//! convergence of the default path through contact, friction and the Hessian switches.

use nalgebra::Vector3;
use stark::presets::SurfaceMaterial;
use stark::{Settings, Simulation};

/// The pushed step's residuals, N.
fn pushed_step_residuals() -> Vec<f64> {
    let mut settings = Settings::default();
    settings.time_step_s = 0.01;
    settings.contact.default_thickness_m = Some(1e-3);
    let mut sim = Simulation::new(settings).expect("settings");
    // The pyramid: apex up at the origin, a 10 cm square base 5 mm below (faces sloping by
    // 0.1, less than μ: the cloth stays on it).
    let (half, depth) = (0.05, 0.005);
    let spike = [
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(-half, -half, -depth),
        Vector3::new(half, -half, -depth),
        Vector3::new(half, half, -depth),
        Vector3::new(-half, half, -depth),
    ];
    let faces = [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]];
    let spike = sim
        .add_prescribed_surface("spike", &spike, &faces, 1e-3, 1e4)
        .expect("spike");
    // The cloth, its centre node 2.5 mm over the apex and 1 mm to the side.
    let s = 0.01;
    let nodes: Vec<Vector3<f64>> = (0..9)
        .map(|i| Vector3::new(s * ((i % 3) as f64 - 1.0) + 1e-3, s * ((i / 3) as f64 - 1.0), 2.5e-3))
        .collect();
    let mut triangles = Vec::new();
    for (r, c) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
        let a = 3 * r + c;
        triangles.push([a, a + 1, a + 4]);
        triangles.push([a, a + 4, a + 3]);
    }
    // Heavy (20 kg/m², a lead sheet's areal density): the apex carries 8 mN, so the pairs'
    // curvature across (force / distance, ~10 N/m) outweighs the membrane's (E·h = 5 N/m) and
    // the nodes' inertia (m/dt², ~1 N/m).
    let mut material = SurfaceMaterial::cotton_fabric();
    material.inertia.density = 20.0;
    let cloth = sim.add_surface("cloth", &nodes, &triangles, &material).expect("cloth");
    let cloth_contact = cloth.contact.expect("contact with the default thickness");
    sim.contact
        .set_friction(spike.contact, cloth_contact, 0.5)
        .expect("friction");
    for _ in 0..20 {
        sim.step().expect("draping step");
    }
    assert!(sim.positions(cloth.nodes)[4].z > 0.0, "the cloth rests on the apex");
    sim.set_velocity(cloth.nodes, Vector3::new(0.0, 0.0, -0.05));
    sim.settings.newton.residual_tolerance_n = 1e-9;
    let report = sim.step().expect("pushed step");
    report.newton_residuals_n
}

#[test]
fn newton_converges_quadratically_at_a_resting_contact() {
    let residuals = pushed_step_residuals();
    let r0 = residuals[0];
    let tail: Vec<f64> = residuals.iter().copied().skip_while(|&r| r > 1e-4 * r0).collect();
    assert!(
        tail.len() <= 4 && tail.last().is_some_and(|&r| r < 1e-9),
        "at most three iterations from 1e-4 r0 to 1e-9 N: {residuals:?}"
    );
    let ratios: Vec<f64> = tail.windows(2).map(|w| w[1] / w[0]).collect();
    assert!(
        ratios.iter().all(|&q| q < 0.1),
        "ratios {ratios:?}, residuals {residuals:?}"
    );
    // Superlinear while above the rounding floor.
    for (k, pair) in ratios.windows(2).enumerate() {
        if tail[k + 2] > 1e-10 {
            assert!(
                pair[1] < pair[0],
                "superlinear: ratios {ratios:?}, residuals {residuals:?}"
            );
        }
    }
}
