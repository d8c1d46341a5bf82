//! Smoothed-aggregation algebraic multigrid (Vaněk, Mandel & Brezina 1996) as CG's
//! preconditioner on the 3×3-block Hessian (`LinearSolver::Amg`).
//!
//! Block-Jacobi CG needs more iterations the finer the mesh (a cloth's: 35 per Newton iteration at
//! 32², 466 at 256²): it only relaxes errors a few elements long, and the long smooth ones take
//! a number of iterations that grows with the node count along the cloth. Multigrid relaxes each
//! wavelength on a grid of its own size: nodes strongly coupled through the matrix are grouped
//! into aggregates of a node and its neighbours; each aggregate moves by the near-null space's
//! modes (the motions that cost no elastic energy: the three translations, and for shells the
//! three rotations too, whose local versions are bending's low-energy motions), orthonormalised
//! per aggregate, so that every coarse unknown is again a 3-block (a translation or a rotation
//! of an aggregate); this interpolation is smoothed by one damped Jacobi step (it then bends with
//! the elements), and the coarse matrix is the Galerkin product `Pᵀ A P`, recursively until a
//! dense Cholesky takes the last few hundred unknowns. One V-cycle with Chebyshev smoothing (a
//! fixed polynomial in `D⁻¹A`: symmetric, parallel, no ordering) is the preconditioner.
//! The cycle reads its matrices (each level's, the prolongators, the smoothers' inverted
//! diagonal blocks) rounded to single precision: its passes over them are memory-bound, and a
//! cycle over rounded matrices is still a fixed symmetric operator (a hanging 128² cloth: the
//! same CG iterations, the linear solve −23%). Each level's matrix is read as its upper block
//! triangle alone ([`UpperTriangle`]: every off-diagonal block applied to both its rows), as is
//! the finest one in CG's own product: half the bytes again.
//!
//! Where it stands (BENCHMARKS.md, "Algebraic multigrid"): CG's iteration count stays nearly flat
//! under refinement (a membrane-like grid: 13–14 from 16² to 128²; the hanging cloths with the
//! rotations: 5–15 per Newton iteration from 32² to 256², block Jacobi 35–466), but the
//! hierarchy's set-up (the Galerkin products) and the V-cycle's passes over memory make it pay
//! only on the largest meshes.
//!
//! A hierarchy's interpolation (aggregates and prolongators) serves later matrices of the same
//! unknowns: [`Amg::refresh_levels`] recomputes the levels' Galerkin matrices on the patterns
//! kept from the last time (values only: on a 128² cloth ~30 ms against ~90 for a new hierarchy)
//! and their smoothers; the Newton solver decides when ([`crate::solver::newton`]).
//!
//! Everything is built from the matrix and the unknowns' positions (rigid-body blocks included:
//! they join aggregates where the coupling is strong, and are left to the smoother where it is
//! weak), deterministic and independent of the thread count (rows are computed independently).

use super::block_sparse::{dot, Block, BlockSparseMatrix, UpperScratch, UpperTriangle, ROWS_PER_TASK};
use super::pcg::block_jacobi;
use nalgebra::DMatrix;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Blocks `i ≠ j` are strongly coupled when `‖A_ij‖ ≥ θ √(‖A_ii‖ ‖A_jj‖)` (Frobenius norms): the
/// classical threshold of smoothed aggregation for elasticity.
const STRENGTH_THRESHOLD: f64 = 0.08;
/// A level with at most this many blocks is solved directly (dense Cholesky of ≤ 600 unknowns:
/// ~7 M multiply-adds, once per solve).
const COARSEST_BLOCKS: usize = 200;
/// Levels at most (a coarsening that stalls stops earlier).
const MAX_LEVELS: usize = 16;
/// Degree of the Chebyshev smoothing polynomial (matrix products per sweep). One (a damped
/// block-Jacobi sweep) costs least per CG iteration: on a 128² cloth, 12 CG iterations per Newton
/// iteration at 2.6–3.6 ms each against degree two's 8 at 5.6–6.9 ms.
const CHEBYSHEV_DEGREE: usize = 1;
/// The Chebyshev polynomial damps the eigenvalues of `D⁻¹A` in `[λ_max / ratio, λ_max]`; the
/// smaller ones are the coarse levels' to reduce.
const CHEBYSHEV_EIGEN_RATIO: f64 = 30.0;
/// Power iterations estimating `λ_max(D⁻¹A)` per level.
const POWER_ITERATIONS: usize = 12;
/// Power iterations when the finest level's smoother is refitted to a later Hessian, from the
/// top eigenvector of the last.
const REFRESH_POWER_ITERATIONS: usize = 4;
/// The estimate is from below: the smoother's interval and the prolongator's damping use it
/// enlarged by this factor.
const SPECTRAL_SAFETY: f64 = 1.1;

