//! What `stark run` adds for the grasp scenes (`franka_cup`, `franka_rigid_box`): pictures of
//! the state when static grasping breaks and when the grasp slips 1 mm, the outcome against the Coulomb threshold, and the plot of
//! the load against the friction capacity.

use crate::plot;
use stark::scenes::franka_cup::{self, GraspOutcome};
use stark::Simulation;
use std::path::PathBuf;

/// The slip watch of a run, with where its picture goes.
pub struct GraspRun {
    watch: franka_cup::SlipWatch,
    pour_start_s: f64,
}

fn probe_log(sim: &Simulation) -> PathBuf {
    sim.settings
        .output
        .directory
        .join(format!("{}.{}.jsonl", sim.settings.name, franka_cup::PROBE))
}

impl GraspRun {
    /// For simulations built by `franka_cup::build` with the default schedule (the built-in
    /// scenes); a resumed run continues its watch from the probe log.
    pub fn find(sim: &Simulation) -> Option<GraspRun> {
        let pour_start_s = franka_cup::FrankaCupOptions::default().pour_start_s;
        let mut watch = franka_cup::SlipWatch::find(sim, pour_start_s)?;
        if sim.summary().steps > 0 {
            if let Err(e) = watch.resume_from_log(&probe_log(sim)) {
                eprintln!("warning: the slip watch starts afresh: {e}");
            }
        }
        Some(GraspRun { watch, pour_start_s })
    }

    /// After every step: draw the state when static grasping breaks and when the grasp slips.
    pub fn after_step(&mut self, sim: &Simulation) {
        for event in self.watch.update(sim) {
            let (what, title) = match event {
                franka_cup::GraspEvent::Slip => ("slip", "the grasp slips"),
                franka_cup::GraspEvent::Break => ("break", "static grasping breaks"),
            };
            let title = format!("{}: {title} at t = {:.3} s", sim.settings.name, sim.time());
            draw_state(sim, what, &title);
        }
    }

    /// Print the outcome and draw the plot of load and capacity.
    pub fn report(&self, sim: &Simulation) {
        let log = probe_log(sim);
        if !sim.settings.output.step_log || !log.exists() {
            return;
        }
        let title = format!("{} at t = {:.3} s", sim.settings.name, sim.time());
        if let Some(png) = draw_state(sim, "final", &title) {
            println!("final state           {}", png.display());
        }
        let outcome = match franka_cup::grasp_outcome(&log, self.pour_start_s) {
            Ok(o) => {
                print_outcome(&o);
                o
            }
            Err(e) => {
                eprintln!("warning: no grasp outcome: {e}");
                return;
            }
        };
        let png = sim
            .settings
            .output
            .directory
            .join(format!("{}.grasp.png", sim.settings.name));
        let series = [
            "grasp.load_n",
            "grasp.capacity_n",
            "grasp.friction_on_held_n",
            "grasp.normal_force_n",
            "grasp.grip_force_n",
            "grasp.balls_in_cup",
            "grasp.held_z_m",
        ]
        .map(String::from);
        let mut marks = Vec::new();
        if let Some(t) = outcome.break_time_s {
            marks.push(plot::Mark {
                time_s: t,
                label: format!(" static grasp breaks, t = {t:.3} s"),
            });
        }
        if let Some(t) = outcome.slip_time_s {
            marks.push(plot::Mark {
                time_s: t,
                label: format!(" slip (1 mm), t = {t:.3} s"),
            });
        }
        match plot::plot_logs_marked(&[log], &series, &marks, Some(&png)) {
            Ok(p) => println!("grasp plot            {}", p.display()),
            Err(e) => eprintln!("warning: no grasp plot: {e}"),
        }
    }
}

/// A picture of the cup (or box), the fingers and the balls: `<name>.<what>.png`.
fn draw_state(sim: &Simulation, what: &str, title: &str) -> Option<PathBuf> {
    let png = sim
        .settings
        .output
        .directory
        .join(format!("{}.{what}.png", sim.settings.name));
    let meshes: Vec<_> = plot::picture_meshes(sim)
        .into_iter()
        .filter(|m| m.label != "floor" && m.label != "franka/fr3_hand")
        .collect();
    // Around the cup and the jaws.
    let region = [[-0.06, -0.06, -0.01], [0.06, 0.06, 0.14]];
    match plot::picture(&meshes, title, Some(region), &png) {
        Ok(()) => Some(png),
        Err(e) => {
            eprintln!("warning: no picture of the {what} state: {e}");
            None
        }
    }
}

fn print_outcome(o: &GraspOutcome) {
    let a = &o.at;
    let sum_n = a.normal_force_n[0] + a.normal_force_n[1];
    match o.slip_time_s {
        Some(t) => println!(
            "grasp                 slipped 1 mm at t = {t:.3} s ({} balls in the cup): load {:.3} N against a friction \
             capacity μ·ΣN = {:.3} N (ΣN = {:.3} + {:.3} = {sum_n:.3} N), {:+.1}%",
            a.balls_in_cup,
            a.load_n,
            a.capacity_n,
            a.normal_force_n[0],
            a.normal_force_n[1],
            100.0 * (o.load_over_capacity - 1.0)
        ),
        None => println!(
            "grasp                 held to the end ({} balls in the cup): load {:.3} N against a friction capacity {:.3} N; \
             drop {:.3} mm",
            a.balls_in_cup,
            a.load_n,
            a.capacity_n,
            1e3 * o.final_drop_m
        ),
    }
    match (o.break_time_s, &o.at_break) {
        (Some(t), Some(b)) => println!(
            "static grasp          broke at t = {t:.3} s ({} balls in the cup; sliding faster than {} mm/s): load {:.3} N, \
             friction {:.3} N against μ·ΣN = {:.3} N, load {:+.1}% over μ·ΣN; the paper: 20 balls, 2.8 N against \
             2.5 N (+12%)",
            b.balls_in_cup,
            1e3 * franka_cup::BREAK_SPEED_M_S,
            b.load_n,
            b.friction_on_held_n,
            b.capacity_n,
            100.0 * (b.load_n / b.capacity_n - 1.0)
        ),
        _ => println!(
            "static grasp          never slid faster than {} mm/s",
            1e3 * franka_cup::BREAK_SPEED_M_S
        ),
    }
    println!(
        "                      largest load/capacity while holding: {:.3} at t = {:.3} s",
        o.max_held_ratio.0, o.max_held_ratio.1
    );
}
