//! The numeric supernodal Cholesky factorisation `L Lᵀ` over faer's symbolic analysis, with the
//! elimination tree's independent subtrees factorised on different threads.
//!
//! faer 0.24 factorises the supernodes one after the other (parallel only inside each
//! supernode's dense kernels, which are small in a cloth's or a towel's factor), so a second
//! thread sat idle through half of a folded towel's Newton iteration. The supernodes of two
//! disjoint subtrees of the elimination tree never read each other's columns: under nested
//! dissection the two halves of each separator are such subtrees. Here every supernode is
//! factorised *left-looking* — its columns gathered from the matrix, then the updates of the
//! supernodes below it that reach its rows subtracted in ascending order, then a dense Cholesky
//! of its diagonal block and a triangular solve for the rows below — by one thread, once all of
//! its subtree is done. The top separators, whose hundreds of updates no subtree shares, are
//! gathered and updated in column blocks of a fixed width, the blocks in parallel. Each
//! supernode's arithmetic is the same whichever thread runs it and whatever ran beside it, so
//! the factor is bit-identical at any thread count.
//!
//! The triangular solves walk the same tree ([`solve_in_place`]): up, each supernode takes what
//! the supernodes below it left for its rows, solves with its diagonal block and leaves its
//! own contribution for the rows above; down, it reads the finished rows above it. Both are
//! bit-identical at any thread count too (faer's solves with two threads rounded differently
//! from one: a folded towel's residuals differed in the fourth digit between `--threads 1`
//! and `2`; now they agree to the last).
//!
//! The factor is written in faer's supernodal layout (each supernode's columns column-major,
//! its diagonal block's rows first, then its pattern's).

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch, LltError};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky;
use faer::{Accum, MatMut, MatRef, Par};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// A subtree with less work than this (multiply-adds, estimated) is factorised on the thread
/// that reached it: forking costs more than it saves.
const FORK_ABOVE_WORK: f64 = 2.0e5;

/// Supernodes of at least this many columns are gathered and updated in blocks of
/// `BLOCK_COLUMNS` columns, in parallel: the top separators of a folded towel's factor (up to
/// ~1000 columns, ~400 updates) took a third of the factorisation's time at two threads with
/// one thread idle. The blocks are fixed, so the arithmetic does not depend on the thread count.
const SPLIT_FROM_COLUMNS: usize = 2 * BLOCK_COLUMNS;
const BLOCK_COLUMNS: usize = 64;
/// Supernodes of at least this many columns solve for their `L₂₁` in chunks of
/// `TRIANGULAR_CHUNK_ROWS` rows, in parallel; the chunks are fixed, so the arithmetic does not
/// depend on the thread count (the unit tests' small grids split from far smaller supernodes,
/// so that their thread-count checks cover it).
const TRIANGULAR_SPLIT_FROM_COLUMNS: usize = if cfg!(test) { 4 } else { SPLIT_FROM_COLUMNS };
const TRIANGULAR_CHUNK_ROWS: usize = if cfg!(test) { 8 } else { 256 };
/// A supernode's part of a triangular solve below its diagonal block (rows × columns) from which
/// it is split across threads (a folded towel's top separators: ~10⁵–10⁶ entries each; the unit
/// tests' small grids split from far fewer, so that their thread-count checks cover the split).
const PARALLEL_SOLVE_FROM_ENTRIES: usize = if cfg!(test) { 1 << 8 } else { 1 << 16 };
/// Rows of such a part per task in the forward pass.
const SOLVE_CHUNK_ROWS: usize = 256;

/// Whether a supernode's part below its diagonal block (`rows` × `cols`) is solved on several
/// threads.
fn split_solve(rows: usize, cols: usize) -> bool {
    rows * cols >= PARALLEL_SOLVE_FROM_ENTRIES && rayon::current_num_threads() > 1
}

/// The scalars the factor is computed in (single or double precision).
pub trait FactorScalar:
    faer::traits::ComplexField + Copy + Default + Send + Sync + std::ops::AddAssign + std::ops::SubAssign
{
    /// One.
    const ONE: Self;
}

impl FactorScalar for f32 {
    const ONE: f32 = 1.0;
}

impl FactorScalar for f64 {
    const ONE: f64 = 1.0;
}

/// The supernodal elimination tree of one symbolic analysis and, per supernode, the supernodes
/// whose columns update it.
pub struct SupernodeTree {
    /// The first column of each supernode, and the column count last.
    begin: Vec<usize>,
    /// Supernodes with a row of their pattern in supernode `s`'s columns, ascending:
    /// `updates[update_start[s]..update_start[s + 1]]`.
    update_start: Vec<usize>,
    updates: Vec<Update>,
    /// Children in the elimination tree: `children[child_start[s]..child_start[s + 1]]`.
    child_start: Vec<usize>,
    children: Vec<u32>,
    roots: Vec<u32>,
    /// Estimated multiply-adds of each supernode's subtree.
    subtree_work: Vec<f64>,
    /// The largest supernode (columns) and the longest update block (rows × columns).
    max_columns: usize,
    max_update: usize,
}

