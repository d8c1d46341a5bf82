use nalgebra::{UnitQuaternion, Vector3};
use stark::{Settings, Simulation};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args[1].parse().unwrap();
    let shrink: f64 = args[2].parse().unwrap();
    let dt: f64 = args[3].parse().unwrap();
    let dur: f64 = args[4].parse().unwrap();
    let eps_v: f64 = args.get(5).map_or(0.01, |s| s.parse().unwrap());
    let mu: f64 = args.get(6).map_or(0.5, |s| s.parse().unwrap());
    let mut settings = Settings::default();
    settings.output.frames = false;
    settings.output.step_log = false;
    settings.time_step_s = dt;
    settings.contact.default_thickness_m = Some(1e-3);
    settings.contact.friction_stick_slide_threshold_m_s = eps_v;
    let mut sim = Simulation::new(settings).unwrap();
    let far = args.get(8).is_some_and(|a| a == "far");
    let fv = if far {
        [
            Vector3::new(-1.0, -5.0, 0.0),
            Vector3::new(9.0, -5.0, 0.0),
            Vector3::new(9.0, 5.0, 0.0),
            Vector3::new(-1.0, 5.0, 0.0),
        ]
    } else {
        [
            Vector3::new(-1.0, -1.0, 0.0),
            Vector3::new(1.0, -1.0, 0.0),
            Vector3::new(1.0, 1.0, 0.0),
            Vector3::new(-1.0, 1.0, 0.0),
        ]
    };
    let floor = sim
        .add_prescribed_surface("floor", &fv, &[[0, 1, 2], [0, 2, 3]], 1e-3, 1e7)
        .unwrap();
    let mut boxes = vec![];
    let mut z = 1e-3;
    for i in 0..n {
        let s = 0.1 - shrink * i as f64;
        let b = sim
            .add_box(
                &format!("b{i}"),
                1.0,
                Vector3::repeat(s),
                Vector3::new(0.0, 0.0, z + 0.5 * s),
                UnitQuaternion::identity(),
                None,
            )
            .unwrap();
        z += s + 1e-3;
        boxes.push(b);
    }
    let mut c = vec![floor.contact];
    c.extend(boxes.iter().map(|b| b.mesh.contact));
    for w in c.windows(2) {
        sim.contact.set_friction(w[0], w[1], mu).unwrap();
    }
    let start: Vec<_> = boxes.iter().map(|b| sim.body_position(b.body)).collect();
    let mut maxpairs = 0;
    let mut report_every = (dur / dt / args.get(7).map_or(10.0, |s| s.parse().unwrap())).round() as usize;
    if report_every == 0 {
        report_every = 1;
    }
    let mut k = 0;
    while sim.time() < dur - 1e-9 {
        let r = sim.step().unwrap();
        let cs = r.contact.unwrap();
        maxpairs = maxpairs.max(cs.active_pairs);
        k += 1;
        if k % report_every == 0 {
            let lat = boxes
                .iter()
                .enumerate()
                .map(|(i, b)| (sim.body_position(b.body) - start[i]).xy().norm())
                .fold(0.0, f64::max);
            let rot = boxes
                .iter()
                .map(|b| sim.body_orientation(b.body).angle())
                .fold(0.0, f64::max);
            let q = sim.body_orientation(boxes[n - 1].body);
            println!(
                "   top axis {:?} w {:?} pos {:?}",
                q.axis().map(|a| a.into_inner()),
                sim.body_angular_velocity(boxes[n - 1].body),
                sim.body_position(boxes[n - 1].body)
            );
            println!(
                "t {:.2} pairs {} fr {} it {} lat {lat:.2e} rot {rot:.2e} mind {:.2e} kappa {:.2e}",
                sim.time(),
                cs.active_pairs,
                cs.friction_pairs,
                r.newton_iterations,
                cs.min_distance_m,
                cs.stiffness
            );
        }
    }
    println!("{:?}", sim.summary().times);
    println!(
        "steps {} newton {} wall {:.2}",
        sim.summary().steps,
        sim.summary().newton_iterations,
        sim.summary().wall_time_s
    );
}
