//! Times one tet's value/gradient/Hessian: generated kernel against hyper-duals.
use stark::deformables::tet_strain::{tet_energy, ELASTIC_PARAMS, FULL_PARAMS};
use stark::energy::{HyperDual, Scalar, Vec3};
use std::hint::black_box;
use std::time::Instant;

fn main() {
    let x = [
        0.01, 0.0, 0.0, 0.11, 0.01, 0.0, 0.0, 0.1, 0.02, 0.0, 0.01, 0.1,
    ];
    let mut p = [0.0; FULL_PARAMS];
    for i in 0..3 {
        p[4 * i] = 10.0;
    }
    p[9] = 1.6e-4;
    p[10] = 4000.0;
    p[11] = 8000.0;
    p[12] = 1.3;
    p[13] = 30.0;
    p[20] = 0.05;
    p[21] = 1e5;
    let mut g = [0.0; 12];
    let mut h = [0.0; 144];
    let n = 200_000;
    for (name, full) in [("elastic", false), ("full", true)] {
        let t = Instant::now();
        let mut acc = 0.0;
        for _ in 0..n {
            let v = if full {
                stark::generated::tet_strain_full(black_box(&x), black_box(&p), &mut g, &mut h)
            } else {
                stark::generated::tet_strain_elastic(
                    black_box(&x),
                    black_box(&p[..ELASTIC_PARAMS]),
                    &mut g,
                    &mut h,
                )
            };
            acc += v + h[17];
        }
        let gen = t.elapsed().as_secs_f64() / n as f64;
        let t = Instant::now();
        for _ in 0..n / 10 {
            let xs: [Vec3<HyperDual<4>>; 4] = std::array::from_fn(|a| {
                Vec3(std::array::from_fn(|i| {
                    HyperDual::variable(x[3 * a + i], a, i)
                }))
            });
            let ps = p.map(HyperDual::<4>::constant);
            acc += tet_energy(black_box(&xs), &ps, full).value;
        }
        let dual = t.elapsed().as_secs_f64() / (n / 10) as f64;
        println!(
            "tet {name}: generated {:.3} µs, hyper-dual {:.3} µs ({acc:.1})",
            gen * 1e6,
            dual * 1e6
        );
    }
}
