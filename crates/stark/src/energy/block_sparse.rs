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

    /// The pattern alone (no values): what an ordering or a symbolic analysis reads.
    pub fn pattern_only(&self) -> BlockSparseMatrix {
        BlockSparseMatrix {
            n_blocks: self.n_blocks,
            row_start: self.row_start.clone(),
            cols: self.cols.clone(),
            diagonal: self.diagonal.clone(),
            values: Vec::new(),
        }
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

/// A 3×3 block as a product reads it: double precision, or rounded to single precision (the
/// multigrid cycle's matrices, half the bytes).
pub trait StoredBlock: Copy + Send + Sync + 'static {
    /// The block rounded from a double-precision one.
    fn from_block(b: &Block) -> Self;
    /// Entry `k` (row-major).
    fn entry(&self, k: usize) -> f64;
    /// The block's three rows as 4-wide vectors. Lane 3 of the first two holds the next row's
    /// first entry (a product must meet it with a zero lane); the third row's lane 3 is zero
    /// (nothing is read past the block).
    ///
    /// # Safety
    /// The target has AVX2 (compile-time feature).
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2", target_feature = "fma"))]
    unsafe fn rows(&self) -> [std::arch::x86_64::__m256d; 3];
}

impl StoredBlock for Block {
    #[inline(always)]
    fn from_block(b: &Block) -> Self {
        *b
    }
    #[inline(always)]
    fn entry(&self, k: usize) -> f64 {
        self[k]
    }
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2", target_feature = "fma"))]
    #[inline(always)]
    unsafe fn rows(&self) -> [std::arch::x86_64::__m256d; 3] {
        use std::arch::x86_64::*;
        let p = self.as_ptr();
        [
            _mm256_loadu_pd(p),
            _mm256_loadu_pd(p.add(3)),
            _mm256_maskload_pd(p.add(6), _mm256_set_epi64x(0, -1, -1, -1)),
        ]
    }
}

impl StoredBlock for [f32; 9] {
    #[inline(always)]
    fn from_block(b: &Block) -> Self {
        b.map(|v| v as f32)
    }
    #[inline(always)]
    fn entry(&self, k: usize) -> f64 {
        f64::from(self[k])
    }
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2", target_feature = "fma"))]
    #[inline(always)]
    unsafe fn rows(&self) -> [std::arch::x86_64::__m256d; 3] {
        use std::arch::x86_64::*;
        let p = self.as_ptr();
        [
            _mm256_cvtps_pd(_mm_loadu_ps(p)),
            _mm256_cvtps_pd(_mm_loadu_ps(p.add(3))),
            _mm256_cvtps_pd(_mm_maskload_ps(p.add(6), _mm_set_epi32(0, -1, -1, -1))),
        ]
    }
}

/// The upper block triangle of a symmetric block matrix, stored alone (each row: its diagonal
/// block, then the blocks right of it), for products that read each off-diagonal block once and
/// apply it twice: `A_rc x_c` to row `r` and `A_rcᵀ x_r` to row `c`. Half the bytes of the
/// both-triangles product: on a 128² cloth's pattern twice as fast at one thread, where the
/// matrix no longer fits the caches (BENCHMARKS.md).
///
/// The product is deterministic and independent of the thread count: rows go in fixed tasks of
/// [`ROWS_PER_TASK`]; a task adds the transposed blocks that land in its own rows to a buffer of
/// its own (in row order), and writes those that land in a later task's rows to slots of its own
/// (in the same order); each task then sums its buffer and the slots aimed at it (in slot order).
#[derive(Clone, Debug, Default)]
pub struct UpperTriangle<B> {
    n_blocks: usize,
    /// Start of each row in `cols`/`values`; the row's first block is its diagonal.
    row_start: Vec<usize>,
    cols: Vec<u32>,
    values: Vec<B>,
    /// First slot of each task (length tasks + 1).
    slot_start: Vec<usize>,
    /// Per task, the slots aimed at its rows (start of each task's list, length tasks + 1), and
    /// the list: (slot, row) in slot order.
    gather_start: Vec<usize>,
    gather: Vec<(u32, u32)>,
}