/// `a b` of two row-major 3×3 blocks.
#[inline]
fn mul(a: &Block, b: &Block) -> Block {
    let mut c = [0.0; 9];
    for i in 0..3 {
        for j in 0..3 {
            c[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
        }
    }
    c
}

/// `aᵀ`.
#[inline]
fn transpose(a: &Block) -> Block {
    [a[0], a[3], a[6], a[1], a[4], a[7], a[2], a[5], a[8]]
}

/// A 3×3 block being summed: each row padded to four lanes, so that a row is one aligned
/// vector (rows stored as overlapping 4-wide vectors would defeat the store-to-load forwarding
/// between consecutive additions to the same block).
#[derive(Clone, Copy, Default)]
#[repr(C, align(32))]
struct PaddedBlock([[f64; 4]; 3]);

impl PaddedBlock {
    fn block(&self) -> Block {
        let [r0, r1, r2] = &self.0;
        [r0[0], r0[1], r0[2], r1[0], r1[1], r1[2], r2[0], r2[1], r2[2]]
    }
}

/// `acc += a b` (3×3 blocks, row-major): row `i` of the product is `Σ_k a_ik b_k·`.
#[inline(always)]
fn multiply_add(acc: &mut PaddedBlock, a: &Block, b: &Block) {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2", target_feature = "fma"))]
    // SAFETY: AVX2 and FMA are compile-time features. The rows of `b` are read as 4-wide
    // vectors whose lane 3 is the next row's first entry (the third row's is masked); it lands
    // in `acc`'s padding lane, never read.
    unsafe {
        use std::arch::x86_64::*;
        let first3 = _mm256_set_epi64x(0, -1, -1, -1);
        let bp = b.as_ptr();
        let b0 = _mm256_loadu_pd(bp);
        let b1 = _mm256_loadu_pd(bp.add(3));
        let b2 = _mm256_maskload_pd(bp.add(6), first3);
        for (i, row) in acc.0.iter_mut().enumerate() {
            let c = _mm256_load_pd(row.as_ptr());
            let c = _mm256_fmadd_pd(_mm256_set1_pd(a[3 * i]), b0, c);
            let c = _mm256_fmadd_pd(_mm256_set1_pd(a[3 * i + 1]), b1, c);
            let c = _mm256_fmadd_pd(_mm256_set1_pd(a[3 * i + 2]), b2, c);
            _mm256_store_pd(row.as_mut_ptr(), c);
        }
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2", target_feature = "fma")))]
    {
        let p = mul(a, b);
        for (i, row) in acc.0.iter_mut().enumerate() {
            for j in 0..3 {
                row[j] += p[3 * i + j];
            }
        }
    }
}

#[inline]
fn add_scaled(acc: &mut Block, s: f64, b: &Block) {
    for (x, y) in acc.iter_mut().zip(b) {
        *x += s * y;
    }
}

#[inline]
fn apply(b: &Block, x: &[f64]) -> [f64; 3] {
    [
        b[0] * x[0] + b[1] * x[1] + b[2] * x[2],
        b[3] * x[0] + b[4] * x[1] + b[5] * x[2],
        b[6] * x[0] + b[7] * x[1] + b[8] * x[2],
    ]
}

/// A 3×3 block, row-major, in single precision.
type Block32 = [f32; 9];

/// The blocks rounded to single precision. The V-cycle's passes over its matrices are
/// memory-bound, and its operator only has to stay fixed, linear and symmetric, which the cycle
/// over the rounded matrices is (a block and its transpose round alike); CG's own product keeps
/// the full matrix.
fn single(values: &[Block]) -> Vec<Block32> {
    let mut out = Vec::new();
    single_into(values, &mut out);
    out
}

/// [`single`] into `out`, reusing its allocation (the finest level's copy is renewed at every
/// Newton iteration).
fn single_into(values: &[Block], out: &mut Vec<Block32>) {
    out.resize(values.len(), [0.0; 9]);
    out.par_chunks_mut(4096)
        .zip(values.par_chunks(4096))
        .for_each(|(out, values)| {
            for (o, v) in out.as_flattened_mut().iter_mut().zip(values.as_flattened()) {
                *o = *v as f32;
            }
        });
}

#[inline]
fn apply32(b: &Block32, x: &[f64]) -> [f64; 3] {
    let b = b.map(f64::from);
    apply(&b, x)
}

/// `Σ_k M_k x_{c_k}` over the blocks `values` with columns `cols` (a block row of a level
/// matrix or of the prolongator), the blocks in single precision.
#[inline(always)]
fn row_times32(cols: &[u32], values: &[Block32], x: &[f64]) -> [f64; 3] {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2", target_feature = "fma"))]
    {
        // SAFETY: the target has AVX2 and FMA (compile-time features); every load reads inside
        // its block or its 3-vector of `x` (masked loads for the block's last row and for `x`),
        // and each column is checked against `x` before the read.
        unsafe {
            use std::arch::x86_64::*;
            let first3 = _mm256_set_epi64x(0, -1, -1, -1);
            let first3_ps = _mm_set_epi32(0, -1, -1, -1);
            let (mut p0, mut p1, mut p2) = (_mm256_setzero_pd(), _mm256_setzero_pd(), _mm256_setzero_pd());
            for (&c, b) in cols.iter().zip(values) {
                let c = c as usize;
                assert!(3 * c + 3 <= x.len(), "block column {c} beyond the vector");
                let xc = _mm256_maskload_pd(x.as_ptr().add(3 * c), first3);
                let bp = b.as_ptr();
                // Lane 3 of the first two rows holds the next row's first entry, times x's zero.
                p0 = _mm256_fmadd_pd(_mm256_cvtps_pd(_mm_loadu_ps(bp)), xc, p0);
                p1 = _mm256_fmadd_pd(_mm256_cvtps_pd(_mm_loadu_ps(bp.add(3))), xc, p1);
                p2 = _mm256_fmadd_pd(_mm256_cvtps_pd(_mm_maskload_ps(bp.add(6), first3_ps)), xc, p2);
            }
            let mut lanes = [[0.0; 4]; 3];
            _mm256_storeu_pd(lanes[0].as_mut_ptr(), p0);
            _mm256_storeu_pd(lanes[1].as_mut_ptr(), p1);
            _mm256_storeu_pd(lanes[2].as_mut_ptr(), p2);
            lanes.map(|l| l[0] + l[1] + l[2])
        }
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2", target_feature = "fma")))]
    {
        let mut acc = [0.0; 3];
        for (&c, b) in cols.iter().zip(values) {
            let c = c as usize;
            let p = apply32(b, &x[3 * c..3 * c + 3]);
            acc[0] += p[0];
            acc[1] += p[1];
            acc[2] += p[2];
        }
        acc
    }
}

/// A rectangular matrix of 3×3 block rows as the cycle reads it (a prolongator or a
/// restriction): its pattern, and its blocks in single precision.
#[derive(Clone, Copy)]
struct CycleMatrix<'a> {
    row_start: &'a [usize],
    cols: &'a [u32],
    values: &'a [Block32],
}

impl<'a> CycleMatrix<'a> {
    /// The rectangular `m` with `values`, its blocks in single precision.
    fn of_rows(m: &'a BlockRows, values: &'a [Block32]) -> Self {
        assert_eq!(
            values.len(),
            m.values.len(),
            "single-precision blocks of another matrix"
        );
        Self {
            row_start: &m.row_start,
            cols: &m.cols,
            values,
        }
    }

    /// `combine(y_r, (A x)_r)` for every block row `r` of `y`, one pass over the rows (in
    /// parallel over fixed chunks of rows).
    fn each_row_product(self, x: &[f64], y: &mut [f64], combine: impl Fn(&mut [f64], [f64; 3]) + Sync) {
        y.par_chunks_mut(3 * ROWS_PER_TASK).enumerate().for_each(|(chunk, ys)| {
            let first = chunk * ROWS_PER_TASK;
            for (k, yr) in ys.chunks_exact_mut(3).enumerate() {
                let span = self.row_start[first + k]..self.row_start[first + k + 1];
                combine(yr, row_times32(&self.cols[span.clone()], &self.values[span], x));
            }
        });
    }
}

/// A level's matrix as the cycle reads it: its upper block triangle in single precision.
type LevelMatrix32 = UpperTriangle<Block32>;

/// `r −= A x` over the rounded matrix.
fn subtract_product32(a: &LevelMatrix32, x: &[f64], r: &mut [f64], scratch: &mut UpperScratch) {
    a.product_with(x, r, scratch, |_, rr, p| {
        for i in 0..3 {
            rr[i] -= p[i];
        }
    });
}

/// `r = b − A x` over the rounded matrix.
fn residual_into32(a: &LevelMatrix32, x: &[f64], b: &[f64], r: &mut [f64], scratch: &mut UpperScratch) {
    a.product_with(x, r, scratch, |row, rr, p| {
        for i in 0..3 {
            rr[i] = b[3 * row + i] - p[i];
        }
    });
}

/// A rectangular matrix of 3×3 blocks, rows compressed (the prolongator and its transpose).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
struct BlockRows {
    n_cols: usize,
    row_start: Vec<usize>,
    cols: Vec<u32>,
    values: Vec<Block>,
}

impl BlockRows {
    fn n_rows(&self) -> usize {
        self.row_start.len() - 1
    }

    fn row(&self, r: usize) -> impl Iterator<Item = (usize, &Block)> {
        let span = self.row_start[r]..self.row_start[r + 1];
        self.cols[span.clone()]
            .iter()
            .map(|&c| c as usize)
            .zip(&self.values[span])
    }

    /// Rows computed independently by `row(r, out)` (sorted, unique columns appended to `out`),
    /// in parallel over fixed chunks and concatenated in order.
    fn from_rows(n_rows: usize, n_cols: usize, row: impl Fn(usize, &mut Vec<(u32, Block)>) + Sync) -> BlockRows {
        // Per chunk: each row's length, and the rows' entries one after the other.
        type Chunk = (Vec<usize>, Vec<(u32, Block)>);
        let chunks: Vec<Chunk> = (0..n_rows.div_ceil(ROWS_PER_TASK))
            .into_par_iter()
            .map(|chunk| {
                let rows = chunk * ROWS_PER_TASK..((chunk + 1) * ROWS_PER_TASK).min(n_rows);
                let mut lengths = Vec::with_capacity(rows.len());
                let mut entries = Vec::new();
                for r in rows {
                    let before = entries.len();
                    row(r, &mut entries);
                    lengths.push(entries.len() - before);
                }
                (lengths, entries)
            })
            .collect();
        let total = chunks.iter().map(|(_, entries)| entries.len()).sum();
        let mut out = BlockRows {
            n_cols,
            row_start: Vec::with_capacity(n_rows + 1),
            cols: Vec::with_capacity(total),
            values: Vec::with_capacity(total),
        };
        out.row_start.push(0);
        for (lengths, entries) in &chunks {
            let mut end = *out.row_start.last().expect("row 0 starts");
            out.row_start.extend(lengths.iter().map(|l| {
                end += l;
                end
            }));
            out.cols.extend(entries.iter().map(|e| e.0));
            out.values.extend(entries.iter().map(|e| e.1));
        }
        out
    }

    /// `y = M x`.
    #[cfg(test)]
    fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        y.par_chunks_mut(3 * ROWS_PER_TASK).enumerate().for_each(|(chunk, ys)| {
            for (k, yr) in ys.chunks_exact_mut(3).enumerate() {
                let mut acc = [0.0; 3];
                for (c, b) in self.row(chunk * ROWS_PER_TASK + k) {
                    let p = apply(b, &x[3 * c..3 * c + 3]);
                    acc[0] += p[0];
                    acc[1] += p[1];
                    acc[2] += p[2];
                }
                yr.copy_from_slice(&acc);
            }
        });
    }

    /// `y = M x` with `values`, this matrix's blocks in single precision.
    fn mul_vec32(&self, values: &[Block32], x: &[f64], y: &mut [f64]) {
        CycleMatrix::of_rows(self, values).each_row_product(x, y, |yr, p| yr.copy_from_slice(&p));
    }

    /// `Mᵀ`.
    fn transposed(&self) -> BlockRows {
        let mut row_start = vec![0usize; self.n_cols + 1];
        for &c in &self.cols {
            row_start[c as usize + 1] += 1;
        }
        for i in 0..self.n_cols {
            row_start[i + 1] += row_start[i];
        }
        let mut next = row_start.clone();
        let mut cols = vec![0u32; self.cols.len()];
        let mut values = vec![[0.0; 9]; self.cols.len()];
        // Rows visited in order: each transposed row's columns come out sorted.
        for r in 0..self.n_rows() {
            for (c, b) in self.row(r) {
                cols[next[c]] = r as u32;
                values[next[c]] = transpose(b);
                next[c] += 1;
            }
        }
        BlockRows {
            n_cols: self.n_rows(),
            row_start,
            cols,
            values,
        }
    }
}

/// Row `r` of `Σ_k L_rk R_k·` accumulated over a dense marker (Gustavson's product), its
/// columns sorted.
struct RowAccumulator {
    slot: Vec<u32>,
    touched: Vec<u32>,
    sums: Vec<PaddedBlock>,
}

impl RowAccumulator {
    const EMPTY: u32 = u32::MAX;

    fn new(n_cols: usize) -> Self {
        Self {
            slot: vec![Self::EMPTY; n_cols],
            touched: Vec::new(),
            sums: Vec::new(),
        }
    }

    /// Column `c` of the row `+= l r`.
    #[inline(always)]
    fn add_product(&mut self, c: usize, l: &Block, r: &Block) {
        let k = self.slot[c];
        let sum = if k == Self::EMPTY {
            self.slot[c] = self.touched.len() as u32;
            self.touched.push(c as u32);
            self.sums.push(PaddedBlock::default());
            self.sums.last_mut().expect("just pushed")
        } else {
            &mut self.sums[k as usize]
        };
        multiply_add(sum, l, r);
    }

    /// Append the row, sorted by column, to `out` and reset.
    fn drain_into(&mut self, out: &mut Vec<(u32, Block)>) {
        // Sort the columns (4 bytes each), then gather the sums (72 each) in that order.
        self.touched.sort_unstable();
        out.reserve(self.touched.len());
        for &c in &self.touched {
            let k = std::mem::replace(&mut self.slot[c as usize], Self::EMPTY);
            out.push((c, self.sums[k as usize].block()));
        }
        self.touched.clear();
        self.sums.clear();
    }
}

/// `L R` for `L` with rows given by `left_row(r)` (columns index rows of `right`).
fn product<'a, F, I>(n_rows: usize, right: &BlockRows, left_row: F) -> BlockRows
where
    F: Fn(usize) -> I + Sync,
    I: Iterator<Item = (usize, &'a Block)>,
{
    product_from(n_rows, right, left_row, |_| 0)
}

/// The blocks of `L R` in columns `first_column(r)..` of each row `r` (see [`product`]).
fn product_from<'a, F, I>(
    n_rows: usize,
    right: &BlockRows,
    left_row: F,
    first_column: impl Fn(usize) -> usize + Sync,
) -> BlockRows
where
    F: Fn(usize) -> I + Sync,
    I: Iterator<Item = (usize, &'a Block)>,
{
    let n_cols = right.n_cols;
    BlockRows::from_rows(n_rows, n_cols, |r, out| {
        thread_local! {
            static ACC: std::cell::RefCell<Option<RowAccumulator>> = const { std::cell::RefCell::new(None) };
        }
        ACC.with(|acc| {
            let mut acc = acc.borrow_mut();
            if acc.as_ref().is_none_or(|a| a.slot.len() != n_cols) {
                *acc = Some(RowAccumulator::new(n_cols));
            }
            let acc = acc.as_mut().expect("accumulator present");
            let first = first_column(r);
            for (k, l) in left_row(r) {
                for (c, rb) in right.row(k) {
                    if c >= first {
                        acc.add_product(c, l, rb);
                    }
                }
            }
            acc.drain_into(out);
        });
    })
}

/// The values of `L R` into `out`, whose pattern holds every block of it in columns
/// `first_column(r)..` of each row `r` (the pattern of an earlier [`product_from`] of the same
/// patterns).
fn product_values<'a, F, I>(
    out: &mut BlockRows,
    right: &BlockRows,
    left_row: F,
    first_column: impl Fn(usize) -> usize + Sync,
) where
    F: Fn(usize) -> I + Sync,
    I: Iterator<Item = (usize, &'a Block)>,
{
    let n_rows = out.n_rows();
    let n_cols = right.n_cols;
    let row_start = &out.row_start;
    let cols = &out.cols;
    // Rows in fixed chunks of `ROWS_PER_TASK`: each chunk's values are one slice of `out.values`.
    let mut chunks: Vec<&mut [Block]> = Vec::with_capacity(n_rows.div_ceil(ROWS_PER_TASK));
    let mut rest = out.values.as_mut_slice();
    for chunk in 0..n_rows.div_ceil(ROWS_PER_TASK) {
        let rows = chunk * ROWS_PER_TASK..((chunk + 1) * ROWS_PER_TASK).min(n_rows);
        let (here, tail) = rest.split_at_mut(row_start[rows.end] - row_start[rows.start]);
        chunks.push(here);
        rest = tail;
    }
    chunks.into_par_iter().enumerate().for_each(|(chunk, values)| {
        thread_local! {
            static SCRATCH: std::cell::RefCell<(Vec<u32>, Vec<PaddedBlock>)> =
                const { std::cell::RefCell::new((Vec::new(), Vec::new())) };
        }
        SCRATCH.with(|scratch| {
            let (slot, sums) = &mut *scratch.borrow_mut();
            if slot.len() != n_cols {
                *slot = vec![u32::MAX; n_cols];
            }
            let first_row = chunk * ROWS_PER_TASK;
            let base = row_start[first_row];
            for r in first_row..((chunk + 1) * ROWS_PER_TASK).min(n_rows) {
                let span = row_start[r]..row_start[r + 1];
                sums.clear();
                sums.resize(span.len(), PaddedBlock::default());
                for (k, &c) in cols[span.clone()].iter().enumerate() {
                    slot[c as usize] = k as u32;
                }
                let first = first_column(r);
                for (k, l) in left_row(r) {
                    for (c, rb) in right.row(k) {
                        if c >= first {
                            multiply_add(&mut sums[slot[c] as usize], l, rb);
                        }
                    }
                }
                for (k, &c) in cols[span.clone()].iter().enumerate() {
                    slot[c as usize] = u32::MAX;
                    values[span.start - base + k] = sums[k].block();
                }
            }
        });
    });
}

/// The values of the symmetric `matrix` (the pattern [`mirrored`] made of an `upper` of this
/// pattern) from its upper block triangle `upper`.
fn mirror_values(upper: &BlockRows, matrix: &mut BlockSparseMatrix) {
    let n = upper.n_rows();
    let mut next_lower = matrix.row_start[..n].to_vec();
    for r in 0..n {
        let d = matrix.diagonal[r];
        for (k, (c, b)) in upper.row(r).enumerate() {
            matrix.values[d + k] = *b;
            if c != r {
                matrix.values[next_lower[c]] = transpose(b);
                next_lower[c] += 1;
            }
        }
    }
}

/// `λ_max(D⁻¹A)` from below, by power iteration from a fixed start (the Rayleigh quotient of the
/// symmetric `D^{-½} A D^{-½}`, in `A`'s inner product), on `A` rounded to single precision (the
/// cycle's matrix, and half the bytes per pass).
fn spectral_radius(a: &LevelMatrix32, inv_diag: &[Block], work: &mut Work) -> f64 {
    power_iteration(
        a,
        inv_diag,
        &mut start_vector(inv_diag.len() * 3),
        POWER_ITERATIONS,
        work,
    )
}

/// A fixed pseudo-random start: not orthogonal to the top mode, the same every run.
fn start_vector(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| {
            let h = (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
            ((h >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        })
        .collect()
}

/// `iterations` power iterations on `D⁻¹A` from `x` (left at the last iterate); the last
/// Rayleigh quotient. The level's cycle vectors serve as scratch (`r` for `A x`, `d` for
/// `D⁻¹A x`).
fn power_iteration(a: &LevelMatrix32, inv_diag: &[Block], x: &mut [f64], iterations: usize, work: &mut Work) -> f64 {
    let Work {
        r: ax, d: y, scratch, ..
    } = work;
    let mut lambda = 0.0;
    for _ in 0..iterations {
        // The estimate only sets the smoother's interval: the rounded matrix serves.
        a.product(x, ax, scratch);
        let xax = dot(x, ax);
        // y = D⁻¹ A x
        y.par_chunks_mut(3)
            .zip(ax.par_chunks(3))
            .zip(inv_diag.par_iter())
            .for_each(|((y, r), m)| {
                y.copy_from_slice(&apply(m, r));
            });
        let axy = dot(ax, y);
        if xax <= 0.0 || !axy.is_finite() {
            break;
        }
        lambda = axy / xax;
        let norm = dot(y, y).sqrt();
        if norm == 0.0 {
            break;
        }
        x.par_iter_mut().zip(&*y).for_each(|(x, y)| *x = y / norm);
    }
    lambda
}

/// The near-null space on one level: the motions that cost (nearly) no elastic energy, which
/// interpolation must reproduce exactly. Per 3-block, its rows of the mode matrix (3 × `columns`,
/// row-major), and which node the block belongs to (a node's blocks aggregate together: on coarse
/// levels an aggregate's translation and rotation blocks).
#[derive(Clone, Debug)]
pub struct NearNullSpace {
    /// 3 (the translations) or 6 (translations and rotations).
    columns: usize,
    rows: Vec<[f64; 18]>,
    node_of_block: Vec<u32>,
    n_nodes: usize,
}

/// What a 3-block of unknowns is, for the rigid motions of the whole.
#[derive(Clone, Copy, Debug)]
pub enum BlockMotion {
    /// A velocity at a point (a node, or a body's linear velocity at its centre of mass), m.
    Point([f64; 3]),
    /// A body's angular velocity.
    Angular,
}

impl NearNullSpace {
    /// The three translations: each block moves as a 3-vector.
    pub fn translations(n_blocks: usize) -> Self {
        let mut row = [0.0; 18];
        (row[0], row[4], row[8]) = (1.0, 1.0, 1.0);
        Self {
            columns: 3,
            rows: vec![row; n_blocks],
            node_of_block: (0..n_blocks as u32).collect(),
            n_nodes: n_blocks,
        }
    }

    /// The six rigid motions `v = t + ω × x`: `[I | −[x]×]` at a point, `[0 | I]` for an angular
    /// velocity. Shells and plates need the rotations: their low-energy motions are local
    /// rotations (bending), which piecewise translations do not span.
    pub fn rigid_motions(blocks: &[BlockMotion]) -> Self {
        let rows = blocks
            .iter()
            .map(|b| {
                let mut row = [0.0; 18];
                match *b {
                    BlockMotion::Point([x, y, z]) => {
                        // Row-major 3 × 6: [1 0 0 | 0 z −y; 0 1 0 | −z 0 x; 0 0 1 | y −x 0].
                        (row[0], row[7], row[14]) = (1.0, 1.0, 1.0);
                        (row[4], row[5]) = (z, -y);
                        (row[9], row[11]) = (-z, x);
                        (row[15], row[16]) = (y, -x);
                    }
                    BlockMotion::Angular => (row[3], row[10], row[17]) = (1.0, 1.0, 1.0),
                }
                row
            })
            .collect();
        Self {
            columns: 6,
            rows,
            node_of_block: (0..blocks.len() as u32).collect(),
            n_nodes: blocks.len(),
        }
    }
}

/// Aggregates of strongly coupled nodes: `aggregate[node]` (`u32::MAX`: none, a node coupled
/// only weakly, left to the smoother) and their number. Nodes `I ≠ J` are strongly coupled when
/// `‖A_IJ‖ ≥ θ √(‖A_II‖ ‖A_JJ‖)` (Frobenius norms over their blocks).
fn aggregate(a: &BlockSparseMatrix, space: &NearNullSpace) -> (Vec<u32>, usize, Vec<Vec<usize>>) {
    const NONE: u32 = u32::MAX;
    let n = space.n_nodes;
    let mut blocks_of_node: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (b, &node) in space.node_of_block.iter().enumerate() {
        blocks_of_node[node as usize].push(b as u32);
    }
    // Squared norms of the node couplings, row by row.
    let mut coupling: Vec<Vec<(u32, f64)>> = Vec::with_capacity(n);
    let mut slot = vec![u32::MAX; n];
    for blocks in &blocks_of_node {
        let mut row: Vec<(u32, f64)> = Vec::new();
        for &r in blocks {
            for idx in a.row_start[r as usize]..a.row_start[r as usize + 1] {
                let node = space.node_of_block[a.cols[idx] as usize];
                let f2: f64 = a.values[idx].iter().map(|x| x * x).sum();
                match slot[node as usize] {
                    u32::MAX => {
                        slot[node as usize] = row.len() as u32;
                        row.push((node, f2));
                    }
                    k => row[k as usize].1 += f2,
                }
            }
        }
        for &(node, _) in &row {
            slot[node as usize] = u32::MAX;
        }
        coupling.push(row);
    }
    let diag: Vec<f64> = (0..n)
        .map(|i| {
            coupling[i]
                .iter()
                .find(|e| e.0 as usize == i)
                .map_or(0.0, |e| e.1.sqrt())
        })
        .collect();
    let strong: Vec<Vec<usize>> = (0..n)
        .map(|i| {
            coupling[i]
                .iter()
                .filter(|&&(j, f2)| {
                    j as usize != i && f2.sqrt() >= STRENGTH_THRESHOLD * (diag[i] * diag[j as usize]).sqrt()
                })
                .map(|&(j, _)| j as usize)
                .collect()
        })
        .collect();
    let mut agg = vec![NONE; n];
    let mut count = 0u32;
    // 1: a node whose strong neighbours are all free seeds an aggregate with them.
    for r in 0..n {
        if agg[r] == NONE && !strong[r].is_empty() && strong[r].iter().all(|&c| agg[c] == NONE) {
            agg[r] = count;
            for &c in &strong[r] {
                agg[c] = count;
            }
            count += 1;
        }
    }
    // 2: the rest join a neighbouring aggregate of step 1.
    let first_pass = agg.clone();
    for r in 0..n {
        if agg[r] == NONE {
            if let Some(&c) = strong[r].iter().find(|&&c| first_pass[c] != NONE) {
                agg[r] = first_pass[c];
            }
        }
    }
    // 3: what is still free (strong neighbours all in new aggregates) seeds new ones.
    for r in 0..n {
        if agg[r] == NONE && !strong[r].is_empty() {
            agg[r] = count;
            for &c in &strong[r] {
                if agg[c] == NONE {
                    agg[c] = count;
                }
            }
            count += 1;
        }
    }
    (agg, count as usize, strong)
}

/// One level below the finest: how to get there and back.
struct Level {
    /// The coarse level's matrix.
    matrix: BlockSparseMatrix,
    /// Prolongator from this coarse level to the one above, and its transpose (restriction).
    prolongator: BlockRows,
    restriction: BlockRows,
    /// The three in single precision, which the cycle reads (the matrix's upper block triangle).
    matrix32: LevelMatrix32,
    prolongator32: Vec<Block32>,
    restriction32: Vec<Block32>,
    /// The Galerkin product's intermediates, whose patterns serve again for a later fine matrix
    /// of the same pattern.
    products: GalerkinProducts,
}

/// The smoother's data on one level (finest included).
struct Smoother {
    /// The inverses of the matrix's diagonal blocks, in single precision.
    inv_diag32: Vec<Block32>,
    lambda_max: f64,
    degree: usize,
}

impl Smoother {
    fn new(inv_diag: &[Block], lambda_max: f64) -> Self {
        Self {
            inv_diag32: single(inv_diag),
            lambda_max,
            degree: CHEBYSHEV_DEGREE,
        }
    }
}

enum CoarsestSolve {
    Cholesky(nalgebra::Cholesky<f64, nalgebra::Dyn>),
    /// A singular coarsest matrix: its pseudo-inverse.
    PseudoInverse(DMatrix<f64>),
}

/// A level's vectors during a cycle.
struct Work {
    /// Right-hand side and solution.
    b: Vec<f64>,
    x: Vec<f64>,
    /// Residual, Chebyshev direction.
    r: Vec<f64>,
    d: Vec<f64>,
    /// The symmetric products' scratch.
    scratch: UpperScratch,
}

impl Work {
    fn new(n: usize) -> Self {
        Self {
            b: vec![0.0; n],
            x: vec![0.0; n],
            r: vec![0.0; n],
            d: vec![0.0; n],
            scratch: UpperScratch::default(),
        }
    }
}

/// The multigrid hierarchy of one matrix.
pub struct Amg {
    levels: Vec<Level>,
    smoothers: Vec<Smoother>,
    coarsest: CoarsestSolve,
    work: Vec<Work>,
    /// The finest level's last power iterate (its top eigenvector, nearly).
    top: Vec<f64>,
    /// The finest matrix (the one last built from or refitted to) as the cycle reads it.
    finest32: LevelMatrix32,
}

/// The part of a hierarchy that [`Amg::refresh_levels`] keeps (saved in checkpoints).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Interpolation {
    prolongators: Vec<BlockRows>,
    top: Vec<f64>,
}

/// Statistics of a hierarchy (logs and tests).
#[derive(Clone, Debug, PartialEq)]
pub struct AmgShape {
    /// Blocks per level, finest first.
    pub blocks: Vec<usize>,
    /// Stored blocks per level.
    pub nnz_blocks: Vec<usize>,
}

impl Amg {
    /// Build the hierarchy of `a` (symmetric positive definite, as a Newton Hessian projected or
    /// held definite).
    pub fn new(a: &BlockSparseMatrix) -> Amg {
        Self::with_near_null_space(a, NearNullSpace::translations(a.n_blocks))
    }

    /// [`Amg::new`] with the given near-null space of the finest level (e.g.
    /// [`NearNullSpace::rigid_motions`] of the unknowns' positions).
    pub fn with_near_null_space(a: &BlockSparseMatrix, mut space: NearNullSpace) -> Amg {
        let mut levels: Vec<Level> = Vec::new();
        let mut smoothers = Vec::new();
        let mut top = Vec::new();
        let mut work = Vec::new();
        let finest32 = LevelMatrix32::of(a);
        loop {
            let fine = levels.last().map_or(a, |l| &l.matrix);
            let fine32 = levels.last().map_or(&finest32, |l| &l.matrix32);
            let inv_diag = block_jacobi(fine);
            // The level's cycle vectors, first the power iteration's scratch.
            work.push(Work::new(fine.dim()));
            let level_work = work.last_mut().expect("just pushed");
            let lambda_max = if levels.is_empty() {
                top = start_vector(a.dim());
                SPECTRAL_SAFETY * power_iteration(fine32, &inv_diag, &mut top, POWER_ITERATIONS, level_work)
            } else {
                SPECTRAL_SAFETY * spectral_radius(fine32, &inv_diag, level_work)
            };
            let done = fine.n_blocks <= COARSEST_BLOCKS || levels.len() + 1 >= MAX_LEVELS;
            let next = if done {
                None
            } else {
                let (agg, n_agg, strong) = aggregate(fine, &space);
                // A coarsening that barely shrinks the level is not worth a level.
                (n_agg > 0 && ((n_agg * space.columns / 3) as f64) < 0.85 * fine.n_blocks as f64)
                    .then(|| coarsen(fine, lambda_max, &space, &agg, n_agg, &strong))
            };
            smoothers.push(Smoother::new(&inv_diag, lambda_max));
            match next {
                Some((level, coarse_space)) => {
                    levels.push(level);
                    space = coarse_space;
                }
                None => break,
            }
        }
        let coarsest = coarsest_solve(levels.last().map_or(a, |l| &l.matrix));
        Amg {
            levels,
            smoothers,
            coarsest,
            work,
            top,
            finest32,
        }
    }

    /// The hierarchy can precondition `a`: the same number of blocks as the matrix it was built
    /// from (the coarse levels of an earlier Hessian of the same unknowns).
    pub fn fits(&self, a: &BlockSparseMatrix) -> bool {
        self.work[0].b.len() == a.dim()
    }

    /// Keep the coarse levels, and fit the finest level's smoother to `a` (a later Hessian of
    /// the same unknowns; the power iteration continues from the last one's top eigenvector).
    pub fn refresh_finest(&mut self, a: &BlockSparseMatrix) {
        let inv_diag = block_jacobi(a);
        self.finest32.refill(a);
        let a32 = &self.finest32;
        let finest_work = &mut self.work[0];
        let mut lambda_max =
            SPECTRAL_SAFETY * power_iteration(a32, &inv_diag, &mut self.top, REFRESH_POWER_ITERATIONS, finest_work);
        if lambda_max <= 0.0 || !lambda_max.is_finite() {
            lambda_max = SPECTRAL_SAFETY * spectral_radius(a32, &inv_diag, finest_work);
        }
        let finest = &mut self.smoothers[0];
        single_into(&inv_diag, &mut finest.inv_diag32);
        finest.lambda_max = lambda_max;
    }

    /// Keep the interpolation (aggregates and prolongators), and recompute everything that
    /// depends on the matrix from `a` (a later Hessian of the same unknowns): every level's
    /// Galerkin matrix, smoother and the coarsest factorisation.
    pub fn refresh_levels(&mut self, a: &BlockSparseMatrix) {
        self.refresh_finest(a);
        for l in 0..self.levels.len() {
            let (above, below) = self.levels.split_at_mut(l);
            let fine = above.last().map_or(a, |lv| &lv.matrix);
            let level = &mut below[0];
            regalerkin(
                fine,
                &level.prolongator,
                &level.restriction,
                &mut level.products,
                &mut level.matrix,
            );
            level.matrix32.refill(&level.matrix);
            let inv_diag = block_jacobi(&level.matrix);
            let lambda_max = SPECTRAL_SAFETY * spectral_radius(&level.matrix32, &inv_diag, &mut self.work[l + 1]);
            self.smoothers[l + 1] = Smoother::new(&inv_diag, lambda_max);
        }
        self.coarsest = coarsest_solve(self.levels.last().map_or(a, |l| &l.matrix));
    }

    /// What [`Amg::refresh_levels`] keeps: the prolongators, and the finest level's last power
    /// iterate (where the next estimate of its smoother's interval starts).
    pub fn interpolation(&self) -> Interpolation {
        Interpolation {
            prolongators: self.levels.iter().map(|l| l.prolongator.clone()).collect(),
            top: self.top.clone(),
        }
    }

    /// A hierarchy of `interpolation` whose matrices are not yet computed: it serves only after
    /// [`Amg::refresh_levels`], which computes them from a matrix exactly as for the hierarchy
    /// the interpolation came from (the Galerkin products' values do not depend on whether
    /// their patterns were kept).
    pub fn from_interpolation(interpolation: Interpolation) -> Result<Amg, String> {
        let Interpolation { prolongators, top } = interpolation;
        let mut fine_blocks = top.len() / 3;
        for (l, p) in prolongators.iter().enumerate() {
            let consistent = p.row_start.len() == fine_blocks + 1
                && p.row_start.first() == Some(&0)
                && p.row_start.windows(2).all(|w| w[0] <= w[1])
                && p.row_start.last() == Some(&p.cols.len())
                && p.values.len() == p.cols.len()
                && p.cols.iter().all(|&c| (c as usize) < p.n_cols);
            if !consistent {
                return Err(format!(
                    "the multigrid prolongator of level {l} does not fit the level above"
                ));
            }
            fine_blocks = p.n_cols;
        }
        let mut work = vec![Work::new(top.len())];
        let levels = prolongators
            .into_iter()
            .map(|prolongator| {
                work.push(Work::new(3 * prolongator.n_cols));
                let restriction = prolongator.transposed();
                Level {
                    matrix: BlockSparseMatrix::default(),
                    matrix32: LevelMatrix32::default(),
                    prolongator32: single(&prolongator.values),
                    restriction32: single(&restriction.values),
                    prolongator,
                    restriction,
                    products: GalerkinProducts::default(),
                }
            })
            .collect::<Vec<_>>();
        let smoothers = (0..=levels.len()).map(|_| Smoother::new(&[], 0.0)).collect();
        Ok(Amg {
            levels,
            smoothers,
            coarsest: CoarsestSolve::PseudoInverse(DMatrix::zeros(0, 0)),
            work,
            top,
            finest32: LevelMatrix32::default(),
        })
    }

    /// Blocks and stored blocks per level.
    pub fn shape(&self, a: &BlockSparseMatrix) -> AmgShape {
        let mut blocks = vec![a.n_blocks];
        let mut nnz_blocks = vec![a.nnz_blocks()];
        for l in &self.levels {
            blocks.push(l.matrix.n_blocks);
            nnz_blocks.push(l.matrix.nnz_blocks());
        }
        AmgShape { blocks, nnz_blocks }
    }

    /// `z ≈ A⁻¹ r`: one V-cycle from zero. `a` is the matrix the hierarchy was built from.
    pub fn precondition(&mut self, a: &BlockSparseMatrix, r: &[f64], z: &mut [f64]) {
        self.work[0].b.copy_from_slice(r);
        assert_eq!(self.finest32.n_blocks(), a.n_blocks, "a hierarchy of another matrix");
        cycle(
            &self.levels,
            &self.smoothers,
            &self.coarsest,
            &mut self.work,
            &self.finest32,
        );
        z.copy_from_slice(&self.work[0].x);
    }
}

/// V-cycle for the right-hand side in `work[0].b` of `matrix` (the level above `levels[0]`),
/// into `work[0].x`.
fn cycle(
    levels: &[Level],
    smoothers: &[Smoother],
    coarsest: &CoarsestSolve,
    work: &mut [Work],
    matrix: &LevelMatrix32,
) {
    let Some((level, coarser)) = levels.split_first() else {
        solve_coarsest(coarsest, &work[0].b, &mut work[0].x);
        return;
    };
    let (here, below) = work.split_first_mut().expect("a work set per level");
    let Work { b, x, r, d, scratch } = here;
    chebyshev(matrix, &smoothers[0], b, x, r, d, scratch, true);
    // The residual after pre-smoothing, restricted; the coarse correction, prolongated.
    residual_into32(matrix, x, b, r, scratch);
    level.restriction.mul_vec32(&level.restriction32, r, &mut below[0].b);
    cycle(coarser, &smoothers[1..], coarsest, below, &level.matrix32);
    CycleMatrix::of_rows(&level.prolongator, &level.prolongator32).each_row_product(&below[0].x, x, |xr, p| {
        for i in 0..3 {
            xr[i] += p[i];
        }
    });
    chebyshev(matrix, &smoothers[0], b, x, r, d, scratch, false);
}

/// The next coarser level from aggregates: the tentative prolongator (each aggregate's blocks
/// move by the near-null space's modes, orthonormalised per aggregate), smoothed by one damped
/// Jacobi step `(I − ω D⁻¹A)`, `ω = 4/(3λ_max)`, the Galerkin product, and the coarse level's
/// near-null space (the modes' coefficients, `R` of the aggregates' QR factorisations).
fn coarsen(
    a: &BlockSparseMatrix,
    lambda_max: f64,
    space: &NearNullSpace,
    agg: &[u32],
    n_agg: usize,
    strong: &[Vec<usize>],
) -> (Level, NearNullSpace) {
    let columns = space.columns;
    // Coarse blocks per aggregate: one per three modes.
    let per = columns / 3;
    let n_coarse = n_agg * per;
    let mut blocks_of_agg: Vec<Vec<usize>> = vec![Vec::new(); n_agg];
    for (b, &node) in space.node_of_block.iter().enumerate() {
        let g = agg[node as usize];
        if g != u32::MAX {
            blocks_of_agg[g as usize].push(b);
        }
    }
    // Per fine block: its tentative prolongator blocks (coarse column, 3×3).
    let mut tentative: Vec<Vec<(u32, Block)>> = vec![Vec::new(); a.n_blocks];
    let mut coarse_rows = vec![[0.0; 18]; n_coarse];
    for (g, blocks) in blocks_of_agg.iter().enumerate() {
        let m = blocks.len();
        let local = DMatrix::from_fn(3 * m, columns, |i, j| space.rows[blocks[i / 3]][columns * (i % 3) + j]);
        let qr = local.qr();
        let (q, r) = (qr.q(), qr.r());
        let k = q.ncols();
        let largest = (0..k).map(|j| r[(j, j)].abs()).fold(0.0, f64::max);
        // A mode the aggregate cannot tell from the others (a rotation of one or two nodes)
        // gets no column: its coarse unknowns are decoupled (see below).
        let kept = |j: usize| j < k && r[(j, j)].abs() > 1e-10 * largest;
        for (p, &b) in blocks.iter().enumerate() {
            for c in 0..per {
                let mut block = [0.0; 9];
                for i in 0..3 {
                    for jj in 0..3 {
                        if kept(3 * c + jj) {
                            block[3 * i + jj] = q[(3 * p + i, 3 * c + jj)];
                        }
                    }
                }
                tentative[b].push(((g * per + c) as u32, block));
            }
        }
        for c in 0..per {
            let row = &mut coarse_rows[g * per + c];
            for i in 0..3 {
                if kept(3 * c + i) {
                    for j in 0..columns {
                        row[columns * i + j] = r[(3 * c + i, j)];
                    }
                }
            }
        }
    }
    let tentative = BlockRows::from_rows(a.n_blocks, n_coarse, |r, out| out.extend_from_slice(&tentative[r]));
    // P = T − ω D⁻¹ A T.
    let omega = 4.0 / (3.0 * lambda_max);
    // The smoothing uses the strong couplings only (the weak ones lumped onto the diagonal, so
    // that translations keep their action): an interpolation as wide as the aggregates'
    // neighbourhoods, not as the matrix's stencil (a cloth's bending couples two rings).
    let jacobi_a = BlockRows::from_rows(a.n_blocks, a.n_blocks, |r, out| {
        let node = space.node_of_block[r] as usize;
        let is_strong = |c: usize| {
            let other = space.node_of_block[c] as usize;
            other == node || strong[node].contains(&other)
        };
        let mut diagonal = a.values[a.diagonal[r]];
        for idx in a.row_start[r]..a.row_start[r + 1] {
            let c = a.cols[idx] as usize;
            if c != r && !is_strong(c) {
                add_scaled(&mut diagonal, 1.0, &a.values[idx]);
            }
        }
        let inverse = nalgebra::Matrix3::from_row_slice(&diagonal)
            .try_inverse()
            .filter(|m| m.iter().all(|x| x.is_finite()))
            .map_or([1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], |m| {
                std::array::from_fn(|k| m[(k / 3, k % 3)])
            });
        for idx in a.row_start[r]..a.row_start[r + 1] {
            let c = a.cols[idx] as usize;
            if c == r {
                out.push((c as u32, mul(&inverse, &diagonal)));
            } else if is_strong(c) {
                out.push((c as u32, mul(&inverse, &a.values[idx])));
            }
        }
    });
    let smoothing = product(a.n_blocks, &tentative, |r| jacobi_a.row(r));
    let prolongator = BlockRows::from_rows(a.n_blocks, n_coarse, |r, out| {
        let start = out.len();
        out.extend(tentative.row(r).map(|(c, b)| (c as u32, *b)));
        for (c, b) in smoothing.row(r) {
            match out[start..].iter_mut().find(|e| e.0 as usize == c) {
                Some(e) => add_scaled(&mut e.1, -omega, b),
                None => {
                    let mut v = [0.0; 9];
                    add_scaled(&mut v, -omega, b);
                    out.push((c as u32, v));
                }
            }
        }
        out[start..].sort_unstable_by_key(|e| e.0);
    });
    let restriction = prolongator.transposed();
    let (matrix, products) = galerkin(a, &prolongator, &restriction);
    let coarse_space = NearNullSpace {
        columns,
        rows: coarse_rows,
        node_of_block: (0..n_coarse).map(|b| (b / per) as u32).collect(),
        n_nodes: n_agg,
    };
    (
        Level {
            matrix32: LevelMatrix32::of(&matrix),
            prolongator32: single(&prolongator.values),
            restriction32: single(&restriction.values),
            matrix,
            prolongator,
            restriction,
            products,
        },
        coarse_space,
    )
}

/// The Galerkin product's intermediates: `A P`, the upper block triangle of `Pᵀ (A P)`, and the
/// pattern of the fine matrix `A` they were computed for.
#[derive(Default)]
struct GalerkinProducts {
    ap: BlockRows,
    upper: BlockRows,
    fine_row_start: Vec<usize>,
    fine_cols: Vec<u32>,
}

impl GalerkinProducts {
    /// `a` has the pattern these products were computed for.
    fn fits(&self, a: &BlockSparseMatrix) -> bool {
        self.fine_row_start == a.row_start && self.fine_cols == a.cols
    }
}

/// The Galerkin coarse matrix `Pᵀ A P` (`restriction` is `Pᵀ`), and the products on the way.
fn galerkin(
    a: &BlockSparseMatrix,
    prolongator: &BlockRows,
    restriction: &BlockRows,
) -> (BlockSparseMatrix, GalerkinProducts) {
    let n_coarse = prolongator.n_cols;
    // A P, then Pᵀ (A P).
    let ap = product(a.n_blocks, prolongator, |r| fine_row(a, r));
    // Its upper block triangle, and the lower one as the upper's transpose (exactly symmetric,
    // half the products).
    let upper = product_from(n_coarse, &ap, |r| restriction.row(r), |r| r);
    let mut matrix = mirrored(&upper);
    unit_diagonal_where_decoupled(&mut matrix);
    let products = GalerkinProducts {
        ap,
        upper,
        fine_row_start: a.row_start.clone(),
        fine_cols: a.cols.clone(),
    };
    (matrix, products)
}

/// [`galerkin`] again for a later `a` into `matrix` (the coarse matrix of the last one): when `a`
/// has the last one's pattern, the products' patterns are kept and only their values are
/// computed (no accumulator bookkeeping, no sorting, no allocation).
fn regalerkin(
    a: &BlockSparseMatrix,
    prolongator: &BlockRows,
    restriction: &BlockRows,
    products: &mut GalerkinProducts,
    matrix: &mut BlockSparseMatrix,
) {
    if !products.fits(a) {
        (*matrix, *products) = galerkin(a, prolongator, restriction);
        return;
    }
    product_values(&mut products.ap, prolongator, |r| fine_row(a, r), |_| 0);
    product_values(&mut products.upper, &products.ap, |r| restriction.row(r), |r| r);
    mirror_values(&products.upper, matrix);
    unit_diagonal_where_decoupled(matrix);
}

/// Row `r` of `a` as (column, block).
fn fine_row(a: &BlockSparseMatrix, r: usize) -> impl Iterator<Item = (usize, &Block)> {
    (a.row_start[r]..a.row_start[r + 1]).map(|idx| (a.cols[idx] as usize, &a.values[idx]))
}

/// Coarse unknowns without a mode (a zero column of `P`) get a unit diagonal: their right-hand
/// side is always zero, so they stay zero.
fn unit_diagonal_where_decoupled(matrix: &mut BlockSparseMatrix) {
    let mean_diagonal = {
        let d: Vec<f64> = matrix
            .diagonal
            .iter()
            .flat_map(|&i| [0, 4, 8].map(|k| matrix.values[i][k]))
            .collect();
        let positive: Vec<f64> = d.into_iter().filter(|&x| x > 0.0).collect();
        positive.iter().sum::<f64>() / positive.len().max(1) as f64
    };
    for r in 0..matrix.n_blocks {
        let i = matrix.diagonal[r];
        for k in [0, 4, 8] {
            if matrix.values[i][k] <= 1e-14 * mean_diagonal {
                matrix.values[i][k] = mean_diagonal.max(1.0e-300);
            }
        }
    }
}

/// The symmetric matrix whose upper block triangle is `upper` (each row's columns from its
/// diagonal on, sorted), written in place: each row's lower part (the transposed blocks of the
/// rows above, in row order: sorted), then its upper part.
fn mirrored(upper: &BlockRows) -> BlockSparseMatrix {
    let n = upper.n_rows();
    let mut lower_len = vec![0usize; n];
    for r in 0..n {
        // P's column blocks of an aggregate are nonzero on its blocks: PᵀAP has its diagonal.
        assert_eq!(
            upper.row(r).next().map(|(c, _)| c),
            Some(r),
            "the coarse matrix has its diagonal"
        );
        for (c, _) in upper.row(r).skip(1) {
            lower_len[c] += 1;
        }
    }
    let mut row_start = Vec::with_capacity(n + 1);
    row_start.push(0);
    for r in 0..n {
        row_start.push(row_start[r] + lower_len[r] + (upper.row_start[r + 1] - upper.row_start[r]));
    }
    let total = row_start[n];
    let mut cols = vec![0u32; total];
    let mut values = vec![[0.0; 9]; total];
    let diagonal: Vec<usize> = (0..n).map(|r| row_start[r] + lower_len[r]).collect();
    // The next free place of each row's lower part.
    let mut next_lower = row_start[..n].to_vec();
    for r in 0..n {
        for (k, (c, b)) in upper.row(r).enumerate() {
            cols[diagonal[r] + k] = c as u32;
            values[diagonal[r] + k] = *b;
            if c != r {
                cols[next_lower[c]] = r as u32;
                values[next_lower[c]] = transpose(b);
                next_lower[c] += 1;
            }
        }
    }
    BlockSparseMatrix {
        n_blocks: n,
        row_start,
        cols,
        diagonal,
        values,
    }
}

fn coarsest_solve(a: &BlockSparseMatrix) -> CoarsestSolve {
    let n = a.dim();
    let dense = DMatrix::from_fn(n, n, |i, j| {
        a.find((i / 3) as u32, (j / 3) as u32)
            .map_or(0.0, |idx| a.values[idx][3 * (i % 3) + j % 3])
    });
    let symmetric = (&dense + dense.transpose()) * 0.5;
    match symmetric.clone().cholesky() {
        Some(c) => CoarsestSolve::Cholesky(c),
        None => {
            let eigen = symmetric.symmetric_eigen();
            let largest = eigen.eigenvalues.iter().fold(0.0f64, |m, &l| m.max(l.abs()));
            let inverse = eigen
                .eigenvalues
                .map(|l| if l > 1e-12 * largest { 1.0 / l } else { 0.0 });
            let v = &eigen.eigenvectors;
            CoarsestSolve::PseudoInverse(v * DMatrix::from_diagonal(&inverse) * v.transpose())
        }
    }
}

fn solve_coarsest(solve: &CoarsestSolve, b: &[f64], x: &mut [f64]) {
    let rhs = nalgebra::DVector::from_column_slice(b);
    let sol = match solve {
        CoarsestSolve::Cholesky(c) => c.solve(&rhs),
        CoarsestSolve::PseudoInverse(p) => p * rhs,
    };
    x.copy_from_slice(sol.as_slice());
}

/// Chebyshev smoothing of `A x = b` on `[λ_max/ratio, λ_max]` of `D⁻¹A` (Adams, Brezina, Hu &
/// Tuminaro 2003), `smoother.degree` products (degree one: a block-Jacobi sweep damped by
/// `1/θ`). `x_is_zero`: start from zero (`x` is
/// overwritten), otherwise from `x`.
#[allow(clippy::too_many_arguments)]
fn chebyshev(
    a: &LevelMatrix32,
    smoother: &Smoother,
    b: &[f64],
    x: &mut [f64],
    r: &mut [f64],
    d: &mut [f64],
    scratch: &mut UpperScratch,
    x_is_zero: bool,
) {
    let upper = smoother.lambda_max;
    if upper <= 0.0 || !upper.is_finite() {
        if x_is_zero {
            x.iter_mut().for_each(|v| *v = 0.0);
        }
        return;
    }
    let lower = upper / CHEBYSHEV_EIGEN_RATIO;
    let theta = 0.5 * (upper + lower);
    let delta = 0.5 * (upper - lower);
    let sigma = theta / delta;
    let mut rho = 1.0 / sigma;
    let inv = &smoother.inv_diag32;
    // d = D⁻¹ r / θ, x += d (r = b from zero).
    if x_is_zero {
        step_direction(x, d, b, inv, Direction::First { theta }, true, smoother.degree > 1);
        if smoother.degree > 1 {
            r.copy_from_slice(b);
        }
    } else {
        residual_into32(a, x, b, r, scratch);
        step_direction(x, d, r, inv, Direction::First { theta }, false, smoother.degree > 1);
    }
    for k in 1..smoother.degree {
        // r −= A d (r = b − A x), then the next direction.
        subtract_product32(a, d, r, scratch);
        let rho_next = 1.0 / (2.0 * sigma - rho);
        let keep = rho_next * rho;
        let push = 2.0 * rho_next / delta;
        let more = smoother.degree > k + 1;
        step_direction(x, d, r, inv, Direction::Next { keep, push }, false, more);
        rho = rho_next;
    }
}

/// A Chebyshev direction: the first `D⁻¹r/θ`, the next ones `keep·d + push·D⁻¹r`.
#[derive(Clone, Copy)]
enum Direction {
    First { theta: f64 },
    Next { keep: f64, push: f64 },
}

/// Chebyshev's direction `d`, then `x ← x + d` (`x ← d` when `x_from_zero`); `d` is stored only
/// when a later direction needs it (`store_direction`). One pass over the vectors.
fn step_direction(
    x: &mut [f64],
    d: &mut [f64],
    r: &[f64],
    inv: &[Block32],
    direction: Direction,
    x_from_zero: bool,
    store_direction: bool,
) {
    let rows = 3 * ROWS_PER_TASK;
    x.par_chunks_mut(rows)
        .zip(d.par_chunks_mut(rows))
        .zip(r.par_chunks(rows))
        .zip(inv.par_chunks(ROWS_PER_TASK))
        .for_each(|(((xs, ds), rs), ms)| {
            for (((x, d), r), m) in xs
                .chunks_exact_mut(3)
                .zip(ds.chunks_exact_mut(3))
                .zip(rs.chunks_exact(3))
                .zip(ms)
            {
                let z = apply32(m, r);
                for i in 0..3 {
                    let di = match direction {
                        Direction::First { theta } => z[i] / theta,
                        Direction::Next { keep, push } => keep * d[i] + push * z[i],
                    };
                    if store_direction {
                        d[i] = di;
                    }
                    x[i] = if x_from_zero { di } else { x[i] + di };
                }
            }
        });
}

#[cfg(test)]
mod tests {
    use super::super::pcg;
    use super::*;

    /// A cloth-like `m × m` grid of 3-vectors: per edge, a spring block `k (I + ½ e eᵀ)` of an
    /// anisotropic stiffness (the coupling along the edge direction `e` is stronger), plus a small
    /// mass on the diagonal, one corner pinned by a stiff diagonal.
    fn grid(m: usize, stiffness: f64, mass: f64) -> BlockSparseMatrix {
        let n = m * m;
        let id = |i: usize, j: usize| (i * m + j) as u32;
        let mut edges = Vec::new();
        for i in 0..m {
            for j in 0..m {
                if i + 1 < m {
                    edges.push((id(i, j), id(i + 1, j), 0));
                }
                if j + 1 < m {
                    edges.push((id(i, j), id(i, j + 1), 1));
                }
            }
        }
        let mut pairs: Vec<(u32, u32)> = (0..n as u32).map(|i| (i, i)).collect();
        for &(a, b, _) in &edges {
            pairs.push((a, b));
            pairs.push((b, a));
        }
        pairs.sort_unstable();
        let mut a = BlockSparseMatrix::from_sorted_pairs(n, &pairs);
        for r in 0..n {
            let d = a.diagonal[r];
            a.values[d] = [mass, 0.0, 0.0, 0.0, mass, 0.0, 0.0, 0.0, mass];
        }
        a.values[a.diagonal[0]][0] += 1e3 * stiffness;
        a.values[a.diagonal[0]][4] += 1e3 * stiffness;
        a.values[a.diagonal[0]][8] += 1e3 * stiffness;
        for &(p, q, axis) in &edges {
            let mut k = [stiffness, 0.0, 0.0, 0.0, stiffness, 0.0, 0.0, 0.0, stiffness];
            k[4 * axis] += 0.5 * stiffness;
            for (r, c, s) in [(p, p, 1.0), (q, q, 1.0), (p, q, -1.0), (q, p, -1.0)] {
                let idx = a.find(r, c).unwrap();
                add_scaled(&mut a.values[idx], s, &k);
            }
        }
        a
    }

    fn rhs(n: usize) -> Vec<f64> {
        (0..n).map(|i| ((i * 37) % 101) as f64 / 50.0 - 1.0).collect()
    }

    fn residual(a: &BlockSparseMatrix, x: &[f64], b: &[f64]) -> f64 {
        let mut ax = vec![0.0; b.len()];
        a.mul_vec(x, &mut ax);
        ax.iter().zip(b).map(|(p, q)| (p - q).powi(2)).sum::<f64>().sqrt()
    }

    /// The grid's node positions (spacing 1/m), for the rigid motions.
    fn grid_positions(m: usize) -> Vec<BlockMotion> {
        (0..m * m)
            .map(|k| BlockMotion::Point([(k / m) as f64 / m as f64, (k % m) as f64 / m as f64, 0.0]))
            .collect()
    }

    /// The rigid-motion rows give a point's velocity `t + ω × x` and a body's spin `ω` for the
    /// coefficients `(t, ω)`.
    #[test]
    fn rigid_motion_rows_are_translations_plus_rotations() {
        let (t, w, x) = ([0.3, -1.2, 0.7], [2.0, 0.5, -0.9], [0.4, -0.25, 1.5]);
        let space = NearNullSpace::rigid_motions(&[BlockMotion::Point(x), BlockMotion::Angular]);
        let coefficients = [t[0], t[1], t[2], w[0], w[1], w[2]];
        let velocity = |row: &[f64; 18]| -> [f64; 3] {
            std::array::from_fn(|i| (0..6).map(|j| row[6 * i + j] * coefficients[j]).sum())
        };
        let cross = [
            w[1] * x[2] - w[2] * x[1],
            w[2] * x[0] - w[0] * x[2],
            w[0] * x[1] - w[1] * x[0],
        ];
        let point = velocity(&space.rows[0]);
        let spin = velocity(&space.rows[1]);
        for i in 0..3 {
            assert!((point[i] - (t[i] + cross[i])).abs() < 1e-14, "{point:?}");
            assert_eq!(spin[i], w[i]);
        }
    }

    #[test]
    fn the_galerkin_matrix_is_pt_a_p() {
        for rotations in [false, true] {
            galerkin_is_pt_a_p(rotations);
        }
    }

    fn galerkin_is_pt_a_p(rotations: bool) {
        let a = grid(24, 1.0, 1e-3);
        let space = if rotations {
            NearNullSpace::rigid_motions(&grid_positions(24))
        } else {
            NearNullSpace::translations(a.n_blocks)
        };
        let (agg, n_agg, strong) = aggregate(&a, &space);
        assert!(
            n_agg > 0 && n_agg < a.n_blocks / 3,
            "{n_agg} aggregates of {}",
            a.n_blocks
        );
        let inv = block_jacobi(&a);
        let lambda = SPECTRAL_SAFETY * spectral_radius(&LevelMatrix32::of(&a), &inv, &mut Work::new(a.dim()));
        let (level, coarse_space) = coarsen(&a, lambda, &space, &agg, n_agg, &strong);
        let n_agg = level.matrix.n_blocks;
        assert_eq!(coarse_space.rows.len(), n_agg);
        assert_eq!(n_agg % (space.columns / 3), 0);
        // Pᵀ A P x against the coarse product, for a random coarse x.
        let xc = rhs(3 * n_agg);
        let mut px = vec![0.0; a.dim()];
        level.prolongator.mul_vec(&xc, &mut px);
        let mut apx = vec![0.0; a.dim()];
        a.mul_vec(&px, &mut apx);
        let mut expected = vec![0.0; 3 * n_agg];
        level.restriction.mul_vec(&apx, &mut expected);
        let mut got = vec![0.0; 3 * n_agg];
        level.matrix.mul_vec(&xc, &mut got);
        let scale = expected.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for (e, g) in expected.iter().zip(&got) {
            assert!((e - g).abs() <= 1e-12 * scale, "{e} vs {g}");
        }
        // Symmetric, as A is.
        let dense = level.matrix.to_dense();
        for i in 0..dense.len() {
            for j in 0..dense.len() {
                assert!((dense[i][j] - dense[j][i]).abs() <= 1e-12 * scale);
            }
        }
    }

    /// Levels recomputed for a later matrix of the same pattern are its Galerkin products with
    /// the kept prolongators (the kept patterns' values equal a product computed from scratch, to
    /// the bit), and a hierarchy restored from the saved interpolation computes the same
    /// levels and the same preconditioned vectors.
    #[test]
    fn refreshed_levels_are_the_new_matrix_galerkin_products() {
        let m = 24;
        let space = || NearNullSpace::rigid_motions(&grid_positions(m));
        let first = grid(m, 1.0, 1e-3);
        // Same pattern, other values (stiffness ×3, mass ×2: not a multiple of the first).
        let later = grid(m, 3.0, 2e-3);
        let mut kept = Amg::with_near_null_space(&first, space());
        assert!(kept.levels.len() >= 2, "a hierarchy of several levels");
        let saved = postcard::to_allocvec(&kept.interpolation()).unwrap();
        let mut restored = Amg::from_interpolation(postcard::from_bytes(&saved).unwrap()).unwrap();
        kept.refresh_levels(&later);
        restored.refresh_levels(&later);
        let mut fine = &later;
        for (k, r) in kept.levels.iter().zip(&restored.levels) {
            let (expected, _) = galerkin(fine, &k.prolongator, &k.restriction);
            for got in [&k.matrix, &r.matrix] {
                assert_eq!(got.row_start, expected.row_start);
                assert_eq!(got.cols, expected.cols);
                let bits = |m: &BlockSparseMatrix| m.values.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(got), bits(&expected));
            }
            fine = &k.matrix;
        }
        let b = rhs(later.dim());
        let (mut zk, mut zr) = (vec![0.0; b.len()], vec![0.0; b.len()]);
        kept.precondition(&later, &b, &mut zk);
        restored.precondition(&later, &b, &mut zr);
        assert_eq!(zk, zr);
        // And it preconditions the later matrix as a new hierarchy does (iterations within 2).
        let fresh = Amg::with_near_null_space(&later, space());
        let iterations = |mut amg: Amg| {
            let mut x = vec![0.0; b.len()];
            let info = pcg::solve_with_product(
                &mut |p, ap| {
                    later.mul_vec(p, ap);
                    dot(p, ap)
                },
                &b,
                &mut x,
                1e-8 * dot(&b, &b).sqrt(),
                200,
                &mut |r, z| amg.precondition(&later, r, z),
            );
            assert!(info.converged);
            info.iterations
        };
        let (with_kept, with_fresh) = (iterations(kept), iterations(fresh));
        assert!(with_kept <= with_fresh + 2, "kept {with_kept}, new {with_fresh}");
        // A bad interpolation is refused with a message.
        let mut wrong = Amg::with_near_null_space(&first, space()).interpolation();
        wrong.top.pop();
        let refused = Amg::from_interpolation(wrong).err().expect("refused");
        assert!(refused.contains("level 0"), "{refused}");
    }

    #[test]
    fn the_spectral_radius_is_estimated_from_below_and_close() {
        let a = grid(16, 1.0, 1e-2);
        let inv = block_jacobi(&a);
        let estimate = spectral_radius(&LevelMatrix32::of(&a), &inv, &mut Work::new(a.dim()));
        // Dense D^{-½} A D^{-½}: the exact largest eigenvalue.
        let n = a.dim();
        let dense = a.to_dense();
        let scaled = DMatrix::from_fn(n, n, |i, j| dense[i][j] / (dense[i][i] * dense[j][j]).sqrt());
        let exact = scaled.symmetric_eigenvalues().max();
        assert!(
            // From below, up to the single-precision rounding of the matrix it is estimated on.
            estimate <= exact * (1.0 + 1e-6) && estimate >= 0.9 * exact,
            "{estimate} vs {exact}"
        );
    }

    /// The point of it: CG's iteration count nearly flat under refinement, where block Jacobi's
    /// grows like the grid's side.
    #[test]
    fn cg_iterations_stay_flat_under_refinement() {
        let mut counts = Vec::new();
        for m in [16, 32, 64, 128] {
            let a = grid(m, 1.0, 1e-4);
            let b = rhs(a.dim());
            let tol = 1e-8 * dot(&b, &b).sqrt();
            let mut amg = Amg::new(&a);
            let mut x = vec![0.0; a.dim()];
            let with = pcg::solve_preconditioned(&a, &b, &mut x, tol, 1000, &mut |r, z| amg.precondition(&a, r, z));
            assert!(with.converged && !with.indefinite, "{m}: {with:?}");
            assert!(residual(&a, &x, &b) <= 1.01 * tol);
            let without = pcg::solve(&a, &b, &mut x, tol, 10_000);
            assert!(without.converged);
            counts.push((m, with.iterations, without.iterations, amg.shape(&a).blocks));
        }
        eprintln!("{counts:?}");
        let (first, last) = (counts[0].1, counts[counts.len() - 1].1);
        // Eight times the side: block Jacobi about eight times the iterations, multigrid < 2×.
        assert!(last <= 2 * first, "{counts:?}");
        assert!(counts[counts.len() - 1].2 >= 4 * last, "{counts:?}");
    }

    #[test]
    fn the_hierarchy_is_deterministic_and_the_preconditioner_symmetric() {
        let a = grid(40, 1.0, 1e-3);
        let mut one = Amg::new(&a);
        let mut two = Amg::new(&a);
        let (u, w) = (
            rhs(a.dim()),
            (0..a.dim()).map(|i| (i as f64 * 0.37).sin()).collect::<Vec<_>>(),
        );
        let (mut mu, mut mw, mut mu2) = (vec![0.0; a.dim()], vec![0.0; a.dim()], vec![0.0; a.dim()]);
        one.precondition(&a, &u, &mut mu);
        two.precondition(&a, &u, &mut mu2);
        assert_eq!(mu, mu2);
        one.precondition(&a, &w, &mut mw);
        // wᵀ M u = uᵀ M w, and positive.
        let (wmu, umw) = (dot(&w, &mu), dot(&u, &mw));
        assert!((wmu - umw).abs() <= 1e-10 * wmu.abs().max(umw.abs()), "{wmu} vs {umw}");
        assert!(dot(&u, &mu) > 0.0);
    }
}