impl SupernodeTree {
    /// The tree of `symbolic`.
    pub fn new(symbolic: &SymbolicSupernodalCholesky<usize>) -> Self {
        let n_super = symbolic.n_supernodes();
        let mut begin = symbolic.supernode_begin().to_vec();
        begin.push(symbolic.supernode_end().last().copied().unwrap_or(0));
        let (row_ptr, rows, nnz) = (
            symbolic.col_ptr_for_row_idx(),
            symbolic.row_idx(),
            symbolic.nnz_per_super(),
        );
        let pattern = |s: usize| &rows[row_ptr[s]..row_ptr[s] + nnz[s]];
        let mut supernode_of_col = vec![0u32; symbolic.nrows()];
        for s in 0..n_super {
            supernode_of_col[begin[s]..begin[s + 1]].fill(s as u32);
        }
        // The supernodes each pattern reaches (rows sorted, so each reached supernode once, in
        // ascending order), collected per reached supernode: ascending in the updater.
        let mut reached: Vec<Vec<Update>> = vec![Vec::new(); n_super];
        let mut parent = vec![u32::MAX; n_super];
        let mut max_update = 0;
        for d in 0..n_super {
            let p = pattern(d);
            let mut last = u32::MAX;
            for (k, &row) in p.iter().enumerate() {
                let s = supernode_of_col[row];
                if s != last {
                    let below = p.len() - k;
                    let within = p[k..].partition_point(|&r| r < begin[s as usize + 1]);
                    max_update = max_update.max(below * within);
                    reached[s as usize].push(Update {
                        d: d as u32,
                        first: k as u32,
                        within: within as u32,
                    });
                    last = s;
                }
            }
            if let Some(&row) = p.first() {
                parent[d] = supernode_of_col[row];
            }
        }
        let mut update_start = Vec::with_capacity(n_super + 1);
        let mut updates = Vec::new();
        update_start.push(0);
        for list in &reached {
            updates.extend_from_slice(list);
            update_start.push(updates.len());
        }
        let mut child_count = vec![0usize; n_super + 1];
        for &p in parent.iter().filter(|&&p| p != u32::MAX) {
            child_count[p as usize + 1] += 1;
        }
        for s in 0..n_super {
            child_count[s + 1] += child_count[s];
        }
        let child_start = child_count;
        let mut fill = child_start.clone();
        let mut children = vec![0u32; child_start[n_super]];
        let mut roots = Vec::new();
        for (d, &p) in parent.iter().enumerate() {
            if p == u32::MAX {
                roots.push(d as u32);
            } else {
                children[fill[p as usize]] = d as u32;
                fill[p as usize] += 1;
            }
        }
        // Children precede their parent (a pattern's rows lie beyond its columns): sums in one
        // ascending pass.
        let mut subtree_work: Vec<f64> = (0..n_super)
            .map(|s| {
                let (cols, below) = ((begin[s + 1] - begin[s]) as f64, nnz[s] as f64);
                cols * cols * cols / 3.0 + cols * cols * below + cols * below * below
            })
            .collect();
        for d in 0..n_super {
            if parent[d] != u32::MAX {
                subtree_work[parent[d] as usize] += subtree_work[d];
            }
        }
        let max_columns = (0..n_super).map(|s| begin[s + 1] - begin[s]).max().unwrap_or(0);
        Self {
            begin,
            update_start,
            updates,
            child_start,
            children,
            roots,
            subtree_work,
            max_columns,
            max_update,
        }
    }

    fn children(&self, s: usize) -> &[u32] {
        &self.children[self.child_start[s]..self.child_start[s + 1]]
    }

    fn updates(&self, s: usize) -> &[Update] {
        &self.updates[self.update_start[s]..self.update_start[s + 1]]
    }
}

/// Supernode `d`'s update of a later supernode: the rows of `d`'s pattern from `first` on reach
/// it, the first `within` of them inside its columns.
#[derive(Clone, Copy)]
struct Update {
    d: u32,
    first: u32,
    within: u32,
}

/// One thread's scratch: where each row of the current supernode lies in it, the update block,
/// the dense factorisation's workspace.
struct Scratch<T> {
    local: Vec<usize>,
    block: BlockScratch<T>,
    stack: MemBuffer,
    /// The largest diagonal block `stack` is sized for.
    stack_columns: usize,
}

impl<T: FactorScalar> Scratch<T> {
    fn new(n: usize, tree: &SupernodeTree) -> Self {
        let mut scratch = Self {
            local: Vec::new(),
            block: BlockScratch::default(),
            stack: MemBuffer::new(StackReq::EMPTY),
            stack_columns: 0,
        };
        scratch.fit(n, tree);
        scratch
    }

    /// Sized for a matrix of `n` unknowns and `tree` (`local` is all `usize::MAX` between
    /// supernodes: each resets the entries it set).
    fn fit(&mut self, n: usize, tree: &SupernodeTree) {
        self.local.resize(n, usize::MAX);
        if self.block.update.len() < tree.max_update {
            self.block.update.resize(tree.max_update, T::default());
        }
        if self.stack_columns < tree.max_columns {
            self.stack = MemBuffer::new(cholesky_in_place_scratch::<T>(
                tree.max_columns,
                Par::Seq,
                Default::default(),
            ));
            self.stack_columns = tree.max_columns;
        }
    }
}

/// The scratch of a supernode's updates (or of one column block's, see `SPLIT_FROM_COLUMNS`):
/// the update's row positions and block.
#[derive(Default)]
struct BlockScratch<T> {
    at: Vec<usize>,
    update: Vec<T>,
}

