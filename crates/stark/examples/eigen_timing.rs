//! Times the symmetric eigen-decomposition used by PSD projection.
use nalgebra::{DMatrix, SMatrix};
use std::hint::black_box;
use std::time::Instant;

fn input(n: usize) -> Vec<f64> {
    let mut h = vec![0.0; n * n];
    for i in 0..n {
        for j in i..n {
            let x = ((i * 7 + j * 13) % 17) as f64 / 17.0 - 0.4 + if i == j { 0.3 } else { 0.0 };
            h[i * n + j] = x;
            h[j * n + i] = x;
        }
    }
    h
}

macro_rules! bench {
    ($n:literal) => {{
        let n = $n;
        let h = input(n);
        let reps = 20000;
        let t = Instant::now();
        let mut w = vec![0.0; n];
        let mut v = vec![0.0; n * n];
        for _ in 0..reps {
            stark::energy::psd::symmetric_eigen(black_box(&h), n, &mut w, &mut v);
        }
        let jac = t.elapsed().as_secs_f64() / reps as f64;
        let m = SMatrix::<f64, $n, $n>::from_row_slice(&h);
        let t = Instant::now();
        let mut acc = 0.0;
        for _ in 0..reps {
            let e = black_box(m).symmetric_eigen();
            acc += e.eigenvalues[0];
        }
        let na = t.elapsed().as_secs_f64() / reps as f64;
        let md = DMatrix::from_row_slice(n, n, &h);
        let t = Instant::now();
        for _ in 0..reps {
            let e = black_box(md.clone()).symmetric_eigen();
            acc += e.eigenvalues[0];
        }
        let nd = t.elapsed().as_secs_f64() / reps as f64;
        println!(
            "n={n}: jacobi {:.2} µs, nalgebra static {:.2} µs, dynamic {:.2} µs ({acc:.1})",
            jac * 1e6,
            na * 1e6,
            nd * 1e6
        );
    }};
}

fn main() {
    bench!(9);
    bench!(12);
}
