//! Block-Jacobi preconditioned conjugate gradients (the default linear solver, as in Stark's
//! BDPCG): the preconditioner inverts the 3×3 diagonal blocks.

use super::block_sparse::{dot, dot_lanes, BlockSparseMatrix};
use nalgebra::Matrix3;
use rayon::prelude::*;
use std::sync::atomic::Ordering::{AcqRel, Acquire, Relaxed, Release};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize};

/// Outcome of a CG solve.
#[derive(Clone, Copy, Debug, Default)]
pub struct CgInfo {
    /// Iterations performed.
    pub iterations: usize,
    /// Final preconditioner-free residual norm `‖b − A x‖₂`.
    pub residual_norm: f64,
    /// The tolerance was reached.
    pub converged: bool,
    /// A direction of non-positive curvature was met (the matrix is not positive definite); the
    /// iterate before it is returned.
    pub indefinite: bool,
}

/// Inverse diagonal blocks of `a`. A singular block (a DOF with no stiffness and no mass) is
/// replaced by the identity, so the preconditioner stays well defined.
pub fn block_jacobi(a: &BlockSparseMatrix) -> Vec<[f64; 9]> {
    (0..a.n_blocks)
        .into_par_iter()
        .map(|r| {
            let b = &a.values[a.diagonal[r]];
            let m = Matrix3::from_row_slice(b);
            match m.try_inverse() {
                Some(inv) if inv.iter().all(|x| x.is_finite()) => {
                    let mut out = [0.0; 9];
                    for i in 0..3 {
                        for j in 0..3 {
                            out[3 * i + j] = inv[(i, j)];
                        }
                    }
                    out
                }
                _ => [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
            }
        })
        .collect()
}

/// `z = M⁻¹ r` on a range of whole blocks (`inv_diag` the range's inverse diagonal blocks).
fn apply_preconditioner(inv_diag: &[[f64; 9]], r: &[f64], z: &mut [f64]) {
    for ((z, r), m) in z.chunks_exact_mut(3).zip(r.chunks_exact(3)).zip(inv_diag) {
        z[0] = m[0] * r[0] + m[1] * r[1] + m[2] * r[2];
        z[1] = m[3] * r[0] + m[4] * r[1] + m[5] * r[2];
        z[2] = m[6] * r[0] + m[7] * r[1] + m[8] * r[2];
    }
}

/// Solve `A x = b` to `‖b − A x‖₂ ≤ tolerance`, starting from `x = 0`, block-Jacobi
/// preconditioned.
///
/// The vectors are cut into chunks of block rows, a function of the size only, and each
/// iteration runs three passes over them (the product with its `p · Ap`; the updates of `x` and
/// `r` with the preconditioner and `r · r`, `r · z`; the new direction), each pass's chunks
/// shared by the pool's threads. The threads stay in the solve from its start to its end,
/// taking chunks as they come: a CG iteration of a 10k-unknown cloth lasts ~0.1 ms, too short for
/// a parallel loop per vector operation, whose idle threads go to sleep between them and wake
/// too late to take a share (two threads on hanging_cloth_64: the second did a tenth of the
/// solve's work, BENCHMARKS.md). The calling thread takes chunks from the front, the others from
/// the back, so that each thread keeps passing over nearly the same rows and finds them in its own
/// cache (taken in one order, the rows changed threads from pass to pass: two threads on a cloth
/// under boxes, 0.67–0.80 s of CG against 0.60–0.63 s; BENCHMARKS.md). Partial sums are kept per
/// chunk and added in chunk order: the result does not depend on the thread count or on who took
/// which chunk.
pub fn solve(a: &BlockSparseMatrix, b: &[f64], x: &mut [f64], tolerance: f64, max_iterations: usize) -> CgInfo {
    let inv_diag = block_jacobi(a);
    let n = b.len();
    assert_eq!(n, a.dim(), "right-hand side of the wrong size");
    assert_eq!(x.len(), n, "solution of the wrong size");
    let rows = a.n_blocks;
    let rows_per_chunk = (rows / CHUNKS_PER_SOLVE).clamp(MIN_ROWS_PER_CHUNK, MAX_ROWS_PER_CHUNK);
    let chunks = rows.div_ceil(rows_per_chunk).max(1);
    // The claims count chunks in 16 bits (`Team::work`).
    assert!(chunks < 1 << 16, "{chunks} CG chunks");
    let mut vectors = vec![0.0; 4 * n];
    let mut partials = vec![0.0; 3 * chunks];
    let (r, rest) = vectors.split_at_mut(n);
    let (z, rest) = rest.split_at_mut(n);
    let (p, ap) = rest.split_at_mut(n);
    let (pap, rest) = partials.split_at_mut(chunks);
    let (rr, rz) = rest.split_at_mut(chunks);
    let team = Team {
        a,
        inv_diag: &inv_diag,
        b,
        rows_per_chunk,
        chunks,
        x: Shared::new(x),
        r: Shared::new(r),
        z: Shared::new(z),
        p: Shared::new(p),
        ap: Shared::new(ap),
        pap: Shared::new(pap),
        rr: Shared::new(rr),
        rz: Shared::new(rz),
        work: AtomicU64::new(0),
        pass: AtomicU64::new(0),
        scalar: AtomicU64::new(0),
        done: AtomicUsize::new(0),
        finished: AtomicBool::new(false),
    };
    let helpers = rayon::current_num_threads().min(chunks) - 1;
    if helpers == 0 {
        return team.lead(tolerance, max_iterations);
    }
    let mut info = CgInfo::default();
    rayon::scope(|s| {
        for _ in 0..helpers {
            s.spawn(|_| team.help());
        }
        info = team.lead(tolerance, max_iterations);
        team.finished.store(true, Release);
    });
    info
}

/// [`solve`]'s chunking: about this many chunks per solve, so that the threads share them
/// evenly whatever the size, with chunks of at least `MIN_ROWS_PER_CHUNK` block rows (a pass
/// over fewer costs less than handing it out) and at most `MAX_ROWS_PER_CHUNK`.
const CHUNKS_PER_SOLVE: usize = 16;
const MIN_ROWS_PER_CHUNK: usize = 64;
const MAX_ROWS_PER_CHUNK: usize = 2048;

/// A pass of [`solve`] over the chunks.
#[derive(Clone, Copy)]
enum Pass {
    /// `x = 0`, `r = b`, `z = M⁻¹ r`, `p = z`; partial `r · r` and `r · z`.
    Start = 1,
    /// `Ap`; partial `p · Ap`.
    Product = 2,
    /// `x += α p`, `r −= α Ap`, `z = M⁻¹ r`; partial `r · r` and `r · z`.
    Update = 3,
    /// `p = z + β p`.
    Direction = 4,
}

/// Which end of a pass's chunks a thread takes from.
#[derive(Clone, Copy)]
enum End {
    Front,
    Back,
}

/// A slice written by several threads, each in chunks it alone has claimed.
#[derive(Clone, Copy)]
struct Shared {
    ptr: *mut f64,
    len: usize,
}

// SAFETY: `Team`'s protocol gives every chunk of a pass to exactly one thread, and a pass reads
// other chunks only of vectors that no thread writes in it (the product reads all of `p`).
unsafe impl Send for Shared {}
unsafe impl Sync for Shared {}

impl Shared {
    fn new(v: &mut [f64]) -> Self {
        Shared {
            ptr: v.as_mut_ptr(),
            len: v.len(),
        }
    }

    /// # Safety
    /// No other thread accesses `range` while the slice lives.
    #[allow(clippy::mut_from_ref)]
    unsafe fn slice_mut(&self, range: std::ops::Range<usize>) -> &mut [f64] {
        assert!(range.start <= range.end && range.end <= self.len);
        std::slice::from_raw_parts_mut(self.ptr.add(range.start), range.len())
    }

    /// # Safety
    /// No thread writes `range` while the slice lives.
    unsafe fn slice(&self, range: std::ops::Range<usize>) -> &[f64] {
        assert!(range.start <= range.end && range.end <= self.len);
        std::slice::from_raw_parts(self.ptr.add(range.start), range.len())
    }
}

/// The state of one [`solve`], shared by the thread that leads it (the caller: it decides,
/// sums and takes chunks) and the helpers (they take chunks until the solve is finished).
struct Team<'a> {
    a: &'a BlockSparseMatrix,
    inv_diag: &'a [[f64; 9]],
    b: &'a [f64],
    rows_per_chunk: usize,
    chunks: usize,
    x: Shared,
    r: Shared,
    z: Shared,
    p: Shared,
    ap: Shared,
    /// Per chunk: `p · Ap`, `r · r`, `r · z`.
    pap: Shared,
    rr: Shared,
    rz: Shared,
    /// The pass's sequence number (high 32 bits), the number of chunks taken from the front (the
    /// next 16 bits) and from the back (the low 16 bits).
    work: AtomicU64,
    /// The pass's kind and its scalar (α or β, as bits); written before `work` announces it.
    pass: AtomicU64,
    scalar: AtomicU64,
    /// Chunks of the current pass finished.
    done: AtomicUsize,
    finished: AtomicBool,
}