/// The factorisation's per-task scratch, kept between factorisations (a towel's is a few MB per
/// task: allocated and zeroed at every factorisation otherwise).
pub struct FactorScratch<T> {
    pool: Vec<Scratch<T>>,
    blocks: Vec<BlockScratch<T>>,
}

impl<T> Default for FactorScratch<T> {
    fn default() -> Self {
        Self {
            pool: Vec::new(),
            blocks: Vec::new(),
        }
    }
}

/// The factor's values, written by several threads: each supernode's slice by the one thread
/// that factorises it, read by others only after it is complete.
#[derive(Clone, Copy)]
struct Shared<T>(*mut T, usize);
// SAFETY: see `factorize` and `solve_in_place`: disjoint writes, reads only of finished
// supernodes.
unsafe impl<T> Send for Shared<T> {}
unsafe impl<T> Sync for Shared<T> {}

impl<T> Shared<T> {
    /// The pointer (a method, so closures capture the whole `Shared`, which is `Sync`).
    fn ptr(self) -> *mut T {
        self.0
    }
}

/// The lower triangle of the (already permuted) matrix in compressed columns.
pub struct LowerColumns<'a, T> {
    /// Column `j`'s entries are `col_ptr[j]..col_ptr[j + 1]`.
    pub col_ptr: &'a [usize],
    /// Their rows (those above the diagonal are skipped).
    pub row_idx: &'a [usize],
    /// Their values.
    pub values: &'a [T],
}

/// `L Lᵀ = A` into `factor` (faer's supernodal layout of `symbolic`, `symbolic.len_val()`
/// values), the subtrees of `tree` in parallel when the current pool has several threads. An
/// error names the first pivot found not positive.
pub fn factorize<T: FactorScalar>(
    symbolic: &SymbolicSupernodalCholesky<usize>,
    tree: &SupernodeTree,
    a: &LowerColumns<'_, T>,
    factor: &mut [T],
    scratch: &mut FactorScratch<T>,
) -> Result<(), String> {
    assert_eq!(factor.len(), symbolic.len_val(), "factor sized for its analysis");
    let n = symbolic.nrows();
    for kept in &mut scratch.pool {
        kept.fit(n, tree);
    }
    let failure = AtomicUsize::new(usize::MAX);
    let block_pool = Mutex::new(std::mem::take(&mut scratch.blocks));
    let job = Job {
        symbolic,
        tree,
        a,
        factor: Shared(factor.as_mut_ptr(), factor.len()),
        failure: &failure,
        block_pool: &block_pool,
    };
    let pool = Mutex::new(std::mem::take(&mut scratch.pool));
    tree.traverse(Direction::Up, &pool, &|| Scratch::new(n, tree), &|s, scratch| {
        job.supernode(s, scratch)
    });
    scratch.pool = pool.into_inner().unwrap_or_else(|e| e.into_inner());
    scratch.blocks = block_pool.into_inner().unwrap_or_else(|e| e.into_inner());
    match failure.into_inner() {
        usize::MAX => Ok(()),
        index => Err(format!("NonPositivePivot {{ index: {index} }}")),
    }
}