/// A product's scratch: per task a 4-wide buffer of its rows, and the slots.
#[derive(Clone, Debug, Default)]
pub struct UpperScratch {
    rows: Vec<[f64; 4]>,
    slots: Vec<[f64; 4]>,
}

impl<B: StoredBlock> UpperTriangle<B> {
    /// The upper triangle of `a` (both triangles stored, symmetric), its blocks as `B`.
    pub fn of(a: &BlockSparseMatrix) -> Self {
        let mut u = Self {
            n_blocks: 0,
            row_start: Vec::new(),
            cols: Vec::new(),
            values: Vec::new(),
            slot_start: Vec::new(),
            gather_start: Vec::new(),
            gather: Vec::new(),
        };
        u.refill(a);
        u
    }

    /// Renew from `a`, reusing the allocations (a later Hessian, of this pattern or another).
    pub fn refill(&mut self, a: &BlockSparseMatrix) {
        let n = a.n_blocks;
        let same_pattern = self.n_blocks == n
            && (0..n).all(|r| {
                let upper = &a.cols[a.diagonal[r]..a.row_start[r + 1]];
                self.row_start[r + 1] - self.row_start[r] == upper.len()
                    && self.cols[self.row_start[r]..self.row_start[r + 1]] == *upper
            });
        if !same_pattern {
            self.set_pattern(a);
        }
        let values = &mut self.values;
        values.clear();
        for r in 0..n {
            values.extend(a.values[a.diagonal[r]..a.row_start[r + 1]].iter().map(B::from_block));
        }
    }

    fn set_pattern(&mut self, a: &BlockSparseMatrix) {
        let n = a.n_blocks;
        self.n_blocks = n;
        self.row_start.clear();
        self.cols.clear();
        self.row_start.push(0);
        for r in 0..n {
            let upper = &a.cols[a.diagonal[r]..a.row_start[r + 1]];
            // The product reads `x` at each column and writes its task's rows from `r` on,
            // unchecked: the row starts at its diagonal, increases, and stays inside the matrix.
            assert!(
                upper.first() == Some(&(r as u32))
                    && upper.windows(2).all(|w| w[0] < w[1])
                    && upper.iter().all(|&c| (c as usize) < n),
                "row {r}: not an upper triangle's row"
            );
            self.cols.extend_from_slice(upper);
            self.row_start.push(self.cols.len());
        }
        // The slots: per task in generation order (rows, then blocks in a row).
        let tasks = n.div_ceil(ROWS_PER_TASK);
        let task_of = |row: usize| row / ROWS_PER_TASK;
        self.slot_start.clear();
        self.slot_start.push(0);
        let mut targets: Vec<u32> = Vec::new();
        for t in 0..tasks {
            let end = ((t + 1) * ROWS_PER_TASK).min(n);
            for r in t * ROWS_PER_TASK..end {
                for &c in &self.cols[self.row_start[r] + 1..self.row_start[r + 1]] {
                    if c as usize >= end {
                        targets.push(c);
                    }
                }
            }
            self.slot_start.push(targets.len());
        }
        // Each task's list of the slots aimed at it, in slot order (a counting sort).
        self.gather_start.clear();
        self.gather_start.resize(tasks + 1, 0);
        for &c in &targets {
            self.gather_start[task_of(c as usize) + 1] += 1;
        }
        for t in 0..tasks {
            self.gather_start[t + 1] += self.gather_start[t];
        }
        let mut next = self.gather_start.clone();
        self.gather.clear();
        self.gather.resize(targets.len(), (0, 0));
        for (slot, &c) in targets.iter().enumerate() {
            let t = task_of(c as usize);
            self.gather[next[t]] = (slot as u32, c);
            next[t] += 1;
        }
    }

    /// Number of block rows.
    pub fn n_blocks(&self) -> usize {
        self.n_blocks
    }

