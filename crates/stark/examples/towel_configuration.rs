//! A new towel configuration for the robot–towel suite, made by simulation: the flat towel lies on
//! the carpet, one corner is lifted and turned over a diagonal fold line (a 180° turn of the
//! corner's nodes about the line), released, and left to settle. The settled positions are written
//! as an OBJ in the flat grid's vertex order, the form of the original's configuration files, and
//! the robot can then drive into it (`--drive S` runs the carpet case on it for S seconds).
//!
//! ```text
//! cargo run --release --example towel_configuration               # ≈ 3 min at 1 thread
//! cargo run --release --example towel_configuration -- --drive 6  # then the robot, 6 s
//! ```
//!
//! Writes `output/towel_configuration/towel_corner_fold.obj`, the frames of the folding run, and
//! with `--drive` the robot's run and its outcome.

use nalgebra::{Rotation3, Unit, Vector3};
use stark::deformables::PrescribedParams;
use stark::presets::meshes;
use stark::scenes::kobuki_towel::{self, Case, Floor, ParamSet, DHAT_M};
use stark::{Settings, Simulation};
use std::fmt::Write as _;
use std::path::Path;

/// Legs of the folded corner along the two edges, m.
const CORNER_LEG_M: f64 = 0.3;
/// Height of the fold line above the towel: about the grid's spacing (13.5 mm), m.
const FOLD_HEIGHT_M: f64 = 0.015;
/// The corner's turn over the fold line, then the settling time, s.
const FOLD_S: f64 = 1.5;
const SETTLE_S: f64 = 1.0;