/// `x ← (L Lᵀ)⁻¹ x` with a factor of [`factorize`], the subtrees in parallel as there, the
/// result bit-identical at any thread count. Going up, each supernode first subtracts from its
/// entries what the supernodes below it left for them (in ascending order), solves with its
/// diagonal block, and leaves `L₂₁ x_s` for the rows of its pattern in `pushed` (at the
/// pattern's offset in faer's row indices: one value per row index); going down, each
/// supernode reads its pattern's entries (finished above it) and solves with `L₁₁ᵀ`. Every
/// block of the factor is read column by column, once per pass.
pub fn solve_in_place<T: FactorScalar + std::ops::Mul<Output = T> + std::ops::Div<Output = T>>(
    symbolic: &SymbolicSupernodalCholesky<usize>,
    tree: &SupernodeTree,
    factor: &[T],
    x: &mut [T],
    pushed: &mut Vec<T>,
) {
    assert_eq!(factor.len(), symbolic.len_val(), "factor sized for its analysis");
    assert_eq!(x.len(), symbolic.nrows(), "one right-hand side");
    let (row_ptr, rows, nnz, val_ptr) = (
        symbolic.col_ptr_for_row_idx(),
        symbolic.row_idx(),
        symbolic.nnz_per_super(),
        symbolic.col_ptr_for_val(),
    );
    pushed.resize(rows.len(), T::default());
    let begin = &tree.begin;
    let x_shared = Shared(x.as_mut_ptr(), x.len());
    let pushed_shared = Shared(pushed.as_mut_ptr(), pushed.len());
    let block = |s: usize| {
        let (start, cols) = (begin[s], begin[s + 1] - begin[s]);
        let l = &factor[val_ptr[s]..val_ptr[s + 1]];
        (start, cols, l, cols + nnz[s])
    };
    // SAFETY (both passes): supernode `s` writes only its own entries of `x` and of `pushed`
    // and reads only those of supernodes finished before it (below it going up, above it going
    // down); the slices are within `x` and `pushed` (the analysis' sizes, asserted above).
    tree.traverse(Direction::Up, &Mutex::new(Vec::new()), &|| (), &|s, _| {
        let (start, cols, l, n_rows) = block(s);
        let xs = unsafe { std::slice::from_raw_parts_mut(x_shared.ptr().add(start), cols) };
        for update in tree.updates(s) {
            let d = update.d as usize;
            let (first, within) = (update.first as usize, update.within as usize);
            let at = row_ptr[d] + first;
            let from = unsafe { std::slice::from_raw_parts(pushed_shared.ptr().add(at), within) };
            for (&row, &v) in rows[at..at + within].iter().zip(from) {
                xs[row - start] -= v;
            }
        }
        for j in 0..cols {
            let column = &l[j * n_rows..(j + 1) * n_rows];
            let xj = xs[j] / column[j];
            xs[j] = xj;
            for (xi, &lij) in xs[j + 1..].iter_mut().zip(&column[j + 1..cols]) {
                *xi -= lij * xj;
            }
        }
        let out = unsafe { std::slice::from_raw_parts_mut(pushed_shared.ptr().add(row_ptr[s]), nnz[s]) };
        // `out = L₂₁ xs`, rows independent: a top separator's rows in chunks on several threads
        // (each row summed in the same order: the same bits at any thread count).
        let xs = &*xs;
        let rows_from = |first: usize, out: &mut [T]| {
            out.fill(T::default());
            // Four columns per pass over `out` (a quarter of its loads and stores).
            let len = out.len();
            let below = |j: usize| &l[j * n_rows + cols + first..][..len];
            let mut j = 0;
            while j + 4 <= cols {
                let (c0, c1, c2, c3) = (below(j), below(j + 1), below(j + 2), below(j + 3));
                let (x0, x1, x2, x3) = (xs[j], xs[j + 1], xs[j + 2], xs[j + 3]);
                for r in 0..out.len() {
                    out[r] += c0[r] * x0 + c1[r] * x1 + c2[r] * x2 + c3[r] * x3;
                }
                j += 4;
            }
            for (j, &xj) in xs.iter().enumerate().skip(j) {
                for (o, &lij) in out.iter_mut().zip(below(j)) {
                    *o += lij * xj;
                }
            }
        };
        if split_solve(out.len(), cols) {
            out.par_chunks_mut(SOLVE_CHUNK_ROWS)
                .enumerate()
                .for_each(|(k, chunk)| rows_from(k * SOLVE_CHUNK_ROWS, chunk));
        } else {
            rows_from(0, out);
        }
    });
    tree.traverse(
        Direction::Down,
        &Mutex::new(Vec::new()),
        &|| (Vec::new(), Vec::new()),
        &|s, scratch: &mut (Vec<T>, Vec<T>)| {
            let (start, cols, l, n_rows) = block(s);
            let pattern = &rows[row_ptr[s]..row_ptr[s] + nnz[s]];
            let (gathered, below) = scratch;
            gathered.clear();
            gathered.extend(pattern.iter().map(|&row| unsafe { *x_shared.ptr().add(row) }));
            let xs = unsafe { std::slice::from_raw_parts_mut(x_shared.ptr().add(start), cols) };
            // `L₂₁ᵀ` times the rows below, column by column (independent: a top separator's
            // columns on several threads, each the same sum).
            let below_dot = |j: usize| dot_lanes(&l[j * n_rows + cols..(j + 1) * n_rows], gathered);
            below.clear();
            if split_solve(pattern.len(), cols) {
                below.par_extend((0..cols).into_par_iter().map(below_dot));
            } else {
                below.extend((0..cols).map(below_dot));
            }
            for j in (0..cols).rev() {
                let column = &l[j * n_rows..(j + 1) * n_rows];
                let sum = below[j] + dot_lanes(&column[j + 1..cols], &xs[j + 1..]);
                xs[j] = (xs[j] - sum) / column[j];
            }
        },
    );
}

/// `a · b` summed in 32 lanes, then 8, then one (a fixed order, which the compiler keeps in
/// four independent vector registers: one would wait on its own additions).
fn dot_lanes<T: FactorScalar + std::ops::Mul<Output = T>>(a: &[T], b: &[T]) -> T {
    let n = a.len().min(b.len());
    let mut wide = [T::default(); 32];
    let n32 = n - n % 32;
    for (ca, cb) in a[..n32].chunks_exact(32).zip(b[..n32].chunks_exact(32)) {
        for k in 0..32 {
            wide[k] += ca[k] * cb[k];
        }
    }
    let mut lanes = [T::default(); 8];
    for k in 0..32 {
        lanes[k % 8] += wide[k];
    }
    let n8 = n - n % 8;
    for (ca, cb) in a[n32..n8].chunks_exact(8).zip(b[n32..n8].chunks_exact(8)) {
        for k in 0..8 {
            lanes[k] += ca[k] * cb[k];
        }
    }
    let mut sum = T::default();
    for (&x, &y) in a[n8..n].iter().zip(&b[n8..n]) {
        sum += x * y;
    }
    for lane in lanes {
        sum += lane;
    }
    sum
}

/// The order of a traversal of the elimination tree.
#[derive(Clone, Copy)]
enum Direction {
    /// Children before their parent.
    Up,
    /// Parents before their children.
    Down,
}

