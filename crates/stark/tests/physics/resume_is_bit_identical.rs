//! A run continued from a checkpoint repeats the uninterrupted run bit for bit (DESIGN §7):
//! a 2 s run against 1 s + `save_checkpoint` + a rebuilt scene + `restore_checkpoint` + 1 s,
//! comparing every DOF (node positions and velocities, body poses and velocities), the time, dt,
//! the counters and the body/joint logs. Scenes from the scene files in `scenes/`:
//!
//! - `rb_box_on_cloth.toml` (cloth 10×10 through `--set`-style overrides): rigid–deformable
//!   contact with friction μ = 0.5, adaptive barrier stiffness, and a keyframed paddle (time
//!   events) that starts moving at t = 1 s, right at the checkpoint;
//! - `rb_pendulum_chain.toml`: five hinged links and a motor-driven wheel; two hinges made soft
//!   (1e4 N/m) with a 0.1 mm tolerance harden during the run (the test checks that they do), so
//!   the hardened stiffnesses must come back;
//! - `twisting_cloth_no_contact.toml` (8×8 cloth): prescribed edges turned by time events;
//! - `rb_box_on_cloth.toml` again with the sparse Cholesky solver, whose factorisation each step
//!   reuses as a preconditioner, and with the multigrid preconditioner, whose hierarchy each step
//!   reuses.
//!
//! Then the errors: a checkpoint restored into another scene, a truncated file and another
//! format version are refused with messages saying so.

use stark::io::load_scene_with_overrides;
use stark::Simulation;
use std::path::{Path, PathBuf};

fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes").join(name)
}

fn build(scene: &str, overrides: &[&str], out: &Path) -> Simulation {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    load_scene_with_overrides(&scene_path(scene), &overrides, |s| {
        s.output.directory = out.to_path_buf();
        s.output.frames = false;
        s.threads = 2;
    })
    .unwrap()
    .simulation
}

fn bits(v: &[nalgebra::Vector3<f64>]) -> Vec<[u64; 3]> {
    v.iter()
        .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect()
}

fn assert_same_state(a: &Simulation, b: &Simulation, scene: &str) {
    assert_eq!(a.time().to_bits(), b.time().to_bits(), "{scene}: time");
    assert_eq!(a.dt().to_bits(), b.dt().to_bits(), "{scene}: dt");
    assert_eq!(bits(&a.nodes.x), bits(&b.nodes.x), "{scene}: node positions");
    assert_eq!(bits(&a.nodes.v), bits(&b.nodes.v), "{scene}: node velocities");
    assert_eq!(
        bits(&a.bodies.position),
        bits(&b.bodies.position),
        "{scene}: body positions"
    );
    assert_eq!(
        bits(&a.bodies.velocity),
        bits(&b.bodies.velocity),
        "{scene}: body velocities"
    );
    assert_eq!(
        bits(&a.bodies.angular_velocity),
        bits(&b.bodies.angular_velocity),
        "{scene}: angular velocities"
    );
    let q = |s: &Simulation| -> Vec<[u64; 4]> {
        s.bodies
            .orientation
            .iter()
            .map(|q| {
                q.coords
                    .as_slice()
                    .iter()
                    .map(|c| c.to_bits())
                    .collect::<Vec<_>>()
                    .try_into()
                    .unwrap()
            })
            .collect()
    };
    assert_eq!(q(a), q(b), "{scene}: orientations");
    let (sa, sb) = (a.summary(), b.summary());
    assert_eq!(sa.steps, sb.steps, "{scene}: steps");
    assert_eq!(sa.newton_iterations, sb.newton_iterations, "{scene}: Newton iterations");
    assert_eq!(sa.hardening_retries, sb.hardening_retries, "{scene}: hardening retries");
    assert_eq!(sa.failed_steps, sb.failed_steps, "{scene}: failed steps");
}

/// Run `scene` for 2 s in one go and as 1 s + checkpoint + resume 1 s; returns the
/// uninterrupted simulation for further checks.
fn check_resume(scene: &str, overrides: &[&str]) -> (Simulation, u64) {
    let dir = tempfile::tempdir().unwrap();
    let (whole_dir, split_dir) = (dir.path().join("whole"), dir.path().join("split"));
    let mut whole = build(scene, overrides, &whole_dir);
    whole.run(2.0).unwrap();

    let ckpt = split_dir.join("at_1s.ckpt");
    let mut first = build(scene, overrides, &split_dir);
    first.run(1.0).unwrap();
    first.save_checkpoint(&ckpt).unwrap();
    let hardened_before = first.summary().hardening_retries;
    drop(first);
    let mut resumed = build(scene, overrides, &split_dir);
    resumed.restore_checkpoint(&ckpt).unwrap();
    assert!(
        (resumed.time() - 1.0).abs() < 1e-12,
        "{scene}: restored at t = {}",
        resumed.time()
    );
    resumed.run(1.0).unwrap();
    assert_same_state(&whole, &resumed, scene);

    // The logs of the split run (cut back to the checkpoint and continued) equal the whole run's.
    let name = whole.settings.name.clone();
    for log in ["bodies", "joints"] {
        let a = std::fs::read_to_string(whole_dir.join(format!("{name}.{log}.jsonl")));
        let b = std::fs::read_to_string(split_dir.join(format!("{name}.{log}.jsonl")));
        if let (Ok(a), Ok(b)) = (a, b) {
            assert_eq!(
                a.lines().count() as u64,
                whole.summary().steps,
                "{scene}: {log} log lines"
            );
            assert!(a == b, "{scene}: the {log} logs differ");
        }
    }
    let steps = |d: &Path| {
        std::fs::read_to_string(d.join(format!("{name}.steps.jsonl")))
            .unwrap()
            .lines()
            .count()
    };
    assert_eq!(steps(&whole_dir), steps(&split_dir), "{scene}: step log lines");
    (whole, hardened_before)
}

