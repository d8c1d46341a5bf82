//! The run-time path (energy::jit) against the built-in generated kernels (BENCHMARKS.md, "Your
//! own energy"): `cargo run --release -p stark --example jit_bench`.
//!
//! 1. Kernel: the Stable Neo-Hookean `Ψ(F)` kernel (9 inputs), rustc-compiled ahead of time vs
//!    traced and compiled with Cranelift at run time (same expression graph).
//! 2. Element: the built-in tet (`TetStrain::derivatives`: F, generated kernel, map to the 12
//!    node coordinates) vs a `UserEnergy` of the same energy written in node positions.
//! 3. Trace, differentiation and compile time per energy, cold, with the disk cache, and from
//!    the memory cache.
use nalgebra::{Matrix3, Vector3};
use stark::deformables::tet_strain::{kernels, tet_psi, Limiting};
use stark::deformables::{NodeSetHandle, TetStrain, TetStrainParams};
use stark::energy::jit;
use stark::energy::symbolic::Sym;
use stark::energy::testing::TestState;
use stark::energy::{trace_element, HyperDual, Mat, Mat3, Node, Potential, Stencil, UserEnergy, Vec3};
use stark::generated;
use std::hint::black_box;
use std::time::Instant;

/// Median of `rounds` timings of `n` calls, µs per call.
fn per_call(n: usize, mut f: impl FnMut() -> f64) -> f64 {
    let mut times: Vec<f64> = (0..9)
        .map(|_| {
            let t = Instant::now();
            let mut acc = 0.0;
            for _ in 0..n {
                acc += f();
            }
            black_box(acc);
            t.elapsed().as_secs_f64() / n as f64 * 1e6
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

/// `V ψ(F)` of a tet written in node positions with parameters `[D_m⁻¹ (9), V, μ', λ', α]`.
fn tet_in_positions(x: &[Vec3<Sym>], p: &[Sym]) -> Sym {
    let ds = Mat3::from_columns3([x[1] - x[0], x[2] - x[0], x[3] - x[0]]);
    let dm_inv: Mat3<Sym> = Mat([[p[0], p[1], p[2]], [p[3], p[4], p[5]], [p[6], p[7], p[8]]]);
    tet_psi(&ds.mul_mat(&dm_inv), &p[9..], false, Limiting::Off)
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
    let eval = st.eval();
    let set = NodeSetHandle {
        index: 0,
        first: 0,
        len: 4,
    };
    let params = TetStrainParams::default();
    let mut tets = TetStrain::default();
    tets.add(&st.nodes, set, "tet", &[[0, 1, 2, 3]], params.clone())
        .unwrap();
    let stencil = Stencil::new(tets.nodes(0), &eval);

    // 1. Kernel against kernel.
    let (mu, lambda) = params.lame();
    let (mu_, lambda_) = (4.0 / 3.0 * mu, lambda + 5.0 / 6.0 * mu);
    let dm = Matrix3::from_columns(&[rest[1] - rest[0], rest[2] - rest[0], rest[3] - rest[0]]);
    let volume = dm.determinant() / 6.0;
    let psi = [
        volume,
        mu_,
        lambda_,
        1.0 + 0.75 * mu_ / lambda_,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        1.0,
        0.0,
    ];
    let f = [1.02, 0.01, -0.02, 0.0, 0.98, 0.03, 0.01, 0.0, 1.05];
    let specs = kernels();
    let spec = &specs[0];
    let t = Instant::now();
    let psi_jit = jit::compile_fn(9, spec.n_params, spec.energy).unwrap();
    let psi_ms = t.elapsed().as_secs_f64() * 1e3;
    let n = 200_000;
    let (mut g, mut h) = ([0.0; 9], [0.0; 81]);
    let builtin_kernel = per_call(n, || {
        generated::tet_psi_elastic(black_box(&f), &psi, &mut g, &mut h) + h[40]
    });
    let (mut g2, mut h2) = ([0.0; 9], [0.0; 81]);
    let jit_kernel = per_call(n, || psi_jit.evaluate(black_box(&f), &psi, &mut g2, &mut h2) + h2[40]);
    let diff = g
        .iter()
        .chain(&h)
        .zip(g2.iter().chain(&h2))
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    println!("Ψ(F) kernel (9 inputs): built-in {builtin_kernel:.3} µs, JIT {jit_kernel:.3} µs ({:.2}×), max |difference| {diff:.1e}, traced+compiled in {psi_ms:.1} ms", jit_kernel / builtin_kernel);

    // 2. Element against element.
    let inv = dm.try_inverse().unwrap();
    let mut p = vec![0.0; 13];
    for i in 0..3 {
        for j in 0..3 {
            p[3 * i + j] = inv[(i, j)];
        }
    }
    p[9..].copy_from_slice(&psi[..4]);
    let traced = trace_element(4, 13, |a| Ok(tet_in_positions(&a.x, &a.p))).unwrap();
    let names = (0..13).map(|k| format!("p{k}")).collect();
    let user = UserEnergy::<4>::new("tet", vec![[0, 1, 2, 3].map(Node::Point)], names, &p, traced).unwrap();
    let mut d = HyperDual::<4>::constant(0.0);
    let builtin_el = per_call(n, || {
        tets.derivatives(0, black_box(&stencil), false, &mut d);
        d.hess[1][1][1][1]
    });
    let mut d2 = HyperDual::<4>::constant(0.0);
    let jit_el = per_call(n, || {
        user.derivatives(0, black_box(&stencil), false, &mut d2);
        d2.hess[1][1][1][1]
    });
    let scale = d
        .hess
        .as_flattened()
        .as_flattened()
        .as_flattened()
        .iter()
        .fold(0.0f64, |m, x| m.max(x.abs()));
    let diff = d
        .hess
        .as_flattened()
        .as_flattened()
        .as_flattened()
        .iter()
        .zip(d2.hess.as_flattened().as_flattened().as_flattened())
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    let dual = per_call(n / 20, || {
        stark::energy::potential::dual_derivatives(&tets, 0, black_box(&stencil)).value
    });
    println!("tet element, value+gradient+Hessian in node positions (12 inputs): built-in {builtin_el:.3} µs, JIT UserEnergy {jit_el:.3} µs ({:.2}×), hyper-duals {dual:.2} µs; Hessian relative difference {:.1e}", jit_el / builtin_el, diff / scale);

    // 3. Trace / differentiate / compile per energy.
    let dir = std::env::temp_dir().join(format!("stark-jit-bench-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    println!("energy | inputs | program ops | trace ms | differentiate ms | compile ms | with disk cache: differentiate + compile ms | memory cache µs");
    type Energy = fn(&stark::energy::ElementArgs<Sym>) -> stark::Result<Sym>;
    let cases: [(&str, usize, usize, Energy); 3] = [
        ("magnet −k/√(r²+ε²)", 1, 5, |a| {
            Ok(stark::scenes::magnet_energy(&a.x[0], &a.p))
        }),
        ("spring + damper", 2, 3, |a| {
            let d = a.x[1] - a.x[0];
            let dv = a.v[1] - a.v[0];
            Ok((d.norm() - a.p[1]).sq() * a.p[0] * 0.5 + a.p[2] * a.dt * dv.norm_sq() * 0.5)
        }),
        ("Stable Neo-Hookean tet", 4, 13, |a| Ok(tet_in_positions(&a.x, &a.p))),
    ];
    use stark::energy::Scalar;
    for (name, nodes, n_params, energy) in cases {
        let t = Instant::now();
        let traced = trace_element(nodes, n_params, energy).unwrap();
        let trace_ms = t.elapsed().as_secs_f64() * 1e3;
        let cold = jit::compile_uncached(&traced, Some(dir.clone())).unwrap();
        let warm = jit::compile_uncached(&traced, Some(dir.clone())).unwrap();
        assert!(warm.timings.from_disk);
        jit::compile(&traced).unwrap();
        let t = Instant::now();
        let again = trace_element(nodes, n_params, energy).unwrap();
        jit::compile(&again).unwrap();
        let mem_us = t.elapsed().as_secs_f64() * 1e6;
        println!(
            "{name} | {} | {} | {trace_ms:.2} | {:.2} | {:.2} | {:.2} | {mem_us:.0} (trace + lookup)",
            3 * nodes,
            cold.timings.program_ops,
            cold.timings.differentiate_ms,
            cold.timings.compile_ms,
            warm.timings.differentiate_ms + warm.timings.compile_ms,
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