fn main() -> stark::Result<()> {
    let drive_s: Option<f64> = match std::env::args().skip(1).collect::<Vec<_>>().as_slice() {
        [] => None,
        [flag, s] if flag == "--drive" => Some(
            s.parse()
                .map_err(|_| stark::StarkError::InvalidInput(format!("--drive takes seconds, not '{s}'")))?,
        ),
        other => {
            return Err(stark::StarkError::InvalidInput(format!(
                "usage: towel_configuration [--drive SECONDS], not {other:?}"
            )))
        }
    };
    let out = Path::new("output/towel_configuration");

    // ---- The flat towel on a carpet floor, as in the suite ----
    let (rest, flat) = kobuki_towel::towel_meshes(1)?;
    let mut settings = Settings::default();
    settings.name = "towel_corner_fold".into();
    settings.output.directory = out.into();
    settings.time_step_s = 0.005;
    settings.newton.residual_tolerance_n = 1e-6;
    settings.newton.linear_solver = stark::solver::LinearSolver::Cholesky;
    let thickness = DHAT_M / 2.0;
    settings.contact.default_thickness_m = Some(thickness);
    let mut sim = Simulation::new(settings)?;
    let towel = sim.add_surface(
        "towel",
        &rest.vertices,
        &rest.elements,
        &kobuki_towel::towel_material(ParamSet::Original),
    )?;
    let towel_contact = towel.contact.expect("the material has a contact thickness");
    let z0 = flat.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
    let mut floor = meshes::box_mesh(Vector3::new(2.0, 1.5, 0.05));
    for v in &mut floor.vertices {
        *v += Vector3::new(0.0, 0.4, z0 - DHAT_M - 0.025);
    }
    let floor = sim.add_prescribed_surface("floor", &floor.vertices, &floor.elements, thickness, 1e6)?;
    sim.contact
        .set_friction(towel_contact, floor.contact, Floor::Carpet.towel_friction())?;
    sim.contact.set_friction(towel_contact, towel_contact, 0.4)?;

    // ---- The corner (+x, −y), held by its nodes within 2 cm ----
    let x_max = flat.iter().map(|p| p.x).fold(f64::NEG_INFINITY, f64::max);
    let y_min = flat.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
    let corner = Vector3::new(x_max, y_min, z0);
    let pin = PrescribedParams {
        stiffness: 1e5,
        ..Default::default()
    };
    let held = sim.prescribe_in_box(towel.nodes, corner, Vector3::new(0.04, 0.04, 0.01), pin)?;

    // The fold line joins the points CORNER_LEG_M from the corner along both edges, FOLD_HEIGHT_M
    // above the towel: a half turn about it lays the corner on top, twice that high, and the
    // crease keeps a radius of about one element (a tighter crease would crush the triangles
    // along it, and their stored energy would fling the flap back up on release).
    let lift = Vector3::new(0.0, 0.0, FOLD_HEIGHT_M);
    let a = corner - Vector3::new(CORNER_LEG_M, 0.0, 0.0) + lift;
    let b = corner + Vector3::new(0.0, CORNER_LEG_M, 0.0) + lift;
    // Turning towards +z first: the axis points from the corner's side over the towel's.
    let axis = Unit::new_normalize(a - b);
    sim.add_time_event(0.0, FOLD_S, move |sim, t| {
        // A smooth start and stop (C¹ ease) of the half turn.
        let s = (t / FOLD_S).clamp(0.0, 1.0);
        let angle = std::f64::consts::PI * s * s * (3.0 - 2.0 * s);
        let rotation = Rotation3::from_axis_angle(&axis, angle);
        // Rotation about the line through `a`: x ↦ R (x − a) + a.
        sim.deformables
            .prescribed
            .set_transform(held, a - rotation * a, rotation)
    });
    // Released: the holding springs go slack.
    sim.add_time_event(FOLD_S, f64::INFINITY, move |sim, _| {
        sim.deformables.prescribed.set_params(
            held,
            PrescribedParams {
                stiffness: 1e-9,
                ..Default::default()
            },
        )
    });
    let summary = sim.run(FOLD_S + SETTLE_S)?;
    println!(
        "folded and settled    {} steps, {:.2} Newton iterations per step, {:.0} s wall",
        summary.steps, summary.newton_iterations_per_step, summary.wall_time_s
    );

    // ---- The configuration file: the towel's positions in the flat grid's order ----
    let positions: Vec<Vector3<f64>> = sim.nodes.x[towel.nodes.range()].to_vec();
    let mut obj = String::from("# A towel configuration made by examples/towel_configuration.rs: corner fold\n");
    for p in &positions {
        writeln!(obj, "v {:.6} {:.6} {:.6}", p.x, p.y, p.z).expect("writing to a String");
    }
    for t in &rest.elements {
        writeln!(obj, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1).expect("writing to a String");
    }
    let path = out.join("towel_corner_fold.obj");
    std::fs::write(&path, obj).map_err(|e| stark::StarkError::InvalidInput(format!("{}: {e}", path.display())))?;
    let z_top = positions.iter().map(|p| p.z).fold(f64::NEG_INFINITY, f64::max);
    let v_max = sim.nodes.v[towel.nodes.range()]
        .iter()
        .map(|v| v.norm())
        .fold(0.0, f64::max);
    println!(
        "configuration         {} (stack height {:.1} mm, fastest node {:.1} mm/s)",
        path.display(),
        (z_top - z0) * 1e3,
        v_max * 1e3
    );

    // ---- The robot drives into it (the carpet case, parameter set `original`) ----
    if let Some(duration_s) = drive_s {
        let case = Case {
            floor: Floor::Carpet,
            configuration: 1,
            params: ParamSet::Original,
        };
        let mut settings = Settings::default();
        settings.name = "kobuki_towel_carpet_corner_fold".into();
        settings.output.directory = out.into();
        let (mut sim, run) = kobuki_towel::build_with_towel(settings, case, &positions)?;
        sim.add_probe(kobuki_towel::PROBE, move |sim| run.record(sim))?;
        let summary = sim.run(duration_s)?;
        println!(
            "robot run             {} steps, {:.2} Newton iterations per step, {:.0} s wall",
            summary.steps, summary.newton_iterations_per_step, summary.wall_time_s
        );
        let log = out.join(format!("kobuki_towel_carpet_corner_fold.{}.jsonl", kobuki_towel::PROBE));
        let outcome = kobuki_towel::classify_log(&log)?;
        println!("outcome               {}: {}", outcome.outcome.letter(), outcome.reason);
    }
    Ok(())
}
