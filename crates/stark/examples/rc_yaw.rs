use nalgebra::{UnitQuaternion, Vector3};
use stark::energy::{EnergyTerm, EvalMode};
use stark::state::{apply_kinematic_map, dof_blocks, EvalState};
use stark::{Settings, Simulation};

fn main() {
    let mut settings = Settings::default();
    settings.contact.default_thickness_m = Some(1e-3);
    let mut sim = Simulation::new(settings).unwrap();
    let fv = [
        Vector3::new(-1.0, -1.0, 0.0),
        Vector3::new(1.0, -1.0, 0.0),
        Vector3::new(1.0, 1.0, 0.0),
        Vector3::new(-1.0, 1.0, 0.0),
    ];
    sim.add_prescribed_surface("floor", &fv, &[[0, 1, 2], [0, 2, 3]], 1e-3, 1e7)
        .unwrap();
    let b = sim
        .add_box(
            "b",
            1.0,
            Vector3::repeat(0.1),
            Vector3::new(0.0, 0.0, 0.0512),
            UnitQuaternion::identity(),
            None,
        )
        .unwrap();
    let dt = 0.01;
    sim.contact.initialize_stiffness(&vec![0.125; sim.nodes.len()], dt);
    let n = dof_blocks(&sim.nodes, &sim.bodies);
    let nn = sim.nodes.len();
    let lin = stark::state::linear_block(nn, b.body.i()) as usize;
    let ang = stark::state::angular_block(nn, b.body.i()) as usize;
    let eval = |sim: &mut Simulation, wz: f64, vz: f64| -> (f64, f64, usize, Vec<String>) {
        let mut v = vec![Vector3::zeros(); n];
        v[ang] = Vector3::new(0.0, 0.0, wz);
        v[lin] = Vector3::new(0.0, 0.0, vz);
        let mut x = vec![];
        let mut poses = vec![];
        apply_kinematic_map(&sim.nodes, &sim.bodies, &v, dt, &mut x, &mut poses);
        let st = EvalState {
            dt,
            time: dt,
            gravity: Vector3::zeros(),
            nodes: &sim.nodes,
            v: &v,
            x: &x,
            bodies: &sim.bodies,
            poses: &poses,
        };
        sim.contact.prepare_evaluation(&st);
        let e = sim.contact.energy(&st);
        // gradient on the angular block, z
        let w = sim.contact.stencil_width(&st);
        let ne = sim.contact.num_elements();
        let mut stencils = vec![0u32; ne * w];
        sim.contact.write_stencils(&st, &mut stencils);
        let mut out = vec![0.0; stark::energy::term::element_stride(w)];
        let mut g = 0.0;
        for e in 0..ne {
            sim.contact
                .evaluate_element(e, &st, EvalMode::ProjectedHessian, &mut out);
            for k in 0..w {
                if stencils[e * w + k] as usize == ang {
                    g += out[1 + 3 * k + 2];
                }
            }
        }
        let kinds = sim
            .contact
            .pairs()
            .iter()
            .map(|p| format!("{:?}{:?}", p.kind, p.nodes))
            .collect();
        (e, g, ne, kinds)
    };
    for vz in [0.0, -0.05] {
        for wz in [-2.0, -1.0, -0.1, -1e-3, 0.0, 1e-3, 0.1, 1.0, 2.0] {
            let (e, g, ne, _) = eval(&mut sim, wz, vz);
            let h = 1e-6;
            let (ep, _, _, _) = eval(&mut sim, wz + h, vz);
            let (em, _, _, _) = eval(&mut sim, wz - h, vz);
            println!(
                "vz {vz} wz {wz:+.3e}: E {e:.9e} dE/dwz {g:+.6e} FD {:+.6e} elements {ne}",
                (ep - em) / (2.0 * h)
            );
        }
    }
    let (_, _, _, kinds) = eval(&mut sim, 0.0, 0.0);
    for k in kinds {
        println!("{k}");
    }
}