    /// `combine(r, y_r, (A x)_r)` for every block row `r` of `y` (in parallel over fixed tasks).
    pub fn product_with(
        &self,
        x: &[f64],
        y: &mut [f64],
        scratch: &mut UpperScratch,
        combine: impl Fn(usize, &mut [f64], [f64; 3]) + Sync,
    ) {
        self.product_tasks(x, y, scratch, |r, yr, p| {
            combine(r, yr, p);
            0.0
        });
    }

    /// `y = A x`, returning `x · y` (summed per task, in order: the same bits at any thread
    /// count).
    pub fn product_dot(&self, x: &[f64], y: &mut [f64], scratch: &mut UpperScratch) -> f64 {
        self.product_tasks(x, y, scratch, |r, yr, p| {
            yr.copy_from_slice(&p);
            x[3 * r] * p[0] + x[3 * r + 1] * p[1] + x[3 * r + 2] * p[2]
        })
    }

    /// The product, `each(r, y_r, (A x)_r)` per row; the sum of what it returns.
    fn product_tasks(
        &self,
        x: &[f64],
        y: &mut [f64],
        scratch: &mut UpperScratch,
        each: impl Fn(usize, &mut [f64], [f64; 3]) -> f64 + Sync,
    ) -> f64 {
        let n = self.n_blocks;
        assert!(x.len() == 3 * n && y.len() == 3 * n, "vectors of another size");
        scratch.rows.resize(n, [0.0; 4]);
        scratch.slots.resize(*self.slot_start.last().unwrap_or(&0), [0.0; 4]);
        // Pass 1: per task, its rows' sums and its slots.
        let mut slot_chunks: Vec<&mut [[f64; 4]]> = Vec::with_capacity(self.slot_start.len());
        let mut rest = scratch.slots.as_mut_slice();
        for w in self.slot_start.windows(2) {
            let (head, tail) = rest.split_at_mut(w[1] - w[0]);
            slot_chunks.push(head);
            rest = tail;
        }
        scratch
            .rows
            .par_chunks_mut(ROWS_PER_TASK)
            .zip(slot_chunks.into_par_iter())
            .enumerate()
            .for_each(|(t, (rows, slots))| {
                let first = t * ROWS_PER_TASK;
                self.task(first..first + rows.len(), x, rows, slots);
            });
        // Pass 2: each task's slots added to the rows they aim at, then combined.
        let (rows, slots) = (&mut scratch.rows, &scratch.slots);
        let partial: Vec<f64> = rows
            .par_chunks_mut(ROWS_PER_TASK)
            .zip(y.par_chunks_mut(3 * ROWS_PER_TASK))
            .enumerate()
            .map(|(t, (rows, ys))| {
                let first = t * ROWS_PER_TASK;
                for &(slot, row) in &self.gather[self.gather_start[t]..self.gather_start[t + 1]] {
                    let (acc, add) = (&mut rows[row as usize - first], &slots[slot as usize]);
                    for i in 0..3 {
                        acc[i] += add[i];
                    }
                }
                let mut sum = 0.0;
                for (k, (acc, yr)) in rows.iter().zip(ys.chunks_exact_mut(3)).enumerate() {
                    sum += each(first + k, yr, [acc[0], acc[1], acc[2]]);
                }
                sum
            })
            .collect();
        partial.iter().sum()
    }

    /// `y = A x`.
    pub fn product(&self, x: &[f64], y: &mut [f64], scratch: &mut UpperScratch) {
        self.product_with(x, y, scratch, |_, yr, p| yr.copy_from_slice(&p));
    }

    /// One task's rows `rows`: `acc[r − first]` gets row `r`'s own product and the transposed
    /// blocks of earlier rows of the task; `slots` the transposed blocks aimed at later tasks.
    fn task(&self, rows: std::ops::Range<usize>, x: &[f64], acc: &mut [[f64; 4]], slots: &mut [[f64; 4]]) {
        acc.fill([0.0; 4]);
        #[cfg(all(target_arch = "x86_64", target_feature = "avx2", target_feature = "fma"))]
        // SAFETY: AVX2 and FMA are compile-time features; the indices are checked (see there).
        unsafe {
            self.task_avx2(rows, x, acc, slots)
        }
        #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2", target_feature = "fma")))]
        self.task_scalar(rows, x, acc, slots)
    }

