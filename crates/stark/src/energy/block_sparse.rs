//! Symmetric block-sparse matrices with 3×3 blocks (BSR, both triangles stored).
//!
//! Every DOF block is 3 wide (a deformable node, a rigid body's linear or angular velocity), so the
//! global Hessian is stored as 3×3 blocks. Storing both triangles makes the product a plain
//! row-parallel loop.

use rayon::prelude::*;

/// Rows handled per parallel task: fixed, so that results do not depend on the thread count.
pub const ROWS_PER_TASK: usize = 512;

/// A 3×3 block, row-major.
pub type Block = [f64; 9];

/// Sparsity pattern and values of a symmetric matrix of `n_blocks × n_blocks` 3×3 blocks.
#[derive(Clone, Debug, Default)]
pub struct BlockSparseMatrix {
    /// Number of block rows (= block columns).
    pub n_blocks: usize,
    /// Start of each block row in `cols`/`values` (length `n_blocks + 1`).
    pub row_start: Vec<usize>,
    /// Block column of each stored block, sorted within a row.
    pub cols: Vec<u32>,
    /// Position of the diagonal block of each row in `values`.
    pub diagonal: Vec<usize>,
    /// Block values.
    pub values: Vec<Block>,
}

impl BlockSparseMatrix {
    /// Build the pattern from sorted, deduplicated `(row, col)` block pairs. Diagonal blocks must
    /// be present for every row.
    pub fn from_sorted_pairs(n_blocks: usize, pairs: &[(u32, u32)]) -> Self {
        let mut row_start = vec![0usize; n_blocks + 1];
        for &(r, _) in pairs {
            row_start[r as usize + 1] += 1;
        }
        for i in 0..n_blocks {
            row_start[i + 1] += row_start[i];
        }
        let cols: Vec<u32> = pairs.iter().map(|&(_, c)| c).collect();
        let diagonal = (0..n_blocks)
            .map(|r| {
                let s = row_start[r];
                let e = row_start[r + 1];
                s + cols[s..e]
                    .binary_search(&(r as u32))
                    .expect("every row has a diagonal block")
            })
            .collect();
        let values = vec![[0.0; 9]; cols.len()];
        BlockSparseMatrix {
            n_blocks,
            row_start,
            cols,
            diagonal,
            values,
        }
    }

    /// Index of block `(r, c)` in `values`, if it is in the pattern.
    pub fn find(&self, r: u32, c: u32) -> Option<usize> {
        let row = self.row_start[r as usize]..self.row_start[r as usize + 1];
        self.cols[row.clone()].binary_search(&c).ok().map(|k| row.start + k)
    }

    /// The pattern as sorted `(row, column)` block pairs.
    pub fn pattern_pairs(&self) -> Vec<(u32, u32)> {
        (0..self.n_blocks)
            .flat_map(|r| {
                self.cols[self.row_start[r]..self.row_start[r + 1]]
                    .iter()
                    .map(move |&c| (r as u32, c))
            })
            .collect()
    }

    /// Number of scalar rows.
    pub fn dim(&self) -> usize {
        3 * self.n_blocks
    }

    /// Number of stored blocks.
    pub fn nnz_blocks(&self) -> usize {
        self.cols.len()
    }