/// A factorisation's data, shared by the threads.
struct Job<'a, T> {
    symbolic: &'a SymbolicSupernodalCholesky<usize>,
    tree: &'a SupernodeTree,
    a: &'a LowerColumns<'a, T>,
    factor: Shared<T>,
    /// The first column found with a pivot not positive (`usize::MAX`: none yet).
    failure: &'a AtomicUsize,
    /// The column blocks' scratch.
    block_pool: &'a Mutex<Vec<BlockScratch<T>>>,
}

impl SupernodeTree {
    /// `f` on every supernode once all below it are done (`Up`) or all above it (`Down`:
    /// parents before children); the subtrees in parallel when the current pool has several
    /// threads, each task with a scratch from `pool` (or made by `scratch`; all returned to
    /// `pool`).
    fn traverse<S: Send>(
        &self,
        direction: Direction,
        pool: &Mutex<Vec<S>>,
        scratch: &(impl Fn() -> S + Sync),
        f: &(impl Fn(usize, &mut S) + Sync),
    ) {
        let parallel = rayon::current_num_threads() > 1;
        let walk = Walk {
            tree: self,
            pool,
            scratch,
            f,
            parallel,
        };
        let visit = |&s: &u32| match direction {
            Direction::Up => walk.up(s as usize),
            Direction::Down => walk.down(s as usize),
        };
        if parallel {
            self.roots.par_iter().for_each(visit);
        } else {
            self.roots.iter().for_each(visit);
        }
    }
}

/// A traversal's state (either direction).
struct Walk<'a, S, M, F> {
    tree: &'a SupernodeTree,
    pool: &'a Mutex<Vec<S>>,
    scratch: &'a M,
    f: &'a F,
    parallel: bool,
}

impl<S: Send, M: Fn() -> S + Sync, F: Fn(usize, &mut S) + Sync> Walk<'_, S, M, F> {
    /// The subtree of `s`: a chain of single children walked down first (no recursion per
    /// supernode), the subtrees below it (in parallel when heavy), then the chain bottom-up.
    fn up(&self, s: usize) {
        let tree = self.tree;
        let scratch = if !self.parallel || tree.subtree_work[s] < FORK_ABOVE_WORK {
            let mut scratch = self.take();
            self.sequential(s, &mut scratch);
            scratch
        } else {
            let mut chain = vec![s];
            let mut bottom = s;
            while let [only] = tree.children(bottom) {
                bottom = *only as usize;
                chain.push(bottom);
            }
            tree.children(bottom).par_iter().for_each(|&c| self.up(c as usize));
            let mut scratch = self.take();
            for &t in chain.iter().rev() {
                (self.f)(t, &mut scratch);
            }
            scratch
        };
        self.pool.lock().unwrap_or_else(|e| e.into_inner()).push(scratch);
    }

    /// The subtree of `s` on this thread, in postorder.
    fn sequential(&self, s: usize, scratch: &mut S) {
        // Depth-first: (supernode, next child to visit).
        let mut stack = vec![(s, 0usize)];
        while let Some(&mut (t, ref mut next)) = stack.last_mut() {
            let children = self.tree.children(t);
            if *next < children.len() {
                let c = children[*next] as usize;
                *next += 1;
                stack.push((c, 0));
            } else {
                (self.f)(t, scratch);
                stack.pop();
            }
        }
    }

    /// The subtree of `s` top-down: a chain of single children first, then the subtrees below
    /// it (in parallel when heavy).
    fn down(&self, s: usize) {
        let tree = self.tree;
        let mut scratch = self.take();
        if !self.parallel || tree.subtree_work[s] < FORK_ABOVE_WORK {
            let mut stack = vec![s as u32];
            while let Some(t) = stack.pop() {
                (self.f)(t as usize, &mut scratch);
                stack.extend_from_slice(tree.children(t as usize));
            }
            self.pool.lock().unwrap_or_else(|e| e.into_inner()).push(scratch);
            return;
        }
        let mut t = s;
        let children = loop {
            (self.f)(t, &mut scratch);
            match tree.children(t) {
                [only] => t = *only as usize,
                children => break children,
            }
        };
        self.pool.lock().unwrap_or_else(|e| e.into_inner()).push(scratch);
        children.par_iter().for_each(|&c| self.down(c as usize));
    }

    fn take(&self) -> S {
        let pooled = self.pool.lock().unwrap_or_else(|e| e.into_inner()).pop();
        pooled.unwrap_or_else(self.scratch)
    }
}