    #[cfg_attr(
        all(target_arch = "x86_64", target_feature = "avx2", target_feature = "fma"),
        allow(dead_code)
    )]
    fn task_scalar(&self, rows: std::ops::Range<usize>, x: &[f64], acc: &mut [[f64; 4]], slots: &mut [[f64; 4]]) {
        let (first, end) = (rows.start, rows.end);
        let mut next_slot = 0;
        for r in rows {
            let xr = &x[3 * r..3 * r + 3];
            let mut own = [0.0; 3];
            for idx in self.row_start[r]..self.row_start[r + 1] {
                let c = self.cols[idx] as usize;
                let b = &self.values[idx];
                let xc = &x[3 * c..3 * c + 3];
                for i in 0..3 {
                    own[i] += b.entry(3 * i) * xc[0] + b.entry(3 * i + 1) * xc[1] + b.entry(3 * i + 2) * xc[2];
                }
                if c == r {
                    continue;
                }
                let t: [f64; 3] =
                    std::array::from_fn(|j| b.entry(j) * xr[0] + b.entry(3 + j) * xr[1] + b.entry(6 + j) * xr[2]);
                let target = if c < end {
                    &mut acc[c - first]
                } else {
                    next_slot += 1;
                    slots[next_slot - 1] = [0.0; 4];
                    &mut slots[next_slot - 1]
                };
                for j in 0..3 {
                    target[j] += t[j];
                }
            }
            for i in 0..3 {
                acc[r - first][i] += own[i];
            }
        }
    }

    #[cfg(all(target_arch = "x86_64", target_feature = "avx2", target_feature = "fma"))]
    #[inline(always)]
    unsafe fn task_avx2(&self, rows: std::ops::Range<usize>, x: &[f64], acc: &mut [[f64; 4]], slots: &mut [[f64; 4]]) {
        use std::arch::x86_64::*;
        let first3 = _mm256_set_epi64x(0, -1, -1, -1);
        let (first, end) = (rows.start, rows.end);
        assert!(acc.len() == end - first && 3 * self.n_blocks == x.len());
        let mut next_slot = 0;
        for r in rows {
            let span = self.row_start[r]..self.row_start[r + 1];
            // Every column is below `n_blocks` (`x` checked above) and at or right of `r` (so a
            // column below `end` is in `acc`); the slots were counted from this very pattern.
            let xr = _mm256_maskload_pd(x.as_ptr().add(3 * r), first3);
            let (x0, x1, x2) = (
                _mm256_set1_pd(x[3 * r]),
                _mm256_set1_pd(x[3 * r + 1]),
                _mm256_set1_pd(x[3 * r + 2]),
            );
            let [d0, d1, d2] = self.values[span.start].rows();
            let mut p0 = _mm256_mul_pd(d0, xr);
            let mut p1 = _mm256_mul_pd(d1, xr);
            let mut p2 = _mm256_mul_pd(d2, xr);
            for idx in span.start + 1..span.end {
                let c = *self.cols.get_unchecked(idx) as usize;
                let [b0, b1, b2] = self.values.get_unchecked(idx).rows();
                let xc = _mm256_maskload_pd(x.as_ptr().add(3 * c), first3);
                p0 = _mm256_fmadd_pd(b0, xc, p0);
                p1 = _mm256_fmadd_pd(b1, xc, p1);
                p2 = _mm256_fmadd_pd(b2, xc, p2);
                // Aᵀ x_r: lane 3 carries the next rows' first entries, never read.
                let t = _mm256_fmadd_pd(x2, b2, _mm256_fmadd_pd(x1, b1, _mm256_mul_pd(x0, b0)));
                if c < end {
                    let target = acc.as_mut_ptr().add(c - first) as *mut f64;
                    _mm256_storeu_pd(target, _mm256_add_pd(_mm256_loadu_pd(target), t));
                } else {
                    let target = slots.as_mut_ptr().add(next_slot) as *mut f64;
                    assert!(next_slot < slots.len());
                    _mm256_storeu_pd(target, t);
                    next_slot += 1;
                }
            }
            let mut lanes = [[0.0; 4]; 3];
            _mm256_storeu_pd(lanes[0].as_mut_ptr(), p0);
            _mm256_storeu_pd(lanes[1].as_mut_ptr(), p1);
            _mm256_storeu_pd(lanes[2].as_mut_ptr(), p2);
            let own = &mut acc[r - first];
            for i in 0..3 {
                own[i] += lanes[i][0] + lanes[i][1] + lanes[i][2];
            }
        }
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

    /// The upper-triangle product equals the both-triangles one to rounding, in double and in
    /// single precision, with the same bits at one and two threads, on a pattern whose rows
    /// reach into later tasks nearby (a band) and far (the last rows).
    #[test]
    fn upper_triangle_product_matches_the_full_one() {
        let n = 2 * ROWS_PER_TASK + 300;
        let mut pairs = Vec::new();
        for r in 0..n as u32 {
            for c in [r, r + 1, r + 37, r + 300, n as u32 - 1 - r % 5, (r * 7919) % n as u32] {
                if c < n as u32 {
                    pairs.push((r, c));
                    pairs.push((c, r));
                }
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        let mut a = BlockSparseMatrix::from_sorted_pairs(n, &pairs);
        for r in 0..n {
            for idx in a.row_start[r]..a.row_start[r + 1] {
                let c = a.cols[idx] as usize;
                // Symmetric: block (c, r) is block (r, c) transposed.
                let (lo, hi) = (r.min(c), r.max(c));
                a.values[idx] = std::array::from_fn(|k| {
                    let (i, j) = if r <= c { (k / 3, k % 3) } else { (k % 3, k / 3) };
                    ((lo * 31 + hi * 7 + 3 * i + j) as f64 * 0.37).sin()
                });
            }
        }
        let x: Vec<f64> = (0..3 * n).map(|i| (i as f64 * 0.11).cos()).collect();
        let mut full = vec![0.0; 3 * n];
        a.mul_vec(&x, &mut full);
        let scale = full.iter().fold(1.0f64, |m, v| m.max(v.abs()));
        let at = |threads: usize, single: bool| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let mut y = vec![7.0; 3 * n];
            let mut scratch = UpperScratch::default();
            pool.install(|| {
                if single {
                    UpperTriangle::<[f32; 9]>::of(&a).product(&x, &mut y, &mut scratch)
                } else {
                    UpperTriangle::<Block>::of(&a).product(&x, &mut y, &mut scratch)
                }
            });
            y
        };
        let double = at(1, false);
        for (p, q) in double.iter().zip(&full) {
            assert!((p - q).abs() <= 1e-13 * scale, "{p} against {q}");
        }
        assert_eq!(double, at(2, false));
        let single = at(1, true);
        for (p, q) in single.iter().zip(&full) {
            assert!((p - q).abs() <= 1e-5 * scale, "{p} against {q}");
        }
        assert_eq!(single, at(2, true));
        // A second matrix of the same pattern refills in place; another pattern is rebuilt.
        let mut u = UpperTriangle::<Block>::of(&a);
        let mut b = a.clone();
        b.values.iter_mut().for_each(|v| v.iter_mut().for_each(|e| *e *= 2.0));
        u.refill(&b);
        let mut y = vec![0.0; 3 * n];
        u.product(&x, &mut y, &mut UpperScratch::default());
        for (p, q) in y.iter().zip(&double) {
            assert!((p - 2.0 * q).abs() <= 1e-12 * scale);
        }
        let small = BlockSparseMatrix::from_sorted_pairs(2, &[(0, 0), (1, 1)]);
        u.refill(&small);
        assert_eq!(u.n_blocks(), 2);
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