    /// `y = A x` (scalar vectors of length `3 n_blocks`), parallel over block rows.
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        y.par_chunks_mut(3 * ROWS_PER_TASK).enumerate().for_each(|(chunk, ys)| {
            let first = chunk * ROWS_PER_TASK;
            for (k, yr) in ys.chunks_exact_mut(3).enumerate() {
                yr.copy_from_slice(&self.row_times(first + k, x));
            }
        });
    }

    /// Block row `r` times `x`.
    #[inline(always)]
    fn row_times(&self, r: usize, x: &[f64]) -> [f64; 3] {
        #[cfg(all(target_arch = "x86_64", target_feature = "avx2", target_feature = "fma"))]
        {
            // SAFETY: the target has AVX2 and FMA (compile-time features); `row_times_avx2`
            // checks each column against `x` before it reads there.
            unsafe { self.row_times_avx2(r, x) }
        }
        #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2", target_feature = "fma")))]
        self.row_times_scalar(r, x)
    }

    /// [`Self::row_times`] with 4-wide vectors: one accumulator per row of the result, a lane
    /// per column of the blocks, summed across the lanes once per block row (the scalar loop's
    /// 9 loads and multiply-adds per block become 4 loads and 3 fused multiply-adds: PCG's
    /// linear solve −20% on hanging_cloth and hanging_cloth_64, BENCHMARKS.md).
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2", target_feature = "fma"))]
    #[inline(always)]
    unsafe fn row_times_avx2(&self, r: usize, x: &[f64]) -> [f64; 3] {
        use std::arch::x86_64::*;
        let first3 = _mm256_set_epi64x(0, -1, -1, -1);
        let (mut p0, mut p1, mut p2) = (_mm256_setzero_pd(), _mm256_setzero_pd(), _mm256_setzero_pd());
        let range = self.row_start[r]..self.row_start[r + 1];
        for (c, b) in self.cols[range.clone()].iter().zip(&self.values[range]) {
            let c = *c as usize;
            // Every load reads inside its block or its 3-vector of `x` (masked loads for the
            // block's last row and for `x`).
            assert!(3 * c + 3 <= x.len(), "block column {c} beyond the vector");
            let xc = _mm256_maskload_pd(x.as_ptr().add(3 * c), first3);
            let bp = b.as_ptr();
            p0 = _mm256_fmadd_pd(_mm256_loadu_pd(bp), xc, p0);
            p1 = _mm256_fmadd_pd(_mm256_loadu_pd(bp.add(3)), xc, p1);
            p2 = _mm256_fmadd_pd(_mm256_maskload_pd(bp.add(6), first3), xc, p2);
        }
        let mut lanes = [[0.0; 4]; 3];
        _mm256_storeu_pd(lanes[0].as_mut_ptr(), p0);
        _mm256_storeu_pd(lanes[1].as_mut_ptr(), p1);
        _mm256_storeu_pd(lanes[2].as_mut_ptr(), p2);
        lanes.map(|l| l[0] + l[1] + l[2])
    }

    #[cfg_attr(
        all(target_arch = "x86_64", target_feature = "avx2", target_feature = "fma"),
        allow(dead_code)
    )]
    #[inline(always)]
    fn row_times_scalar(&self, r: usize, x: &[f64]) -> [f64; 3] {
        let mut acc = [0.0; 3];
        for idx in self.row_start[r]..self.row_start[r + 1] {
            let c = self.cols[idx] as usize;
            let b = &self.values[idx];
            let xc = &x[3 * c..3 * c + 3];
            acc[0] += b[0] * xc[0] + b[1] * xc[1] + b[2] * xc[2];
            acc[1] += b[3] * xc[0] + b[4] * xc[1] + b[5] * xc[2];
            acc[2] += b[6] * xc[0] + b[7] * xc[1] + b[8] * xc[2];
        }
        acc
    }

    /// `y = A x`, returning `x · y` (summed per task of rows, in order: the same bits at any
    /// thread count), in one pass over the matrix.
    pub fn mul_vec_dot(&self, x: &[f64], y: &mut [f64]) -> f64 {
        let partial: Vec<f64> = y
            .par_chunks_mut(3 * ROWS_PER_TASK)
            .enumerate()
            .map(|(chunk, ys)| {
                let first = chunk * ROWS_PER_TASK;
                self.mul_rows_dot(first..first + ys.len() / 3, x, ys)
            })
            .collect();
        partial.iter().sum()
    }

    /// Block rows `rows` of `A x` into `y` (their `3 · rows.len()` entries), returning `x · y`
    /// over those rows (summed per component, then the three added).
    #[inline]
    pub fn mul_rows_dot(&self, rows: std::ops::Range<usize>, x: &[f64], y: &mut [f64]) -> f64 {
        debug_assert_eq!(y.len(), 3 * rows.len());
        let mut xy = [0.0; 3];
        for (r, yr) in rows.zip(y.chunks_exact_mut(3)) {
            let acc = self.row_times(r, x);
            yr.copy_from_slice(&acc);
            for i in 0..3 {
                xy[i] += x[3 * r + i] * acc[i];
            }
        }
        xy[0] + xy[1] + xy[2]
    }

    /// Dense copy (tests and debugging only).
    pub fn to_dense(&self) -> Vec<Vec<f64>> {
        let n = self.dim();
        let mut d = vec![vec![0.0; n]; n];
        for r in 0..self.n_blocks {
            for idx in self.row_start[r]..self.row_start[r + 1] {
                let c = self.cols[idx] as usize;
                for i in 0..3 {
                    for j in 0..3 {
                        d[3 * r + i][3 * c + j] = self.values[idx][3 * i + j];
                    }
                }
            }
        }
        d
    }
}

/// Deterministic parallel dot product: partial sums over fixed chunks, added in order.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    const CHUNK: usize = 4096;
    if a.len() <= CHUNK {
        return dot_lanes(a, b);
    }
    let partial: Vec<f64> = a
        .par_chunks(CHUNK)
        .zip(b.par_chunks(CHUNK))
        .map(|(x, y)| dot_lanes(x, y))
        .collect();
    partial.iter().sum()
}

/// `a · b` summed in eight interleaved lanes: the compiler keeps them in vector registers, where
/// one running sum would make every addition wait for the one before (a fixed order all the same,
/// so results do not depend on the thread count).
pub fn dot_lanes(a: &[f64], b: &[f64]) -> f64 {
    const LANES: usize = 8;
    let mut acc = [0.0f64; LANES];
    let (a8, b8) = (a.chunks_exact(LANES), b.chunks_exact(LANES));
    let tail: f64 = a8.remainder().iter().zip(b8.remainder()).map(|(x, y)| x * y).sum();
    for (x, y) in a8.zip(b8) {
        for l in 0..LANES {
            acc[l] += x[l] * y[l];
        }
    }
    let pairs = [acc[0] + acc[4], acc[1] + acc[5], acc[2] + acc[6], acc[3] + acc[7]];
    (pairs[0] + pairs[2]) + (pairs[1] + pairs[3]) + tail
}