impl<'a, T: FactorScalar> Job<'a, T> {
    /// Factorise supernode `s` (every supernode below it is done).
    fn supernode(&self, s: usize, scratch: &mut Scratch<T>) {
        if self.failure.load(Ordering::Relaxed) != usize::MAX {
            // The factorisation has failed: nothing computed from here on is read.
            return;
        }
        let val_ptr = self.symbolic.col_ptr_for_val();
        let (start, end) = (self.tree.begin[s], self.tree.begin[s + 1]);
        let cols = end - start;
        let pattern = self.pattern(s);
        let n_rows = cols + pattern.len();
        // SAFETY: supernode `s`'s values are written only here, by this thread; the updating
        // supernodes read below are in `s`'s subtree, finished before it started.
        let ls: &mut [T] = unsafe {
            assert!(val_ptr[s + 1] <= self.factor.1);
            std::slice::from_raw_parts_mut(self.factor.ptr().add(val_ptr[s]), val_ptr[s + 1] - val_ptr[s])
        };
        debug_assert_eq!(ls.len(), n_rows * cols);
        let local = &mut scratch.local;
        for (i, &row) in pattern.iter().enumerate() {
            local[row] = cols + i;
        }
        if cols >= SPLIT_FROM_COLUMNS {
            // Column blocks of a fixed width, each gathered and updated on its own (in parallel
            // when the pool has several threads): the same arithmetic at any thread count.
            let local: &[usize] = local;
            let each = |(b, columns): (usize, &mut [T]), block: &mut BlockScratch<T>| {
                self.gather_and_update(s, b * BLOCK_COLUMNS, columns, local, block);
            };
            if rayon::current_num_threads() > 1 {
                ls.par_chunks_mut(BLOCK_COLUMNS * n_rows).enumerate().for_each(|item| {
                    let mut block = self
                        .block_pool
                        .lock()
                        .unwrap_or_else(|e| e.into_inner())
                        .pop()
                        .unwrap_or_default();
                    each(item, &mut block);
                    self.block_pool.lock().unwrap_or_else(|e| e.into_inner()).push(block);
                });
            } else {
                let block = &mut scratch.block;
                ls.chunks_mut(BLOCK_COLUMNS * n_rows)
                    .enumerate()
                    .for_each(|item| each(item, block));
            }
        } else {
            self.gather_and_update(s, 0, ls, local, &mut scratch.block);
        }
        let local = &mut scratch.local;
        for &row in pattern {
            local[row] = usize::MAX;
        }
        let (mut top, mut bottom) = MatMut::from_column_major_slice_mut(ls, n_rows, cols).split_at_row_mut(cols);
        let stack = MemStack::new(&mut scratch.stack);
        if let Err(LltError::NonPositivePivot { index }) =
            cholesky_in_place(top.rb_mut(), Default::default(), Par::Seq, stack, Default::default())
        {
            self.failure.fetch_min(start + index, Ordering::Relaxed);
            return;
        }
        // L₂₁ L₁₁ᵀ = A₂₁, i.e. L₁₁ L₂₁ᵀ = A₂₁ᵀ: each row of L₂₁ on its own. A split supernode's
        // rows go in fixed chunks (in parallel when the pool has several threads: at two threads
        // these solves were a serial ~0.4 s of the folded towel's 10-step window).
        let solve_rows = |rows: MatMut<'_, T>| {
            faer::linalg::triangular_solve::solve_lower_triangular_in_place(top.rb(), rows.transpose_mut(), Par::Seq);
        };
        if cols >= TRIANGULAR_SPLIT_FROM_COLUMNS && bottom.nrows() > TRIANGULAR_CHUNK_ROWS {
            let mut chunks = Vec::with_capacity(bottom.nrows().div_ceil(TRIANGULAR_CHUNK_ROWS));
            while bottom.nrows() > TRIANGULAR_CHUNK_ROWS {
                let (head, tail) = bottom.split_at_row_mut(TRIANGULAR_CHUNK_ROWS);
                chunks.push(head);
                bottom = tail;
            }
            chunks.push(bottom);
            if rayon::current_num_threads() > 1 {
                chunks.into_par_iter().for_each(solve_rows);
            } else {
                chunks.into_iter().for_each(solve_rows);
            }
        } else {
            solve_rows(bottom);
        }
    }

    /// The rows of supernode `s`'s pattern (below its columns).
    fn pattern(&self, s: usize) -> &'a [usize] {
        let sym = self.symbolic;
        let start = sym.col_ptr_for_row_idx()[s];
        &sym.row_idx()[start..start + sym.nnz_per_super()[s]]
    }

    /// Supernode `s`'s columns from `c0` on (`columns`, whole columns of its block, zeroed
    /// here): the matrix's entries gathered, then the updates of the supernodes below it
    /// subtracted in ascending order. `local` places each pattern row in the block.
    fn gather_and_update(&self, s: usize, c0: usize, columns: &mut [T], local: &[usize], block: &mut BlockScratch<T>) {
        let BlockScratch { at, update } = block;
        let val_ptr = self.symbolic.col_ptr_for_val();
        let begin = &self.tree.begin;
        let (start, end) = (begin[s], begin[s + 1]);
        let n_rows = end - start + self.pattern(s).len();
        let c1 = c0 + columns.len() / n_rows;
        columns.fill(T::default());
        for (jj, j) in (start + c0..start + c1).enumerate() {
            let column = &mut columns[jj * n_rows..(jj + 1) * n_rows];
            for k in self.a.col_ptr[j]..self.a.col_ptr[j + 1] {
                let i = self.a.row_idx[k];
                if i < j {
                    continue;
                }
                let r = if i < end { i - start } else { local[i] };
                column[r] += self.a.values[k];
            }
        }
        for u in self.tree.updates(s) {
            let d = u.d as usize;
            let d_cols = begin[d + 1] - begin[d];
            let d_pattern = self.pattern(d);
            let d_rows = d_cols + d_pattern.len();
            let (first, within) = (u.first as usize, u.within as usize);
            let reach = &d_pattern[first..];
            // The update's columns that fall in `c0..c1`.
            let ca = reach[..within].partition_point(|&row| row < start + c0);
            let cb = reach[..within].partition_point(|&row| row < start + c1);
            if ca == cb {
                continue;
            }
            let (below, width) = (reach.len() - ca, cb - ca);
            // SAFETY: `d` is finished (below `s` in the tree) and not written any more.
            let ld: &[T] =
                unsafe { std::slice::from_raw_parts(self.factor.ptr().add(val_ptr[d]), val_ptr[d + 1] - val_ptr[d]) };
            let ld = MatRef::from_column_major_slice(ld, d_rows, d_cols);
            let lower = ld.subrows(d_cols + first + ca, below);
            let upper = ld.subrows(d_cols + first + ca, width);
            if update.len() < below * width {
                update.resize(below * width, T::default());
            }
            let w = &mut update[..below * width];
            matmul_into(w, below, width, lower, upper);
            // Where each reached row lies in `s`: inside its columns, then in its pattern.
            at.clear();
            at.extend(reach[ca..within].iter().map(|&row| row - start));
            at.extend(reach[within..].iter().map(|&row| local[row]));
            // Subtract the lower part: column c of the update is column `at[c]` of `s`, its
            // rows from the same index on.
            for c in 0..width {
                let target = at[c] - c0;
                let column = &mut columns[target * n_rows..(target + 1) * n_rows];
                let wc = &w[c * below..(c + 1) * below];
                for (&i, &v) in at[c..].iter().zip(&wc[c..]) {
                    column[i] -= v;
                }
            }
        }
    }
}

