//! Bad input gives an error naming the problem, never a panic: an inverted or zero-volume rest
//! tet, a NaN or negative Young's modulus, a missing mesh file, a selection box that misses.

use nalgebra::Vector3;
use stark::deformables::PrescribedParams;
use stark::presets::VolumeMaterial;
use stark::{Settings, Simulation};

fn sim() -> Simulation {
    let mut s = Settings::default();
    s.output.frames = false;
    s.output.step_log = false;
    Simulation::new(s).unwrap()
}

fn tet() -> Vec<Vector3<f64>> {
    vec![Vector3::zeros(), Vector3::x(), Vector3::y(), Vector3::z()]
}

#[test]
fn bad_input_gives_clear_errors() {
    let m = VolumeMaterial::soft_rubber();
    let err = sim()
        .add_volume("cup", &tet(), &[[0, 2, 1, 3]], &m)
        .unwrap_err()
        .to_string();
    assert!(err.contains("tet 0 of 'cup'") && err.contains("inverted"), "{err}");
    let flat = vec![
        Vector3::zeros(),
        Vector3::x(),
        Vector3::y(),
        Vector3::new(1.0, 1.0, 0.0),
    ];
    let err = sim()
        .add_volume("flat", &flat, &[[0, 1, 2, 3]], &m)
        .unwrap_err()
        .to_string();
    assert!(err.contains("zero or degenerate"), "{err}");
    for (e, what) in [(f64::NAN, "NaN"), (-1e4, "-10000")] {
        let mut bad = m.clone();
        bad.strain.youngs_modulus = e;
        let err = sim()
            .add_volume("jelly", &tet(), &[[0, 1, 2, 3]], &bad)
            .unwrap_err()
            .to_string();
        assert!(err.contains(&format!("`youngs_modulus` = {what} on 'jelly'")), "{err}");
    }
    let err = stark::io::load_mesh("definitely/missing/cup.obj")
        .unwrap_err()
        .to_string();
    assert!(err.contains("cup.obj"), "{err}");
    let mut s = sim();
    let body = s.add_volume("box", &tet(), &[[0, 1, 2, 3]], &m).unwrap();
    let err = s
        .prescribe_in_box(
            body.nodes,
            Vector3::repeat(5.0),
            Vector3::repeat(0.1),
            PrescribedParams::default(),
        )
        .unwrap_err()
        .to_string();
    assert!(err.contains("contains no node of 'box'"), "{err}");
    let mut settings = Settings::default();
    settings.time_step_s = -1.0;
    let err = Simulation::new(settings).err().unwrap().to_string();
    assert!(err.contains("time_step_s"), "{err}");
}

/// `--set` overrides (`load_scene_with_overrides`): a value reaches the simulation, and a path
/// that selects nothing is an error naming the override and what exists.
#[test]
fn scene_overrides_apply_or_name_the_bad_path() {
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/rb_pendulum_chain.toml");
    let load = |o: &[&str]| {
        let o: Vec<String> = o.iter().map(|s| s.to_string()).collect();
        stark::io::load_scene_with_overrides(&scene, &o, |s| s.output.step_log = false)
    };
    let ok = load(&[
        "settings.time_step_s=0.005",
        "joint.motor.max_torque_n_m=2.5",
        "duration_s=1",
    ])
    .unwrap();
    assert_eq!(ok.simulation.settings.time_step_s, 0.005);
    assert_eq!(ok.duration_s, 1.0);
    assert_eq!(ok.name, "rb_pendulum_chain");
    let err = |o: &[&str]| load(o).err().expect("an error").to_string();
    let e = err(&["joint.elbow.stiffness=1"]);
    assert!(
        e.contains("no entry named 'elbow'") && e.contains("pivot, hinge1"),
        "{e}"
    );
    let e = err(&["rigid_body.9.mass_kg=1"]);
    assert!(e.contains("there is no entry 9"), "{e}");
    let e = err(&["duration_s.x=1"]);
    assert!(e.contains("`duration_s` is a float, not a table"), "{e}");
    let e = err(&["settings.time_step=0.01"]);
    assert!(e.contains("time_step"), "{e}");
    let e = err(&["settings.time_step_s"]);
    assert!(e.contains("expected key.path=value"), "{e}");
}