/// Largest absolute entry.
pub fn norm_inf(a: &[f64]) -> f64 {
    a.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn product_matches_dense() {
        let pairs = vec![(0, 0), (0, 2), (1, 1), (2, 0), (2, 2)];
        let mut a = BlockSparseMatrix::from_sorted_pairs(3, &pairs);
        for (k, v) in a.values.iter_mut().enumerate() {
            for (i, e) in v.iter_mut().enumerate() {
                *e = (k * 9 + i) as f64 * 0.1 - 1.0;
            }
        }
        let x: Vec<f64> = (0..9).map(|i| (i as f64).sin()).collect();
        let mut y = vec![0.0; 9];
        a.mul_vec(&x, &mut y);
        let d = a.to_dense();
        for i in 0..9 {
            let e: f64 = (0..9).map(|j| d[i][j] * x[j]).sum();
            assert!((e - y[i]).abs() < 1e-12);
        }
    }

    /// The vectorised block-row product agrees with the scalar one to rounding, and
    /// `mul_vec_dot` returns `x · A x`.
    #[test]
    fn vectorised_and_scalar_block_rows_agree() {
        let n = 40;
        let pairs: Vec<(u32, u32)> = (0..n as u32)
            .flat_map(|r| {
                (0..n as u32)
                    .filter(move |c| (r * 7 + c * 3) % 5 == 0 || r == *c)
                    .map(move |c| (r, c))
            })
            .collect();
        let mut a = BlockSparseMatrix::from_sorted_pairs(n, &pairs);
        for (k, v) in a.values.iter_mut().enumerate() {
            for (i, e) in v.iter_mut().enumerate() {
                *e = ((k * 9 + i) as f64 * 0.37).sin();
            }
        }
        let x: Vec<f64> = (0..3 * n).map(|i| (i as f64 * 0.71).cos()).collect();
        let mut y = vec![0.0; 3 * n];
        let xy = a.mul_vec_dot(&x, &mut y);
        for r in 0..n {
            let scalar = a.row_times_scalar(r, &x);
            for i in 0..3 {
                assert!((scalar[i] - y[3 * r + i]).abs() < 1e-12, "row {r}: {scalar:?}");
            }
        }
        let plain: f64 = x.iter().zip(&y).map(|(a, b)| a * b).sum();
        assert!((xy - plain).abs() < 1e-10);
    }

    /// The lane-summed dot product equals the plain sum to rounding at every length (tails of
    /// 0–7 entries, one chunk and several), and its bits do not depend on the thread count.
    #[test]
    fn dot_matches_the_plain_sum_at_any_thread_count() {
        for n in [0, 1, 7, 8, 9, 100, 4096, 4097, 20_001] {
            let a: Vec<f64> = (0..n).map(|i| (0.37 * i as f64).sin()).collect();
            let b: Vec<f64> = (0..n).map(|i| (0.11 * i as f64).cos() - 0.2).collect();
            let plain: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
            let scale: f64 = a.iter().zip(&b).map(|(x, y)| (x * y).abs()).sum();
            let at = |threads: usize| {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                pool.install(|| dot(&a, &b))
            };
            let one = at(1);
            assert!(
                (one - plain).abs() <= 1e-14 * scale.max(1.0),
                "n = {n}: {one} against {plain}"
            );
            assert_eq!(one.to_bits(), at(2).to_bits(), "n = {n}");
        }
    }

    /// The fused product returns `x · A x` of the plain product, to rounding, with the same bits
    /// at one and two threads.
    #[test]
    fn fused_product_returns_its_dot_product() {
        let n = 3000;
        let mut pairs = Vec::new();
        for r in 0..n as u32 {
            for c in [
                r.saturating_sub(7),
                r,
                (r + 1).min(n as u32 - 1),
                (r + 40).min(n as u32 - 1),
            ] {
                pairs.push((r, c));
                pairs.push((c, r));
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        let mut a = BlockSparseMatrix::from_sorted_pairs(n, &pairs);
        for (k, v) in a.values.iter_mut().enumerate() {
            for (i, e) in v.iter_mut().enumerate() {
                *e = ((k * 9 + i) as f64 * 0.37).sin();
            }
        }
        let x: Vec<f64> = (0..3 * n).map(|i| (i as f64 * 0.11).cos()).collect();
        let mut y = vec![0.0; 3 * n];
        a.mul_vec(&x, &mut y);
        let plain = dot(&x, &y);
        let at = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let mut z = vec![0.0; 3 * n];
            let d = pool.install(|| a.mul_vec_dot(&x, &mut z));
            assert_eq!(z, y, "the same product");
            d
        };
        let one = at(1);
        let scale: f64 = x.iter().zip(&y).map(|(p, q)| (p * q).abs()).sum();
        assert!((one - plain).abs() <= 1e-13 * scale, "{one} against {plain}");
        assert_eq!(one.to_bits(), at(2).to_bits());
    }
}