/// `w = lower · upperᵀ` (`rows × cols`, column-major).
fn matmul_into<T: FactorScalar>(w: &mut [T], rows: usize, cols: usize, lower: MatRef<'_, T>, upper: MatRef<'_, T>) {
    let dst = MatMut::from_column_major_slice_mut(w, rows, cols);
    faer::linalg::matmul::matmul(dst, Accum::Replace, lower, upper.transpose(), T::ONE, Par::Seq);
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::linalg::cholesky::{
        factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholeskyRaw, SymmetricOrdering,
    };
    use faer::sparse::linalg::SupernodalThreshold;
    use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
    use faer::Side;

    /// The lower triangle (compressed columns) of a 5-point Laplacian plus a mass on a
    /// `width × height` grid, ordered as one step of nested dissection: the nodes left of the
    /// middle column, those right of it, then the middle column (so the elimination tree has
    /// two large subtrees).
    fn dissected_grid(width: usize, height: usize, mass: f64) -> (SymbolicSparseColMat<usize>, Vec<f64>) {
        let middle = width / 2;
        let mut nodes: Vec<(usize, usize)> = Vec::new();
        for part in 0..3 {
            for y in 0..height {
                for x in 0..width {
                    let in_part = match part {
                        0 => x < middle,
                        1 => x > middle,
                        _ => x == middle,
                    };
                    if in_part {
                        nodes.push((x, y));
                    }
                }
            }
        }
        let mut index = vec![0usize; width * height];
        for (i, &(x, y)) in nodes.iter().enumerate() {
            index[y * width + x] = i;
        }
        let n = nodes.len();
        let mut columns: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
        for (j, &(x, y)) in nodes.iter().enumerate() {
            columns[j].push((j, 4.0 + mass));
            let mut neighbour = |xx: usize, yy: usize| {
                let i = index[yy * width + xx];
                if i > j {
                    columns[j].push((i, -1.0));
                }
            };
            if x > 0 {
                neighbour(x - 1, y);
            }
            if x + 1 < width {
                neighbour(x + 1, y);
            }
            if y > 0 {
                neighbour(x, y - 1);
            }
            if y + 1 < height {
                neighbour(x, y + 1);
            }
        }
        let (mut col_ptr, mut row_idx, mut values) = (vec![0], Vec::new(), Vec::new());
        for column in &mut columns {
            column.sort_by_key(|e| e.0);
            row_idx.extend(column.iter().map(|e| e.0));
            values.extend(column.iter().map(|e| e.1));
            col_ptr.push(row_idx.len());
        }
        (SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx), values)
    }

    /// faer's supernodal analysis of the lower `pattern` in its own order (faer reads the upper
    /// triangle when no ordering is asked for: the pattern's transpose).
    fn analyse(pattern: &SymbolicSparseColMat<usize>) -> faer::sparse::linalg::cholesky::SymbolicCholesky<usize> {
        let n = pattern.ncols();
        let mut upper: Vec<Vec<usize>> = vec![Vec::new(); n];
        for j in 0..n {
            for i in pattern.row_idx_of_col(j) {
                upper[i].push(j);
            }
        }
        let (mut col_ptr, mut row_idx) = (vec![0], Vec::new());
        for column in &upper {
            row_idx.extend_from_slice(column);
            col_ptr.push(row_idx.len());
        }
        let upper = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        factorize_symbolic_cholesky(upper.as_ref(), Side::Upper, SymmetricOrdering::Identity, params).unwrap()
    }

    fn ours(
        threads: usize,
        symbolic: &SymbolicSupernodalCholesky<usize>,
        pattern: &SymbolicSparseColMat<usize>,
        values: &[f64],
    ) -> Result<Vec<f64>, String> {
        let tree = SupernodeTree::new(symbolic);
        let lower = LowerColumns {
            col_ptr: pattern.col_ptr(),
            row_idx: pattern.row_idx(),
            values,
        };
        let mut factor = vec![0.0; symbolic.len_val()];
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let mut scratch = FactorScratch::default();
        pool.install(|| factorize(symbolic, &tree, &lower, &mut factor, &mut scratch))?;
        // Again with the kept scratch: the same factor.
        let mut again = vec![0.0; factor.len()];
        pool.install(|| factorize(symbolic, &tree, &lower, &mut again, &mut scratch))?;
        assert!(again.iter().zip(&factor).all(|(a, b)| a.to_bits() == b.to_bits()));
        Ok(factor)
    }

    /// The factor equals faer's own supernodal factorisation to rounding, and is bit-identical
    /// at one and at two threads (the two halves of the grid then run side by side, and the
    /// separator's column blocks).
    #[test]
    fn the_factor_is_faers_and_independent_of_the_thread_count() {
        let (pattern, values) = dissected_grid(15, 300, 0.01);
        let analysis = analyse(&pattern);
        let SymbolicCholeskyRaw::Supernodal(symbolic) = analysis.raw() else {
            panic!("a supernodal analysis was forced");
        };
        let tree = SupernodeTree::new(symbolic);
        assert!(tree.roots.len() == 1 && tree.subtree_work[tree.roots[0] as usize] > 10.0 * FORK_ABOVE_WORK);
        assert!(
            tree.max_columns >= SPLIT_FROM_COLUMNS + BLOCK_COLUMNS / 2,
            "a separator split in blocks"
        );
        assert!(
            (0..tree.begin.len() - 1).any(|s| tree.begin[s + 1] - tree.begin[s] >= TRIANGULAR_SPLIT_FROM_COLUMNS
                && symbolic.nnz_per_super()[s] > 2 * TRIANGULAR_CHUNK_ROWS),
            "a supernode's rows below solved in chunks"
        );
        let one = ours(1, symbolic, &pattern, &values).unwrap();
        let two = ours(2, symbolic, &pattern, &values).unwrap();
        assert!(one.iter().zip(&two).all(|(a, b)| a.to_bits() == b.to_bits()));
        let mut reference = vec![0.0; analysis.len_val()];
        let req = analysis.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default());
        let mut buffer = MemBuffer::new(req);
        analysis
            .factorize_numeric_llt(
                &mut reference,
                SparseColMatRef::new(pattern.as_ref(), &values),
                Side::Lower,
                Default::default(),
                Par::Seq,
                MemStack::new(&mut buffer),
                Default::default(),
            )
            .unwrap();
        let largest = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let worst = one
            .iter()
            .zip(&reference)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(worst <= 1e-13 * largest, "largest difference {worst:e} of {largest:e}");
    }

    /// The solves with the factor equal faer's to rounding, bit-identical at one and two
    /// threads.
    #[test]
    fn the_solves_are_faers_and_independent_of_the_thread_count() {
        let (pattern, values) = dissected_grid(41, 40, 0.01);
        let analysis = analyse(&pattern);
        let SymbolicCholeskyRaw::Supernodal(symbolic) = analysis.raw() else {
            panic!("a supernodal analysis was forced");
        };
        let tree = SupernodeTree::new(symbolic);
        let factor = ours(1, symbolic, &pattern, &values).unwrap();
        let n = pattern.ncols();
        let rhs: Vec<f64> = (0..n).map(|i| ((i * 7919) % 101) as f64 / 50.0 - 1.0).collect();
        let solve = |threads: usize| {
            let mut x = rhs.clone();
            let mut pushed = Vec::new();
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| solve_in_place(symbolic, &tree, &factor, &mut x, &mut pushed));
            x
        };
        let (one, two) = (solve(1), solve(2));
        assert!(one.iter().zip(&two).all(|(a, b)| a.to_bits() == b.to_bits()));
        let mut reference = rhs.clone();
        let req = analysis.solve_in_place_scratch::<f64>(1, Par::Seq);
        let mut buffer = MemBuffer::new(req);
        faer::sparse::linalg::cholesky::LltRef::new(&analysis, &factor).solve_in_place_with_conj(
            faer::Conj::No,
            MatMut::from_column_major_slice_mut(&mut reference, n, 1),
            Par::Seq,
            MemStack::new(&mut buffer),
        );
        let largest = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let worst = one
            .iter()
            .zip(&reference)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(worst <= 1e-12 * largest, "largest difference {worst:e} of {largest:e}");
    }

    /// A matrix that is not positive definite fails, at any thread count.
    #[test]
    fn an_indefinite_matrix_fails() {
        let (pattern, mut values) = dissected_grid(21, 20, 0.01);
        // The middle column's first diagonal entry made negative: the pivot fails there.
        let last = pattern.ncols() - 20;
        values[pattern.col_ptr()[last]] = -1.0;
        let analysis = analyse(&pattern);
        let SymbolicCholeskyRaw::Supernodal(symbolic) = analysis.raw() else {
            panic!("a supernodal analysis was forced");
        };
        for threads in [1, 2] {
            let error = ours(threads, symbolic, &pattern, &values).unwrap_err();
            assert!(error.contains("NonPositivePivot"), "{error}");
        }
    }
}
