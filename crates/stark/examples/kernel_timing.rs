//! Times one element's value/gradient/Hessian by each path: generated Ψ(F) kernel with and without
//! projection, and hyper-duals.
use nalgebra::Vector3;
use stark::deformables::{NodeSetHandle, TetStrain, TetStrainParams, TriangleStrain, TriangleStrainParams};
use stark::energy::potential::{dual_derivatives, element_derivatives};
use stark::energy::testing::TestState;
use stark::energy::{Potential, Scalar, Stencil};
use std::hint::black_box;
use std::time::Instant;

fn time<const N: usize, P: Potential<N>>(name: &str, p: &P, st: &TestState) {
    let eval = st.eval();
    let stencil = Stencil::new(p.nodes(0), &eval);
    let n = 100_000;
    for (label, project) in [("exact", false), ("projected", true)] {
        let t = Instant::now();
        let mut acc = 0.0;
        for _ in 0..n {
            let mut d = stark::energy::HyperDual::<N>::constant(0.0);
            element_derivatives(p, 0, black_box(&stencil), project, &mut d);
            acc += d.hess[0][0][0][0];
        }
        println!(
            "{name} generated ({label}): {:.3} µs ({acc:.2e})",
            t.elapsed().as_secs_f64() / n as f64 * 1e6
        );
    }
    let t = Instant::now();
    let mut acc = 0.0;
    for _ in 0..n / 10 {
        acc += dual_derivatives(p, 0, black_box(&stencil)).value;
    }
    println!(
        "{name} hyper-dual: {:.3} µs ({acc:.2e})",
        t.elapsed().as_secs_f64() / (n / 10) as f64 * 1e6
    );
}

fn main() {
    let rest = vec![
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(0.1, 0.0, 0.0),
        Vector3::new(0.0, 0.1, 0.0),
        Vector3::new(0.0, 0.0, 0.1),
    ];
    let x0: Vec<_> = rest
        .iter()
        .map(|p| p * 1.02 + Vector3::new(0.001, -0.002, 0.0))
        .collect();
    let v = vec![
        Vector3::new(0.1, 0.0, -0.2),
        Vector3::new(0.0, 0.3, 0.1),
        Vector3::new(-0.1, 0.1, 0.0),
        Vector3::new(0.2, 0.0, 0.1),
    ];
    let st = TestState::new(rest.clone(), x0, vec![Vector3::zeros(); 4], v, 1.0 / 30.0);
    let set = NodeSetHandle {
        index: 0,
        first: 0,
        len: 4,
    };
    for (name, params) in [
        (
            "tet elastic",
            TetStrainParams {
                youngs_modulus: 1e4,
                ..Default::default()
            },
        ),
        (
            "tet damped",
            TetStrainParams {
                youngs_modulus: 1e4,
                damping: 10.0,
                ..Default::default()
            },
        ),
        (
            "tet limited",
            TetStrainParams {
                youngs_modulus: 1e4,
                damping: 10.0,
                strain_limit: 0.001,
                ..Default::default()
            },
        ),
    ] {
        let mut tets = TetStrain::default();
        tets.add(&st.nodes, set, "t", &[[0, 1, 2, 3]], params).unwrap();
        time(name, &tets, &st);
    }
    let mut tris = TriangleStrain::default();
    let p = TriangleStrainParams {
        youngs_modulus: 5e3,
        damping: 0.5,
        strain_limit: 0.1,
        strain_limit_stiffness: 1e6,
        ..Default::default()
    };
    tris.add(&st.nodes, set, "c", &[[0, 1, 2]], p).unwrap();
    time("triangle cotton", &tris, &st);
}