impl Team<'_> {
    /// The CG iteration: passes over the chunks, sums of their partials in chunk order, and the
    /// decisions, on the calling thread.
    fn lead(&self, tolerance: f64, max_iterations: usize) -> CgInfo {
        let mut sequence = 0u64;
        let mut pass = |kind: Pass, scalar: f64| {
            sequence += 1;
            self.pass.store(kind as u64, Relaxed);
            self.scalar.store(scalar.to_bits(), Relaxed);
            self.done.store(0, Relaxed);
            self.work.store(sequence << 32, Release);
            self.take_chunks(sequence, End::Front);
            spin_until(|| self.done.load(Acquire) == self.chunks);
        };
        // SAFETY (the sums): read after the pass, when every chunk is done and no thread writes.
        let sum = |v: &Shared| unsafe { v.slice(0..self.chunks) }.iter().sum::<f64>();
        pass(Pass::Start, 0.0);
        let mut rz = sum(&self.rz);
        let mut info = CgInfo {
            residual_norm: sum(&self.rr).sqrt(),
            ..Default::default()
        };
        if info.residual_norm <= tolerance {
            info.converged = true;
            return info;
        }
        while info.iterations < max_iterations {
            pass(Pass::Product, 0.0);
            let pap = sum(&self.pap);
            if pap <= 0.0 || !pap.is_finite() {
                info.indefinite = true;
                break;
            }
            pass(Pass::Update, rz / pap);
            info.iterations += 1;
            info.residual_norm = sum(&self.rr).sqrt();
            if info.residual_norm <= tolerance {
                info.converged = true;
                break;
            }
            let rz_new = sum(&self.rz);
            let beta = rz_new / rz;
            rz = rz_new;
            pass(Pass::Direction, beta);
        }
        info
    }

    /// A helper: take the chunks of each pass as it is announced, until the solve is finished.
    fn help(&self) {
        let mut seen = 0u64;
        loop {
            let mut sequence = seen;
            spin_until(|| {
                sequence = self.work.load(Acquire) >> 32;
                sequence != seen || self.finished.load(Acquire)
            });
            if self.finished.load(Acquire) {
                return;
            }
            seen = sequence;
            self.take_chunks(sequence, End::Back);
        }
    }

    /// Claim and run the chunks of pass `sequence` from `end` until none is left.
    fn take_chunks(&self, sequence: u64, end: End) {
        loop {
            let work = self.work.load(Acquire);
            let (front, back) = ((work >> 16) as u16 as usize, work as u16 as usize);
            if work >> 32 != sequence || front + back >= self.chunks {
                return;
            }
            let (next, chunk) = match end {
                End::Front => (work + (1 << 16), front),
                End::Back => (work + 1, self.chunks - 1 - back),
            };
            if self.work.compare_exchange_weak(work, next, AcqRel, Relaxed).is_ok() {
                // The pass cannot have moved on: its chunk `chunk` was not done yet.
                let kind = self.pass.load(Relaxed);
                let scalar = f64::from_bits(self.scalar.load(Relaxed));
                self.run_chunk(kind, scalar, chunk);
                self.done.fetch_add(1, Release);
            }
        }
    }

    fn run_chunk(&self, kind: u64, scalar: f64, chunk: usize) {
        let first = chunk * self.rows_per_chunk;
        let rows = first..(first + self.rows_per_chunk).min(self.a.n_blocks);
        let s = 3 * rows.start..3 * rows.end;
        let inv_diag = &self.inv_diag[rows.clone()];
        // SAFETY: this thread alone claimed `chunk` of the pass (`take_chunks`); the other
        // chunks of the vectors written here are not read in this pass, and `p`, read whole in
        // the product, is written in no product.
        unsafe {
            match kind {
                k if k == Pass::Start as u64 => {
                    let (x, r, z, p) = (
                        self.x.slice_mut(s.clone()),
                        self.r.slice_mut(s.clone()),
                        self.z.slice_mut(s.clone()),
                        self.p.slice_mut(s.clone()),
                    );
                    x.fill(0.0);
                    r.copy_from_slice(&self.b[s.clone()]);
                    apply_preconditioner(inv_diag, r, z);
                    p.copy_from_slice(z);
                    self.rr.slice_mut(chunk..chunk + 1)[0] = dot_lanes(r, r);
                    self.rz.slice_mut(chunk..chunk + 1)[0] = dot_lanes(r, z);
                }
                k if k == Pass::Product as u64 => {
                    let p = self.p.slice(0..self.p.len);
                    let ap = self.ap.slice_mut(s.clone());
                    self.pap.slice_mut(chunk..chunk + 1)[0] = self.a.mul_rows_dot(rows, p, ap);
                }
                k if k == Pass::Update as u64 => {
                    let alpha = scalar;
                    let (x, r, z) = (
                        self.x.slice_mut(s.clone()),
                        self.r.slice_mut(s.clone()),
                        self.z.slice_mut(s.clone()),
                    );
                    let (p, ap) = (self.p.slice(s.clone()), self.ap.slice(s.clone()));
                    for (x, p) in x.iter_mut().zip(p) {
                        *x += alpha * p;
                    }
                    for (r, ap) in r.iter_mut().zip(ap) {
                        *r -= alpha * ap;
                    }
                    apply_preconditioner(inv_diag, r, z);
                    self.rr.slice_mut(chunk..chunk + 1)[0] = dot_lanes(r, r);
                    self.rz.slice_mut(chunk..chunk + 1)[0] = dot_lanes(r, z);
                }
                _ => {
                    let beta = scalar;
                    let (p, z) = (self.p.slice_mut(s.clone()), self.z.slice(s.clone()));
                    for (p, z) in p.iter_mut().zip(z) {
                        *p = z + beta * *p;
                    }
                }
            }
        }
    }
}

