use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use stark::{Settings, Simulation};

fn run(dt: f64, w0: Vector3<f64>, t_end: f64) -> (f64, f64, Vec<(f64, Vector3<f64>, Vector3<f64>, f64)>) {
    let mut s = Settings::default();
    s.output.frames = false;
    s.output.step_log = false;
    s.time_step_s = dt;
    s.gravity_m_s2 = [0.0; 3];
    s.newton.residual_tolerance_n = 1e-10;
    s.newton.step_tolerance_m_s = 0.0;
    s.newton.linear_solver = stark::solver::LinearSolver::Cholesky;
    s.threads = 1;
    let mut sim = Simulation::new(s).unwrap();
    let j = Matrix3::from_diagonal(&Vector3::new(1.0, 2.0, 3.0));
    let b = sim
        .add_rigid_body("b", 1.0, j, Vector3::zeros(), UnitQuaternion::identity())
        .unwrap();
    sim.set_body_angular_velocity(b, w0).unwrap();
    let l0 = sim.body_angular_momentum(b);
    let e0 = 0.5 * w0.dot(&l0);
    let mut maxdrift: f64 = 0.0;
    let mut trace = vec![];
    while sim.time() < t_end - 1e-9 {
        sim.step().unwrap();
        let l = sim.body_angular_momentum(b);
        maxdrift = maxdrift.max((l - l0).norm() / l0.norm());
        let w = sim.body_angular_velocity(b);
        let e = 0.5 * w.dot(&l);
        let k = if w0.x.abs() > 1.0 {
            0
        } else if w0.y.abs() > 1.0 {
            1
        } else {
            2
        };
        let ax3 = sim.body_direction_to_world(b, &Vector3::ith(k, 1.0));
        trace.push((sim.time(), l, ax3, e / e0));
    }
    let ef = trace.last().unwrap().3;
    (maxdrift, ef, trace)
}

fn main() {
    let w0 = Vector3::new(1.0, 0.5, 2.0);
    for dt in [1e-2, 1e-3] {
        let (d, ef, _) = run(dt, w0, 2.0);
        println!("dt {dt}: max |L-L0|/|L0| {d:.3e}, E/E0 at end {ef:.6}");
    }
    // major/minor axes
    for dt in [1e-2, 1e-3] {
        let (_, ef, tr) = run(dt, Vector3::new(5.0, 0.01, 0.01), 40.0);
        let lhat = tr[0].1.normalize();
        for (t, _, ax, e) in tr.iter().step_by((4.0 / dt) as usize) {
            println!(
                "minor dt {dt} t {t:.1}: angle {:.4e} E/E0 {e:.6}",
                ax.dot(&lhat).clamp(-1.0, 1.0).acos()
            );
        }
        let _ = ef;
    }
    for (name, w) in [
        ("major", Vector3::new(0.01, 0.01, 5.0)),
        ("minor", Vector3::new(5.0, 0.01, 0.01)),
        ("inter", Vector3::new(0.01, 5.0, 0.01)),
    ] {
        for dt in [1e-2, 1e-3] {
            let (d, ef, tr) = run(dt, w, 10.0);
            let lhat = tr[0].1.normalize();
            let mut maxang: f64 = 0.0;
            let mut t_flip: Option<f64> = None;
            for (t, _l, ax, _) in &tr {
                let ang = ax.dot(&lhat).clamp(-1.0, 1.0).acos();
                maxang = maxang.max(ang);
                if ang > 1.5 && t_flip.is_none() {
                    t_flip = Some(*t);
                }
            }
            println!(
                "{name} dt {dt}: L drift {d:.3e}, E/E0 {ef:.6}, max axis angle {maxang:.4} rad, flip at {t_flip:?}"
            );
        }
    }
}