#[test]
fn contact_with_friction_and_keyframes_resumes_bit_identically() {
    let (whole, _) = check_resume("rb_box_on_cloth.toml", &["surface.cloth.grid.quads=[10, 10]"]);
    assert!(whole.summary().max_active_pairs > 0, "the box must touch the cloth");
}

/// The sparse Cholesky solver reuses each step's factorisation as CG's preconditioner for the
/// step's later Newton iterations: every step starts from a fresh factor, so a resumed run is
/// the same run.
#[test]
fn cholesky_with_factor_reuse_resumes_bit_identically() {
    let (whole, _) = check_resume(
        "rb_box_on_cloth.toml",
        &[
            "surface.cloth.grid.quads=[10, 10]",
            "settings.newton.linear_solver=\"cholesky\"",
        ],
    );
    let s = whole.summary();
    assert!(s.max_active_pairs > 0, "the box must touch the cloth");
    // The reuse path ran: CG iterations preconditioned by the step's factor.
    assert!(s.cg_iterations > 0 && s.newton_iterations > s.steps, "{s:?}");
}

/// The multigrid preconditioner keeps each step's hierarchy for the step's later Newton
/// iterations: every step builds its own, so a resumed run is the same run. (A 24² cloth: a
/// hierarchy of two levels.)
#[test]
fn multigrid_with_hierarchy_reuse_resumes_bit_identically() {
    let (whole, _) = check_resume(
        "rb_box_on_cloth.toml",
        &[
            "surface.cloth.grid.quads=[24, 24]",
            "settings.newton.linear_solver=\"amg\"",
        ],
    );
    let s = whole.summary();
    assert!(s.max_active_pairs > 0, "the box must touch the cloth");
    assert!(s.cg_iterations > 0 && s.newton_iterations > s.steps, "{s:?}");
}

#[test]
fn hardening_joints_and_motor_resume_bit_identically() {
    // Softer hinges with a tight tolerance, so that they harden during the first second.
    let (whole, hardened_before) = check_resume(
        "rb_pendulum_chain.toml",
        &[
            "joint.hinge1.stiffness=1e4",
            "joint.hinge1.tolerance_m=1e-4",
            "joint.pivot.stiffness=1e4",
            "joint.pivot.tolerance_m=1e-4",
        ],
    );
    assert!(hardened_before > 0, "the hinges should harden before the checkpoint");
    assert!(whole.summary().hardening_retries > 0);
}

#[test]
fn prescribed_motion_events_resume_bit_identically() {
    check_resume("twisting_cloth_no_contact.toml", &["surface.cloth.grid.quads=[8, 8]"]);
}

#[test]
fn wrong_scene_truncated_file_and_other_version_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mut sim = build(
        "twisting_cloth_no_contact.toml",
        &["surface.cloth.grid.quads=[4, 4]"],
        dir.path(),
    );
    sim.run(0.1).unwrap();
    let ckpt = dir.path().join("a.ckpt");
    sim.save_checkpoint(&ckpt).unwrap();

    let mut other = build(
        "twisting_cloth_no_contact.toml",
        &["surface.cloth.grid.quads=[5, 4]"],
        dir.path(),
    );
    let e = other.restore_checkpoint(&ckpt).unwrap_err().to_string();
    assert!(e.contains("not of this scene"), "{e}");

    let bytes = std::fs::read(&ckpt).unwrap();
    let cut = dir.path().join("cut.ckpt");
    std::fs::write(&cut, &bytes[..bytes.len() - 100]).unwrap();
    let mut fresh = build(
        "twisting_cloth_no_contact.toml",
        &["surface.cloth.grid.quads=[4, 4]"],
        dir.path(),
    );
    let e = fresh.restore_checkpoint(&cut).unwrap_err().to_string();
    assert!(e.contains("truncated"), "{e}");

    // The format version is the varint right after the 8-byte magic.
    let this_version = bytes[8];
    assert_eq!(u32::from(this_version), stark::io::CHECKPOINT_FORMAT_VERSION);
    let mut next = bytes.clone();
    next[8] = this_version + 1;
    let other_version = dir.path().join("next.ckpt");
    std::fs::write(&other_version, &next).unwrap();
    let e = fresh.restore_checkpoint(&other_version).unwrap_err().to_string();
    assert!(
        e.contains(&format!("format version {}", this_version + 1)) && e.contains(&format!("to {this_version}")),
        "{e}"
    );

    let e = fresh
        .restore_checkpoint(dir.path().join("missing.ckpt"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("cannot read"), "{e}");
    fresh.restore_checkpoint(&ckpt).unwrap();
    assert_eq!(fresh.time(), sim.time());
}