/// Wait for `ready`: spinning first (a pass of the solve lasts microseconds), then yielding the
/// core (another process may need it: a sweep's cases side by side).
fn spin_until(mut ready: impl FnMut() -> bool) {
    let mut spins = 0u32;
    while !ready() {
        if spins < SPINS_BEFORE_YIELD {
            std::hint::spin_loop();
            spins += 1;
        } else {
            std::thread::yield_now();
        }
    }
}

const SPINS_BEFORE_YIELD: u32 = 1 << 14;

/// [`solve`] with the preconditioner `precondition(r, z)`: `z ≈ A⁻¹ r` (symmetric positive
/// definite).
pub fn solve_preconditioned(
    a: &BlockSparseMatrix,
    b: &[f64],
    x: &mut [f64],
    tolerance: f64,
    max_iterations: usize,
    precondition: &mut dyn FnMut(&[f64], &mut [f64]),
) -> CgInfo {
    solve_with_product(
        &mut |p, ap| a.mul_vec_dot(p, ap),
        b,
        x,
        tolerance,
        max_iterations,
        precondition,
    )
}

/// [`solve_preconditioned`] with the product given: `product(p, ap)` sets `ap = A p` and returns
/// `p · ap` (e.g. over the matrix's upper triangle,
/// [`super::block_sparse::UpperTriangle::product_dot`]).
pub fn solve_with_product(
    product: &mut dyn FnMut(&[f64], &mut [f64]) -> f64,
    b: &[f64],
    x: &mut [f64],
    tolerance: f64,
    max_iterations: usize,
    precondition: &mut dyn FnMut(&[f64], &mut [f64]),
) -> CgInfo {
    let n = b.len();
    x.iter_mut().for_each(|v| *v = 0.0);
    let mut r = b.to_vec();
    let mut z = vec![0.0; n];
    let mut ap = vec![0.0; n];
    precondition(&r, &mut z);
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut info = CgInfo {
        residual_norm: dot(&r, &r).sqrt(),
        ..Default::default()
    };
    if info.residual_norm <= tolerance {
        info.converged = true;
        return info;
    }
    while info.iterations < max_iterations {
        let pap = product(&p, &mut ap);
        if pap <= 0.0 || !pap.is_finite() {
            info.indefinite = true;
            break;
        }
        let alpha = rz / pap;
        x.par_iter_mut().zip(p.par_iter()).for_each(|(x, p)| *x += alpha * p);
        r.par_iter_mut().zip(ap.par_iter()).for_each(|(r, ap)| *r -= alpha * ap);
        info.iterations += 1;
        info.residual_norm = dot(&r, &r).sqrt();
        if info.residual_norm <= tolerance {
            info.converged = true;
            break;
        }
        precondition(&r, &mut z);
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        p.par_iter_mut().zip(z.par_iter()).for_each(|(p, z)| *p = z + beta * *p);
    }
    info
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 1D chain of 3×3 blocks: tridiagonal SPD (Laplacian plus mass).
    fn chain(n: usize) -> BlockSparseMatrix {
        let mut pairs = vec![];
        for i in 0..n as u32 {
            if i > 0 {
                pairs.push((i, i - 1));
            }
            pairs.push((i, i));
            if (i as usize) < n - 1 {
                pairs.push((i, i + 1));
            }
        }
        let mut a = BlockSparseMatrix::from_sorted_pairs(n, &pairs);
        for r in 0..n {
            for idx in a.row_start[r]..a.row_start[r + 1] {
                let c = a.cols[idx] as usize;
                let v = if c == r { 2.1 } else { -1.0 };
                a.values[idx] = [
                    v,
                    0.0,
                    0.0,
                    0.0,
                    v * 1.5,
                    0.1 * (c == r) as i32 as f64,
                    0.0,
                    0.1 * (c == r) as i32 as f64,
                    v,
                ];
            }
        }
        a
    }

    #[test]
    fn solves_spd_chain() {
        for n in [5, 50, 400] {
            let a = chain(n);
            let b: Vec<f64> = (0..3 * n).map(|i| ((i * 7) % 11) as f64 - 5.0).collect();
            let mut x = vec![0.0; 3 * n];
            let info = solve(&a, &b, &mut x, 1e-12, 10_000);
            assert!(info.converged, "{info:?}");
            let mut ax = vec![0.0; 3 * n];
            a.mul_vec(&x, &mut ax);
            let err = ax.iter().zip(&b).map(|(p, q)| (p - q).abs()).fold(0.0, f64::max);
            assert!(err < 1e-10 * n as f64, "n = {n}: {err}");
        }
    }

    /// The chunks' partial sums are added in chunk order whatever thread ran them: the same
    /// bits at one, two and five threads (more threads than some solves have chunks).
    #[test]
    fn same_bits_at_any_thread_count() {
        for n in [7, 300, 5000] {
            let a = chain(n);
            let b: Vec<f64> = (0..3 * n).map(|i| ((i * 13) % 17) as f64 - 8.0).collect();
            let run = |threads: usize| {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                let mut x = vec![0.0; 3 * n];
                let info = pool.install(|| solve(&a, &b, &mut x, 1e-9, 10_000));
                (x, info.iterations, info.residual_norm.to_bits())
            };
            let one = run(1);
            assert!(one.1 > 0);
            for threads in [2, 5] {
                let other = run(threads);
                assert_eq!(one.1, other.1, "n = {n}, {threads} threads: iterations");
                assert_eq!(one.2, other.2, "n = {n}, {threads} threads: residual");
                assert!(
                    one.0.iter().zip(&other.0).all(|(p, q)| p.to_bits() == q.to_bits()),
                    "n = {n}, {threads} threads: solution"
                );
            }
        }
    }

    /// A direction of negative curvature stops the solve with the iterate before it.
    #[test]
    fn reports_an_indefinite_matrix() {
        let mut a = chain(600);
        for r in 0..600 {
            if r % 2 == 1 {
                let d = a.diagonal[r];
                a.values[d][0] = -5.0;
            }
        }
        let b = vec![1.0; 1800];
        let mut x = vec![0.0; 1800];
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let info = pool.install(|| solve(&a, &b, &mut x, 1e-12, 10_000));
        assert!(info.indefinite && !info.converged, "{info:?}");
        assert!(x.iter().all(|v| v.is_finite()));
    }
}
