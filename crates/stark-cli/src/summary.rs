//! The run summary printed at the end: totals, rigid bodies and joints, logs, the towel outcome.

use super::*;

/// Most joints listed in the summary.
const MAX_JOINTS_SHOWN: usize = 12;

/// The rigid-body part of the summary: counts, largest joint violations and each joint's state
/// at the end.
pub(super) fn print_rigid_summary(sim: &Simulation, s: &RunSummary) {
    if s.rigid_bodies == 0 {
        return;
    }
    println!(
        "rigid bodies          {} bodies, {} joints (largest violation {:.2e} m, {:.2e}°)",
        s.rigid_bodies,
        s.joints,
        s.max_joint_violation_m,
        s.max_joint_violation_rad.to_degrees()
    );
    let joints = &sim.rigid_bodies.named_joints;
    if joints.is_empty() {
        return;
    }
    println!(
        "  {:<22} {:>12} {:>14} {:>14} {:>10} {:>9}",
        "joint at the end", "coordinate", "rate", "driver effort", "violation", "angle"
    );
    let elements = &sim.rigid_bodies.joints.potential.elements;
    for (h, (label, state)) in joints.iter().zip(sim.joint_states()).take(MAX_JOINTS_SHOWN) {
        let (coordinate, rate) = match (h.measure, state.coordinate, state.coordinate_rate) {
            (Some(Measure::Angle { .. }), Some(c), Some(r)) => {
                (format!("{:.2}°", c.to_degrees()), format!("{:.2}°/s", r.to_degrees()))
            }
            (Some(Measure::Position { .. }), Some(c), Some(r)) => (format!("{c:.4} m"), format!("{r:.4} m/s")),
            _ => ("-".into(), "-".into()),
        };
        let effort = match h.driver.and_then(|d| elements.get(d as usize)) {
            Some(d) if matches!(d.primitive, Primitive::AngularVelocity { .. }) => {
                format!("{:.4} N·m", state.driver_effort)
            }
            Some(_) => format!("{:.4} N", state.driver_effort),
            None => "-".into(),
        };
        println!(
            "  {:<22} {:>12} {:>14} {:>14} {:>8.1e} m {:>8.1e}°",
            label,
            coordinate,
            rate,
            effort,
            state.violation_m,
            state.violation_rad.to_degrees()
        );
    }
    if joints.len() > MAX_JOINTS_SHOWN {
        println!(
            "  ... and {} more (all of them, every step: the joint log)",
            joints.len() - MAX_JOINTS_SHOWN
        );
    }
}

pub(super) fn print_summary(s: &RunSummary, out: &std::path::Path) {
    println!("scene                 {}", s.scene);
    println!(
        "problem size          {} unknowns ({} nodes, {} rigid bodies)",
        s.unknowns, s.nodes, s.rigid_bodies
    );
    println!(
        "simulated time        {:.4} s in {} steps ({} failed attempts, {} hardening retries)",
        s.simulated_time_s, s.steps, s.failed_steps, s.hardening_retries
    );
    println!(
        "Newton iterations     {} ({:.2} per step), {} CG iterations",
        s.newton_iterations, s.newton_iterations_per_step, s.cg_iterations
    );
    println!(
        "largest residual      {:.3e} N ({} steps ended by the step-size criterion, {} at the forces' rounding error)",
        s.max_residual_n, s.steps_converged_by_step_size, s.steps_at_rounding_floor
    );
    println!(
        "wall time             {:.3} s ({:.3} s per simulated second)",
        s.wall_time_s, s.wall_time_per_simulated_s
    );
    let t = &s.times;
    let total = t.total_s().max(1e-12);
    println!(
        "time per phase        evaluation {:.0}%, linear solve {:.0}%, line search {:.0}%, contact detection {:.0}%, \
         CCD {:.0}%, step start {:.0}%, step end {:.0}%",
        100.0 * t.evaluation_s / total,
        100.0 * t.linear_solve_s / total,
        100.0 * t.line_search_s / total,
        100.0 * t.prepare_s / total,
        100.0 * t.ccd_s / total,
        100.0 * t.step_start_s / total,
        100.0 * t.step_end_s / total
    );
    if s.max_active_pairs > 0 {
        println!(
            "contact               {:.0} active pairs on average, {} at most",
            s.mean_active_pairs, s.max_active_pairs
        );
    }
    println!("output                {} frames in {}", s.frames, out.display());
}

/// The logs the run wrote.
pub(super) fn print_logs(sim: &Simulation) {
    let o = &sim.settings.output;
    if !o.step_log {
        return;
    }
    let name = &sim.settings.name;
    let mut logs = vec![format!("{name}.steps.jsonl")];
    if o.bodies_log && sim.num_rigid_bodies() > 0 {
        logs.push(format!("{name}.bodies.jsonl"));
    }
    if o.joints_log && !sim.rigid_bodies.named_joints.is_empty() {
        logs.push(format!("{name}.joints.jsonl"));
    }
    println!("logs                  {}", logs.join(", "));
}

/// The outcome of a robot–towel run (the scenes that write a `robot_towel` probe log).
pub(super) fn print_robot_towel_outcome(sim: &Simulation) {
    use stark::scenes::kobuki_towel;
    let o = &sim.settings.output;
    let log = o
        .directory
        .join(format!("{}.{}.jsonl", sim.settings.name, kobuki_towel::PROBE));
    if !o.step_log || !log.exists() {
        return;
    }
    match kobuki_towel::classify_log(&log) {
        Ok(c) => {
            let lab = kobuki_towel::Case::from_name(&sim.settings.name)
                .map(|case| format!(" (lab: {})", case.lab_outcome()))
                .unwrap_or_default();
            println!("outcome               {}{lab}: {}", c.outcome.letter(), c.reason);
        }
        Err(e) => eprintln!("warning: no outcome: {e}"),
    }
    // The paper's Fig. 1: motor torque and suspension compression over time (with the wheel
    // speeds and the robot's advance).
    let png = o.directory.join(format!("{}.motors.png", sim.settings.name));
    let series = [
        "robot_towel.motor_torque_n_m",
        "robot_towel.suspension_compression_m",
        "robot_towel.wheel_speed_rad_s",
        "robot_towel.sample.robot_y_m",
    ]
    .map(String::from);
    match plot::plot_logs(&[log], &series, Some(&png)) {
        Ok(p) => println!("motor plot            {}", p.display()),
        Err(e) => eprintln!("warning: no motor plot: {e}"),
    }
    // The final state, top and side views, around the robot and the towel.
    let png = o.directory.join(format!("{}.final.png", sim.settings.name));
    let meshes: Vec<_> = plot::picture_meshes(sim)
        .into_iter()
        .filter(|m| m.label != "floor")
        .collect();
    let title = format!("{} at t = {:.2} s", sim.settings.name, sim.time());
    match plot::picture(&meshes, &title, None, &png) {
        Ok(()) => println!("final state           {}", png.display()),
        Err(e) => eprintln!("warning: no picture of the final state: {e}"),
    }
}
