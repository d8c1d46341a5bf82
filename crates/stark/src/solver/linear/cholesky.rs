//! Sparse Cholesky `LLᵀ` (faer's symbolic analysis; the numeric factorisation and the solves of
//! a supernodal analysis our own, its elimination subtrees on several threads: [`supernodal`]),
//! with the symbolic analysis (ordering, elimination tree) reused
//! while the sparsity pattern is unchanged, the ordering reused within a time step when it
//! changes, the matrix gathered already permuted (faer would permute it at every factorisation),
//! and the factor's values and the workspace kept between factorisations (a fresh allocation of
//! tens of MB each time costs page faults).
//!
//! Above [`SINGLE_PRECISION_FROM_UNKNOWNS`] the factor is computed in single precision, of the
//! matrix scaled to a unit diagonal, and each solve is refined by CG in double precision on the
//! unscaled matrix with that factor as its preconditioner (to the caller's tolerance, Newton's
//! forcing term, or two or three iterations to a relative residual of
//! [`REFINE_RELATIVE_TOLERANCE`]): the factorisation and the triangular solves move half the
//! bytes. A folded towel under the robot: 10 steps 46.1 → 40.7 s, the same Newton iterations and
//! residuals (BENCHMARKS.md).
//!
//! [`CholeskySolver::prepare`] orders and analyses a new pattern ahead of the solve (Newton runs
//! it beside the assembly of the values), keeping the last factorisation usable meanwhile.

use super::block_sparse::BlockSparseMatrix;
use super::pcg;
use super::supernodal::{self, FactorScalar, FactorScratch, LowerColumns, SupernodeTree};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, LltRef, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};
use rayon::prelude::*;

/// An analysis with the step's ordering whose factor has more than this many times the entries of
/// the last one orders afresh.
const REORDER_ABOVE_FILL_GROWTH: f64 = 1.5;

/// Systems with at least this many unknowns are factorised in single precision (smaller ones
/// factorise in well under a millisecond, where the refinement would cost more than it saves).
pub const SINGLE_PRECISION_FROM_UNKNOWNS: usize = 2000;

/// The refinement of a single-precision factor's solve stops at this residual relative to the
/// right-hand side (the double-precision factor's solves reach ~1e-13; Newton's iterates agree to
/// the printed digits with either).
const REFINE_RELATIVE_TOLERANCE: f64 = 1e-10;

/// Refinement iterations after which the single-precision factor is given up for this matrix
/// and it is factorised in double precision.
const REFINE_MAX_CG: usize = 30;

/// Cached analysis of one pattern.
struct Analysis {
    pattern_id: u64,
    symbolic_matrix: SymbolicSparseColMat<usize>,
    symbolic_llt: SymbolicCholesky<usize>,
    /// For each scalar lower-triangle entry (column-major order), where to read it:
    /// `(block index, entry within the block)`.
    source: Vec<(u32, u8)>,
    /// With our own ordering the matrix is gathered already permuted (`P A Pᵀ`, so faer need
    /// not permute it at each factorisation): the old scalar index of each new one.
    forward: Option<Vec<usize>>,
    /// The supernodal elimination tree, when faer's analysis is supernodal (our own numeric
    /// factorisation then, its subtrees in parallel: [`supernodal`]).
    tree: Option<SupernodeTree>,
    /// Column boundaries splitting the lower triangle's entries into runs of about
    /// [`PARALLEL_ENTRIES`] (the per-entry passes of a factorisation run on them in parallel).
    column_runs: Vec<usize>,
}

/// Entries per parallel run of the gather and the scaling that precede a factorisation (on one
/// thread they were ~3% of the two-thread time of a folded towel under the robot).
const PARALLEL_ENTRIES: usize = 1 << 15;

/// `out` (one entry per lower-triangle entry of `an`) split at `an.column_runs`.
fn column_run_slices<'a, T>(an: &Analysis, mut out: &'a mut [T]) -> Vec<(std::ops::Range<usize>, &'a mut [T])> {
    let col_ptr = an.symbolic_matrix.col_ptr();
    an.column_runs
        .windows(2)
        .map(|w| {
            let (head, tail) = std::mem::take(&mut out).split_at_mut(col_ptr[w[1]] - col_ptr[w[0]]);
            out = tail;
            (w[0]..w[1], head)
        })
        .collect()
}

/// The fill-reducing ordering: METIS's nested dissection of the block graph, each block's three
/// unknowns kept together (`order[new] = old`, per block). `None` (faer's approximate minimum
/// degree then) if METIS fails.
///
/// A cloth's Hessian is a planar graph, layered where it folds onto itself; nested dissection
/// orders it with about half the factorisation work of minimum degree (a folded towel under the
/// robot: 4.1 instead of 8.9 G multiply-adds, 11 M instead of 17 M factor entries). METIS's seed
/// is fixed: the same pattern always gets the same ordering (bit-identical runs and resumes).
fn nested_dissection(a: &BlockSparseMatrix) -> Option<Vec<usize>> {
    use metis_sys as metis;
    let blocks = a.row_start.len() - 1;
    // The block graph without self loops, in METIS's CSR form.
    let mut xadj: Vec<metis::idx_t> = Vec::with_capacity(blocks + 1);
    let mut adjncy: Vec<metis::idx_t> = Vec::with_capacity(a.cols.len());
    xadj.push(0);
    for r in 0..blocks {
        let neighbours = a.cols[a.row_start[r]..a.row_start[r + 1]].iter();
        adjncy.extend(neighbours.filter(|&&c| c as usize != r).map(|&c| c as metis::idx_t));
        xadj.push(metis::idx_t::try_from(adjncy.len()).ok()?);
    }
    let mut vertices = metis::idx_t::try_from(blocks).ok()?;
    let mut options = [0 as metis::idx_t; metis::METIS_NOPTIONS as usize];
    let mut perm = vec![0 as metis::idx_t; blocks];
    let mut iperm = vec![0 as metis::idx_t; blocks];
    // METIS's random number generator (GKlib's) is one global state, seeded per call: two calls
    // at once on different threads (two simulations in one process, parallel tests) draw from
    // each other's sequence and order differently. One call at a time keeps orderings, and so
    // the runs, deterministic.
    static METIS: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _one_at_a_time = METIS.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    // SAFETY: the arrays have the lengths METIS_NodeND reads and writes (xadj: blocks + 1,
    // adjncy: xadj[blocks], perm and iperm: blocks, options: METIS_NOPTIONS); no vertex weights.
    let status = unsafe {
        metis::METIS_SetDefaultOptions(options.as_mut_ptr());
        options[metis::moptions_et_METIS_OPTION_NUMBERING as usize] = 0;
        metis::METIS_NodeND(
            &mut vertices,
            xadj.as_mut_ptr(),
            adjncy.as_mut_ptr(),
            std::ptr::null_mut(),
            options.as_mut_ptr(),
            perm.as_mut_ptr(),
            iperm.as_mut_ptr(),
        )
    };
    if status != metis::rstatus_et_METIS_OK {
        return None;
    }
    // METIS's perm[new] = old, per block.
    Some(perm.iter().map(|&b| b as usize).collect())
}

/// The scalar `(forward, inverse)` permutations of a block ordering (`order[new] = old`): scalar
/// unknown `3b + i` follows its block.
fn scalar_permutation(order: &[usize]) -> (Vec<usize>, Vec<usize>) {
    let forward: Vec<usize> = order.iter().flat_map(|&b| [3 * b, 3 * b + 1, 3 * b + 2]).collect();
    let mut inverse = vec![0usize; forward.len()];
    for (new, &old) in forward.iter().enumerate() {
        inverse[old] = new;
    }
    (forward, inverse)
}

/// The upper triangle's pattern (CSC, sorted rows) of a symmetric matrix given by its lower one.
fn upper_pattern(lower: &SymbolicSparseColMat<usize>) -> SymbolicSparseColMat<usize> {
    let n = lower.ncols();
    let (col_ptr, row_idx) = (lower.col_ptr(), lower.row_idx());
    // Entry (i, j), i ≥ j, of the lower triangle is entry (j, i) of the upper one: column i.
    let mut count = vec![0usize; n + 1];
    for &i in row_idx {
        count[i + 1] += 1;
    }
    for k in 0..n {
        count[k + 1] += count[k];
    }
    let mut next = count.clone();
    let mut rows = vec![0usize; row_idx.len()];
    // Columns j in increasing order: each upper column receives its rows sorted.
    for j in 0..n {
        for &i in &row_idx[col_ptr[j]..col_ptr[j + 1]] {
            rows[next[i]] = j;
            next[i] += 1;
        }
    }
    SymbolicSparseColMat::new_checked(n, n, count, None, rows)
}

/// A direct solver that re-analyses only when the block pattern changes.
#[derive(Default)]
pub struct CholeskySolver {
    /// The analysis of the last factorisation (the reuses' preconditioner reads it).
    analysis: Option<Analysis>,
    /// An analysis made ahead of the next factorisation ([`CholeskySolver::prepare`]).
    pending: Option<Analysis>,
    values: Vec<f64>,
    /// The factor's values.
    factor: Vec<f64>,
    /// A permuted right-hand side.
    scratch: Vec<f64>,
    /// The solve's values passed up the elimination tree ([`supernodal::solve_in_place`]).
    pushed: Vec<f64>,
    /// The factorisation's per-task scratch.
    factor_scratch: FactorScratch<f64>,
    /// Workspace of the factorisation and the solve, the parallelism it was sized for and its
    /// size in bytes (kept across analyses while large enough: a fresh allocation of tens of MB
    /// costs page faults).
    workspace: Option<(MemBuffer, Par, usize)>,
    /// The last nested-dissection ordering (per block), reused by the analyses of changed
    /// patterns until [`CholeskySolver::fresh_ordering_next`] asks for a new one.
    ordering: Option<Vec<usize>>,
    /// The `pattern_id` of the block pattern `ordering` was made from (the assembler gives an
    /// unchanged pattern its id again, and a changed one a new id).
    ordering_pattern_id: Option<u64>,
    /// The next analysis computes a fresh ordering. Set at each time step's start: within a
    /// step the pattern changes only by the contact pairs that appear and vanish, and the
    /// step's first ordering stays nearly as good (METIS is two thirds of an analysis), while
    /// a run resumed at a step makes the same orderings.
    pub fresh_ordering_next: bool,
    /// Number of symbolic analyses performed (for logs and tests).
    pub analyses: usize,
    /// Number of them that computed a fresh ordering.
    pub fresh_orderings: usize,
    /// `factor` holds a complete factorisation of the current analysis.
    factored: bool,
    /// The single-precision factor (large systems).
    single: SingleFactor,
    /// Factorisations in double precision after the single-precision one failed on a matrix
    /// expected to be positive definite, or its refinement did not converge (for logs and tests).
    pub single_precision_fallbacks: usize,
    /// CG iterations of the last solve's refinement (0: solved with a double-precision factor).
    pub refine_iterations: usize,
}

/// A single-precision factor: `S P A Pᵀ S = L Lᵀ`, `S` the inverse square roots of the
/// diagonal of `P A Pᵀ` (the scaling keeps the entries of stiff contacts and light nodes, 1e9
/// apart in a folded towel under the robot, within `f32`'s range and its pivots well scaled).
#[derive(Default)]
struct SingleFactor {
    /// `S`, per unknown of the analysis' order.
    scale: Vec<f64>,
    values: Vec<f32>,
    factor: Vec<f32>,
    /// A scaled, permuted right-hand side.
    rhs: Vec<f32>,
    /// The solve's values passed up the elimination tree.
    pushed: Vec<f32>,
    factor_scratch: FactorScratch<f32>,
    workspace: Option<(MemBuffer, Par, usize)>,
    /// `factor` is a complete factorisation of the current analysis (and `CholeskySolver::factor`
    /// is not).
    factored: bool,
}

/// A workspace of at least `req` for parallelism `par`, reusing the one in `slot` if it fits.
fn workspace(
    slot: &mut Option<(MemBuffer, Par, usize)>,
    req: StackReq,
    par: Par,
) -> Result<&mut MemBuffer, CholeskyError> {
    let fits = |w: &(MemBuffer, Par, usize)| w.1 == par && w.2 >= req.size_bytes();
    if !slot.as_ref().is_some_and(fits) {
        let buffer = MemBuffer::try_new(req).map_err(|e| CholeskyError::Analysis(format!("workspace: {e:?}")))?;
        *slot = Some((buffer, par, req.size_bytes()));
    }
    Ok(&mut slot.as_mut().expect("workspace present").0)
}

/// Why a factorisation failed.
#[derive(Debug, thiserror::Error)]
pub enum CholeskyError {
    /// The matrix is not positive definite.
    #[error("sparse Cholesky factorisation failed: the Hessian is not positive definite ({0})")]
    NotPositiveDefinite(String),
    /// The symbolic analysis failed.
    #[error("sparse Cholesky analysis failed: {0}")]
    Analysis(String),
}

impl CholeskySolver {
    /// Order `a`'s pattern (`pattern_id`) by nested dissection.
    fn order(&mut self, a: &BlockSparseMatrix, pattern_id: u64) {
        self.ordering = nested_dissection(a);
        self.ordering_pattern_id = Some(pattern_id);
    }

    fn analyse(a: &BlockSparseMatrix, pattern_id: u64, order: Option<&[usize]>) -> Result<Analysis, CholeskyError> {
        let n = a.dim();
        let blocks = a.row_start.len() - 1;
        // The new block of each old one (the identity without an ordering of our own).
        let mut new_of_old: Vec<usize> = (0..blocks).collect();
        if let Some(order) = order {
            for (new, &old) in order.iter().enumerate() {
                new_of_old[old] = new;
            }
        }
        // Lower triangle of `P A Pᵀ` in CSC: new column j (scalar) of new block column bj holds
        // rows i ≥ j. By symmetry its entries are row j of the upper part: the old block row
        // bc = order[bj] with its neighbours br, taken transposed.
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        let mut source = Vec::new();
        // Per block column: its neighbours at or below it, sorted once for its three columns.
        let mut neighbours: Vec<(usize, u32)> = Vec::new();
        col_ptr.push(0usize);
        for bj in 0..blocks {
            let bc = order.map_or(bj, |o| o[bj]);
            neighbours.clear();
            neighbours.extend(
                (a.row_start[bc]..a.row_start[bc + 1])
                    .map(|idx| (new_of_old[a.cols[idx] as usize], idx as u32))
                    .filter(|&(brn, _)| brn >= bj),
            );
            neighbours.sort_unstable_by_key(|e| e.0);
            for jj in 0..3 {
                let j = 3 * bj + jj;
                for &(brn, idx) in &neighbours {
                    for ii in 0..3 {
                        let i = 3 * brn + ii;
                        if i >= j {
                            // Entry (i, j) = entry (j, i) of old block (bc, br): row jj, column ii.
                            row_idx.push(i);
                            source.push((idx, (3 * jj + ii) as u8));
                        }
                    }
                }
                col_ptr.push(row_idx.len());
            }
        }
        let mut column_runs = vec![0];
        for j in 1..=n {
            if j == n || col_ptr[j] - col_ptr[*column_runs.last().expect("nonempty")] >= PARALLEL_ENTRIES {
                column_runs.push(j);
            }
        }
        let symbolic_matrix = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let symbolic_llt = match order {
            // faer's analysis without an ordering reads the upper triangle whatever the side
            // (its numeric factorisation takes the lower one as it is).
            Some(_) => factorize_symbolic_cholesky(
                upper_pattern(&symbolic_matrix).as_ref(),
                Side::Upper,
                SymmetricOrdering::Identity,
                Default::default(),
            ),
            None => factorize_symbolic_cholesky(
                symbolic_matrix.as_ref(),
                Side::Lower,
                SymmetricOrdering::Amd,
                Default::default(),
            ),
        }
        .map_err(|e| CholeskyError::Analysis(format!("{e:?}")))?;
        let tree = match (symbolic_llt.raw(), symbolic_llt.perm()) {
            (SymbolicCholeskyRaw::Supernodal(supernodal), None) => Some(SupernodeTree::new(supernodal)),
            _ => None,
        };
        Ok(Analysis {
            tree,
            pattern_id,
            symbolic_matrix,
            symbolic_llt,
            source,
            forward: order.map(|o| scalar_permutation(o).0),
            column_runs,
        })
    }

    /// Solve with the last factor in place: `z ← (P A Pᵀ)⁻¹`-permuted, i.e. `A⁻¹ z` in the
    /// caller's unknowns.
    fn solve_with_factor(
        an: &Analysis,
        factor: &[f64],
        z: &mut [f64],
        scratch: &mut Vec<f64>,
        pushed: &mut Vec<f64>,
        par: Par,
        buffer: &mut MemBuffer,
    ) {
        match &an.forward {
            Some(forward) => {
                scratch.clear();
                scratch.extend(forward.iter().map(|&old| z[old]));
                solve_factor(an, factor, scratch, pushed, par, buffer);
                for (&old, &y) in forward.iter().zip(scratch.iter()) {
                    z[old] = y;
                }
            }
            None => solve_factor(an, factor, z, pushed, par, buffer),
        }
    }

    /// The last factorisation's `(L Lᵀ)⁻¹ r` into `z`, for a matrix near the one factorised (a
    /// preconditioner for the next Newton iterations). False when there is no factor of this size.
    pub fn apply_last_factor(&mut self, r: &[f64], z: &mut [f64]) -> bool {
        let Some(an) = self.analysis.as_ref() else {
            return false;
        };
        if an.symbolic_llt.nrows() != r.len() {
            return false;
        }
        if self.single.factored {
            self.single.apply(an, r, z);
            return true;
        }
        let Some((buffer, par, _)) = self.workspace.as_mut() else {
            return false;
        };
        if !self.factored {
            return false;
        }
        z.copy_from_slice(r);
        Self::solve_with_factor(an, &self.factor, z, &mut self.scratch, &mut self.pushed, *par, buffer);
        true
    }

    /// Entries of the current analysis' factor `L` (0 before the first analysis).
    pub fn factor_len(&self) -> usize {
        self.analysis.as_ref().map_or(0, |an| an.symbolic_llt.len_val())
    }

    /// Whether the next solve with a matrix of pattern `pattern_id` orders or analyses first
    /// (then [`CholeskySolver::prepare`] can run beside the assembly of its values).
    pub fn needs_analysis(&self, pattern_id: u64) -> bool {
        self.fresh_ordering_next || !self.has_analysis(pattern_id)
    }

    /// An analysis of pattern `pattern_id` is at hand (the last factorisation's or a pending one).
    fn has_analysis(&self, pattern_id: u64) -> bool {
        [&self.analysis, &self.pending]
            .iter()
            .any(|an| an.as_ref().is_some_and(|an| an.pattern_id == pattern_id))
    }

    /// The ordering and symbolic analysis of `a`'s pattern (`pattern_id`; `a`'s values are not
    /// read), unless one is at hand: what [`CholeskySolver::solve`] does first. The last
    /// factorisation and its analysis stay usable ([`CholeskySolver::apply_last_factor`]).
    pub fn prepare(&mut self, a: &BlockSparseMatrix, pattern_id: u64) -> Result<(), CholeskyError> {
        // A step's first solve orders its pattern afresh, unless the ordering was made from this
        // very pattern (METIS's result is a function of the pattern: the same ordering, and the
        // same analysis if it was made with it, at no cost; a settled scene's contacts keep
        // their pattern from step to step).
        let mut fresh = false;
        if std::mem::take(&mut self.fresh_ordering_next) && self.ordering_pattern_id != Some(pattern_id) {
            self.order(a, pattern_id);
            fresh = true;
        }
        if fresh || !self.has_analysis(pattern_id) {
            let blocks = a.row_start.len() - 1;
            if !fresh && self.ordering.as_ref().is_none_or(|o| o.len() != blocks) {
                self.order(a, pattern_id);
                fresh = true;
            }
            let previous_len = self.factor_len();
            let mut analysis = Self::analyse(a, pattern_id, self.ordering.as_deref())?;
            if !fresh && analysis.symbolic_llt.len_val() as f64 > REORDER_ABOVE_FILL_GROWTH * previous_len as f64 {
                // The new couplings do not fit the old ordering (an obstacle's nodes that now
                // touch a whole cloth, ordered early, fill everything in): order afresh.
                self.order(a, pattern_id);
                analysis = Self::analyse(a, pattern_id, self.ordering.as_deref())?;
                fresh = true;
            }
            self.pending = Some(analysis);
            self.analyses += 1;
            self.fresh_orderings += usize::from(fresh);
        }
        Ok(())
    }

    /// Solve `A x = b`. `pattern_id` identifies the sparsity pattern of `a`: the analysis is
    /// redone only when it changes. `definite`: the matrix is expected to be positive definite
    /// (its terms' definite or projected forms); a single-precision factorisation that fails then
    /// is repeated in double precision, while otherwise its failure is reported at once (the
    /// caller's next attempt is with definite forms). `tolerance`: the residual norm `‖b − A x‖`
    /// at which the refinement of a single-precision solve may stop (0: to
    /// [`REFINE_RELATIVE_TOLERANCE`] of `‖b‖`, as a double-precision factor solves).
    pub fn solve(
        &mut self,
        a: &BlockSparseMatrix,
        pattern_id: u64,
        b: &[f64],
        x: &mut [f64],
        definite: bool,
        tolerance: f64,
    ) -> Result<(), CholeskyError> {
        // The thread pool the solve runs in (one thread: no parallel overhead at all).
        let par = match rayon::current_num_threads() {
            1 => Par::Seq,
            n => Par::rayon(n),
        };
        self.factored = false;
        self.single.factored = false;
        self.refine_iterations = 0;
        self.prepare(a, pattern_id)?;
        if self.pending.as_ref().is_some_and(|an| an.pattern_id == pattern_id) {
            self.analysis = self.pending.take();
        }
        let an = self.analysis.as_ref().expect("analysis present");
        debug_assert_eq!(an.pattern_id, pattern_id);
        // The gather in parallel runs (a random read per entry).
        self.values.resize(an.source.len(), 0.0);
        self.values
            .par_chunks_mut(PARALLEL_ENTRIES)
            .zip(an.source.par_chunks(PARALLEL_ENTRIES))
            .for_each(|(out, source)| {
                for (v, &(blk, e)) in out.iter_mut().zip(source) {
                    *v = a.values[blk as usize][e as usize];
                }
            });
        if b.len() >= SINGLE_PRECISION_FROM_UNKNOWNS {
            match self.single.factorise(an, &self.values, par) {
                Ok(()) => {
                    let b_norm = b.iter().map(|v| v * v).sum::<f64>().sqrt();
                    let single = &mut self.single;
                    let info = pcg::solve_preconditioned(
                        a,
                        b,
                        x,
                        tolerance.max(REFINE_RELATIVE_TOLERANCE * b_norm),
                        REFINE_MAX_CG,
                        &mut |r, z| single.apply(an, r, z),
                    );
                    self.refine_iterations = info.iterations;
                    if info.converged {
                        return Ok(());
                    }
                    self.single.factored = false;
                    if info.indefinite && !definite {
                        return Err(CholeskyError::NotPositiveDefinite(
                            "negative curvature in the refinement of the single-precision solve".into(),
                        ));
                    }
                }
                // An exact Hessian that is not positive definite fails in either precision.
                Err(e) if !definite => return Err(e),
                Err(_) => {}
            }
            self.single_precision_fallbacks += 1;
        }
        let buffer = factorise_numeric(
            an,
            &self.values,
            &mut self.factor,
            &mut self.factor_scratch,
            &mut self.workspace,
            par,
        )
        .map_err(CholeskyError::NotPositiveDefinite)?;
        self.factored = true;
        x.copy_from_slice(b);
        Self::solve_with_factor(an, &self.factor, x, &mut self.scratch, &mut self.pushed, par, buffer);
        Ok(())
    }
}

/// `x ← (L Lᵀ)⁻¹ x` with `an`'s factor (in the analysis' order).
fn solve_factor<T: FactorScalar + std::ops::Mul<Output = T> + std::ops::Div<Output = T>>(
    an: &Analysis,
    factor: &[T],
    x: &mut [T],
    pushed: &mut Vec<T>,
    par: Par,
    buffer: &mut MemBuffer,
) {
    if let (Some(tree), SymbolicCholeskyRaw::Supernodal(supernodal)) = (&an.tree, an.symbolic_llt.raw()) {
        supernodal::solve_in_place(supernodal, tree, factor, x, pushed);
        return;
    }
    let n = x.len();
    LltRef::new(&an.symbolic_llt, factor).solve_in_place_with_conj(
        Conj::No,
        MatMut::from_column_major_slice_mut(x, n, 1),
        par,
        MemStack::new(buffer),
    );
}

/// The numeric factorisation `L Lᵀ` of `values` (the lower triangle in `an`'s pattern) into
/// `factor`, in `T`'s precision, with the workspace in `slot` (sized for the solves too).
fn factorise_numeric<'w, T: FactorScalar>(
    an: &Analysis,
    values: &[T],
    factor: &mut Vec<T>,
    scratch: &mut FactorScratch<T>,
    slot: &'w mut Option<(MemBuffer, Par, usize)>,
    par: Par,
) -> Result<&'w mut MemBuffer, String> {
    let symbolic = &an.symbolic_llt;
    // Our supernodal factorisation and solves need no workspace of faer's (whose size is a pass
    // over the supernodes: ~1 ms of serial work at each factorisation of a folded towel).
    let req = if an.tree.is_some() {
        StackReq::EMPTY
    } else {
        StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<T>(par, Default::default()),
            symbolic.solve_in_place_scratch::<T>(1, par),
        ])
    };
    let buffer = workspace(slot, req, par).map_err(|e| e.to_string())?;
    factor.resize(symbolic.len_val(), T::default());
    if let (Some(tree), SymbolicCholeskyRaw::Supernodal(supernodal)) = (&an.tree, symbolic.raw()) {
        let m = &an.symbolic_matrix;
        let lower = LowerColumns {
            col_ptr: m.col_ptr(),
            row_idx: m.row_idx(),
            values,
        };
        supernodal::factorize(supernodal, tree, &lower, factor, scratch)?;
        return Ok(buffer);
    }
    symbolic
        .factorize_numeric_llt(
            factor,
            SparseColMatRef::new(an.symbolic_matrix.as_ref(), values),
            Side::Lower,
            Default::default(),
            par,
            MemStack::new(buffer),
            Default::default(),
        )
        .map_err(|e| format!("{e:?}"))?;
    Ok(buffer)
}

impl SingleFactor {
    /// Scale `values` (the lower triangle of `P A Pᵀ`, `an`'s pattern) to a unit diagonal and
    /// factorise in single precision.
    fn factorise(&mut self, an: &Analysis, values: &[f64], par: Par) -> Result<(), CholeskyError> {
        self.factored = false;
        let m = &an.symbolic_matrix;
        let (col_ptr, row_idx) = (m.col_ptr(), m.row_idx());
        let n = m.ncols();
        self.scale.clear();
        for j in 0..n {
            // Rows are sorted and at or below the diagonal: a column starts with its diagonal.
            let k = col_ptr[j];
            let d = if k < col_ptr[j + 1] && row_idx[k] == j {
                values[k]
            } else {
                0.0
            };
            if !(d > 0.0 && d.is_finite()) {
                return Err(CholeskyError::NotPositiveDefinite(format!("diagonal entry {j} is {d}")));
            }
            self.scale.push(1.0 / d.sqrt());
        }
        self.values.resize(values.len(), 0.0);
        let scale = &self.scale;
        column_run_slices(an, &mut self.values)
            .into_par_iter()
            .for_each(|(columns, out)| {
                let base = col_ptr[columns.start];
                for j in columns {
                    let sj = scale[j];
                    for k in col_ptr[j]..col_ptr[j + 1] {
                        out[k - base] = (values[k] * scale[row_idx[k]] * sj) as f32;
                    }
                }
            });
        factorise_numeric(
            an,
            &self.values,
            &mut self.factor,
            &mut self.factor_scratch,
            &mut self.workspace,
            par,
        )
        .map_err(|e| CholeskyError::NotPositiveDefinite(format!("single precision: {e}")))?;
        self.factored = true;
        Ok(())
    }

    /// `z ≈ A⁻¹ r` with the factor (`z = S (L Lᵀ)⁻¹ S r` in the analysis' order).
    fn apply(&mut self, an: &Analysis, r: &[f64], z: &mut [f64]) {
        self.rhs.clear();
        match &an.forward {
            Some(forward) => self
                .rhs
                .extend(forward.iter().zip(&self.scale).map(|(&old, s)| (r[old] * s) as f32)),
            None => self.rhs.extend(r.iter().zip(&self.scale).map(|(v, s)| (v * s) as f32)),
        }
        let (buffer, par, _) = self.workspace.as_mut().expect("workspace of the factorisation");
        solve_factor(an, &self.factor, &mut self.rhs, &mut self.pushed, *par, buffer);
        match &an.forward {
            Some(forward) => {
                for ((&old, &y), s) in forward.iter().zip(&self.rhs).zip(&self.scale) {
                    z[old] = f64::from(y) * s;
                }
            }
            None => {
                for ((z, &y), s) in z.iter_mut().zip(&self.rhs).zip(&self.scale) {
                    *z = f64::from(y) * s;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_and_reuses_analysis() {
        let pairs = vec![(0, 0), (0, 1), (1, 0), (1, 1), (1, 2), (2, 1), (2, 2)];
        let mut a = BlockSparseMatrix::from_sorted_pairs(3, &pairs);
        let mut solver = CholeskySolver::default();
        for round in 0..2 {
            for r in 0..3 {
                for idx in a.row_start[r]..a.row_start[r + 1] {
                    let c = a.cols[idx] as usize;
                    let mut blk = [0.0; 9];
                    for i in 0..3 {
                        for j in 0..3 {
                            blk[3 * i + j] = if r == c {
                                if i == j {
                                    4.0 + round as f64
                                } else {
                                    0.3
                                }
                            } else {
                                -0.5 - 0.1 * ((i + j) as f64) + 0.0 * (r + c) as f64
                            };
                        }
                    }
                    a.values[idx] = blk;
                }
            }
            // Make the off-diagonal blocks mutually transposed (symmetric matrix).
            let b: Vec<f64> = (0..9).map(|i| i as f64 - 3.0).collect();
            let mut x = vec![0.0; 9];
            solver.solve(&a, 7, &b, &mut x, true, 0.0).unwrap();
            let mut ax = vec![0.0; 9];
            a.mul_vec(&x, &mut ax);
            for i in 0..9 {
                assert!((ax[i] - b[i]).abs() < 1e-10, "{ax:?} vs {b:?}");
            }
        }
        assert_eq!(solver.analyses, 1);
    }

    /// A `side × side` grid of nodes with the 9-point stencil, `hubs` more nodes after them, and
    /// `extra` couplings (contact pairs), symmetric and diagonally dominant.
    fn grid_matrix(side: usize, hubs: usize, extra: &[(u32, u32)]) -> BlockSparseMatrix {
        let node = |i: usize, j: usize| (i * side + j) as u32;
        let mut pairs = Vec::new();
        for i in 0..side {
            for j in 0..side {
                for di in -1i64..=1 {
                    for dj in -1i64..=1 {
                        let (k, l) = (i as i64 + di, j as i64 + dj);
                        if (0..side as i64).contains(&k) && (0..side as i64).contains(&l) {
                            pairs.push((node(i, j), node(k as usize, l as usize)));
                        }
                    }
                }
            }
        }
        pairs.extend(extra.iter().flat_map(|&(a, b)| [(a, b), (b, a)]));
        pairs.sort();
        pairs.dedup();
        let n_blocks = side * side + hubs;
        pairs.extend((side * side..n_blocks).map(|h| (h as u32, h as u32)));
        pairs.sort();
        let mut a = BlockSparseMatrix::from_sorted_pairs(n_blocks, &pairs);
        for r in 0..n_blocks {
            // Each neighbour block adds 1 to a row's off-diagonal absolute sum.
            let d = (a.row_start[r + 1] - a.row_start[r]) as f64;
            for idx in a.row_start[r]..a.row_start[r + 1] {
                a.values[idx] = if a.cols[idx] as usize == r {
                    [d, 0.0, 0.0, 0.0, d, 0.0, 0.0, 0.0, d]
                } else {
                    [-1.0 / 3.0; 9]
                };
            }
        }
        a
    }

    fn solves_exactly(solver: &mut CholeskySolver, a: &BlockSparseMatrix, pattern_id: u64) -> bool {
        let b: Vec<f64> = (0..a.dim()).map(|i| (i % 7) as f64 - 3.0).collect();
        let mut x = vec![0.0; b.len()];
        solver.solve(a, pattern_id, &b, &mut x, true, 0.0).unwrap();
        let mut ax = vec![0.0; b.len()];
        a.mul_vec(&x, &mut ax);
        ax.iter().zip(&b).all(|(p, q)| (p - q).abs() < 1e-10)
    }

    /// Within a time step a changed pattern (contact pairs that appear) is analysed again with
    /// the step's ordering; the next step's first analysis orders afresh. Either way the
    /// factorisation solves the system.
    #[test]
    fn a_changed_pattern_reuses_the_steps_ordering() {
        let side = 20;
        let flat = grid_matrix(side, 0, &[]);
        // A small fold: the first row of nodes now touches the third.
        let third = (2 * side) as u32;
        let folded = grid_matrix(side, 0, &(0..side as u32).map(|j| (j, third + j)).collect::<Vec<_>>());
        let mut solver = CholeskySolver {
            fresh_ordering_next: true,
            ..Default::default()
        };
        assert!(solves_exactly(&mut solver, &flat, 1));
        let flat_order = nested_dissection(&flat).unwrap();
        assert_eq!(solver.ordering.as_ref(), Some(&flat_order));
        assert!(solves_exactly(&mut solver, &folded, 2));
        assert_eq!(solver.analyses, 2);
        assert_eq!(
            solver.ordering.as_ref(),
            Some(&flat_order),
            "the step's ordering is kept"
        );
        solver.fresh_ordering_next = true;
        assert!(solves_exactly(&mut solver, &folded, 3));
        let folded_order = nested_dissection(&folded).unwrap();
        assert_ne!(folded_order, flat_order);
        assert_eq!(
            solver.ordering.as_ref(),
            Some(&folded_order),
            "a new step orders afresh"
        );
        // A step that starts with the pattern its ordering was made from keeps both the
        // ordering and the analysis (they are what ordering afresh would make).
        let (analyses, fresh) = (solver.analyses, solver.fresh_orderings);
        solver.fresh_ordering_next = true;
        assert!(solves_exactly(&mut solver, &folded, 3));
        assert_eq!((solver.analyses, solver.fresh_orderings), (analyses, fresh));
        // A step that starts with the pattern the last one ended with (still analysed with the
        // ordering of that step's start) orders it afresh, as a run resumed at this step would:
        // the orderings, and so the rounding, do not depend on where a run was resumed.
        solver.fresh_ordering_next = true;
        assert!(solves_exactly(&mut solver, &flat, 4));
        assert!(solves_exactly(&mut solver, &folded, 5));
        assert_eq!(solver.ordering.as_ref(), Some(&flat_order));
        solver.fresh_ordering_next = true;
        assert!(solves_exactly(&mut solver, &folded, 5));
        assert_eq!(solver.ordering.as_ref(), Some(&folded_order));
        let mut resumed = CholeskySolver {
            fresh_ordering_next: true,
            ..Default::default()
        };
        assert!(solves_exactly(&mut resumed, &folded, 1));
        assert_eq!(resumed.factor, solver.factor, "the same factor, bit for bit");
    }

    /// An analysis made ahead of a solve (beside the assembly of the values) leaves the last
    /// factorisation usable as a preconditioner, and the solve that uses it computes the same
    /// bits as one that analysed the pattern itself.
    #[test]
    fn an_analysis_made_ahead_keeps_the_last_factor_and_gives_the_same_solve() {
        let side = 20;
        let flat = grid_matrix(side, 0, &[]);
        let fold = |row: usize| {
            let other = (row * side) as u32;
            grid_matrix(side, 0, &(0..side as u32).map(|j| (j, other + j)).collect::<Vec<_>>())
        };
        let (folded, folded_more) = (fold(2), fold(3));
        let b: Vec<f64> = (0..flat.dim()).map(|i| ((i * 29) % 13) as f64 - 6.0).collect();
        let solve = |solver: &mut CholeskySolver, a: &BlockSparseMatrix, id: u64| {
            let mut x = vec![0.0; b.len()];
            solver.solve(a, id, &b, &mut x, true, 0.0).unwrap();
            x
        };
        let fresh = || CholeskySolver {
            fresh_ordering_next: true,
            ..Default::default()
        };
        let mut ahead = fresh();
        solve(&mut ahead, &flat, 1);
        let mut before = vec![0.0; b.len()];
        assert!(ahead.apply_last_factor(&b, &mut before));
        // A trial's pattern analysed and not solved, then the pattern solved next.
        assert!(ahead.needs_analysis(3));
        ahead.prepare(&folded_more.pattern_only(), 3).unwrap();
        assert!(!ahead.needs_analysis(3));
        ahead.prepare(&folded.pattern_only(), 2).unwrap();
        assert!(!ahead.needs_analysis(2));
        let mut after = vec![0.0; b.len()];
        assert!(ahead.apply_last_factor(&b, &mut after));
        assert_eq!(before, after, "the last factor is the flat pattern's still");
        let x_ahead = solve(&mut ahead, &folded, 2);
        assert_eq!(ahead.analyses, 3, "the prepared analysis serves the solve");
        let mut direct = fresh();
        solve(&mut direct, &flat, 1);
        let x_direct = solve(&mut direct, &folded, 2);
        assert_eq!(x_ahead, x_direct, "the same solution, bit for bit");
    }

    /// An obstacle's node that was on its own and now touches the whole cloth: with the step's
    /// ordering (which put it first) the factor would be dense; the analysis sees the fill grow
    /// and orders afresh.
    #[test]
    fn an_ordering_that_no_longer_fits_is_replaced() {
        let side = 20;
        let hub = (side * side) as u32;
        let apart = grid_matrix(side, 1, &[]);
        let touching = grid_matrix(side, 1, &(0..hub).map(|i| (i, hub)).collect::<Vec<_>>());
        let mut solver = CholeskySolver {
            fresh_ordering_next: true,
            ..Default::default()
        };
        assert!(solves_exactly(&mut solver, &apart, 1));
        let apart_len = solver.factor_len();
        // The hub first: any ordering of the separate node is as good while it is separate.
        solver.ordering = Some(std::iter::once(hub as usize).chain(0..hub as usize).collect());
        assert!(solves_exactly(&mut solver, &touching, 2));
        assert_eq!((solver.analyses, solver.fresh_orderings), (2, 2));
        assert!(
            (solver.factor_len() as f64) < 1.5 * apart_len as f64,
            "{} factor entries against {apart_len} apart",
            solver.factor_len()
        );
    }

    /// A cloth-like pattern (a 40 × 40 grid of nodes, 9-point stencil): nested dissection is a
    /// permutation that keeps each block's unknowns together, fills in less than minimum degree,
    /// and the factorisation solves the system.
    #[test]
    fn nested_dissection_orders_a_grid_with_less_fill() {
        let side = 40;
        let n_blocks = side * side;
        let a = grid_matrix(side, 0, &[]);
        let order = nested_dissection(&a).expect("METIS orders the grid");
        let (forward, inverse) = scalar_permutation(&order);
        let mut seen = vec![false; 3 * n_blocks];
        for (new, &old) in forward.iter().enumerate() {
            assert!(!seen[old]);
            seen[old] = true;
            assert_eq!(inverse[old], new);
            assert_eq!(old % 3, new % 3, "a block's unknowns stay together, in order");
        }
        let mut solver = CholeskySolver::default();
        assert!(solves_exactly(&mut solver, &a, 1));
        let an = solver.analysis.as_ref().unwrap();
        let amd = factorize_symbolic_cholesky(
            an.symbolic_matrix.as_ref(),
            Side::Lower,
            SymmetricOrdering::Amd,
            Default::default(),
        )
        .unwrap();
        assert!(
            solver.factor_len() < amd.len_val(),
            "nested dissection {} factor entries, minimum degree {}",
            solver.factor_len(),
            amd.len_val()
        );
    }

    /// `‖A x − b‖ / ‖b‖`.
    fn relative_residual(a: &BlockSparseMatrix, x: &[f64], b: &[f64]) -> f64 {
        let mut ax = vec![0.0; x.len()];
        a.mul_vec(x, &mut ax);
        let r: f64 = ax.iter().zip(b).map(|(p, q)| (p - q) * (p - q)).sum::<f64>().sqrt();
        r / b.iter().map(|v| v * v).sum::<f64>().sqrt()
    }

    /// Large systems factorise in single precision and refine to the double-precision tolerance;
    /// the factor serves as a preconditioner afterwards (`apply_last_factor`).
    #[test]
    fn single_precision_factor_refines_to_the_tolerance() {
        let a = grid_matrix(30, 0, &[]);
        assert!(a.dim() >= SINGLE_PRECISION_FROM_UNKNOWNS);
        let b: Vec<f64> = (0..a.dim()).map(|i| ((i * 29) % 13) as f64 - 6.0).collect();
        let mut x = vec![0.0; a.dim()];
        let mut solver = CholeskySolver::default();
        solver.solve(&a, 1, &b, &mut x, false, 0.0).unwrap();
        assert!(solver.single.factored && !solver.factored);
        assert!(
            (1..=REFINE_MAX_CG).contains(&solver.refine_iterations),
            "{}",
            solver.refine_iterations
        );
        assert!(relative_residual(&a, &x, &b) <= REFINE_RELATIVE_TOLERANCE);
        // The factor alone: single-precision accuracy.
        let mut z = vec![0.0; a.dim()];
        assert!(solver.apply_last_factor(&b, &mut z));
        let e = relative_residual(&a, &z, &b);
        assert!(e < 1e-4 && e > 1e-12, "{e}");
        assert_eq!(solver.single_precision_fallbacks, 0);
    }

    /// An indefinite matrix fails at once in single precision when definite forms are not
    /// expected, and in double precision too when they are.
    #[test]
    fn an_indefinite_matrix_fails_in_either_precision() {
        let mut a = grid_matrix(30, 0, &[]);
        let d = a.diagonal[100];
        a.values[d][4] = -3.0;
        let b = vec![1.0; a.dim()];
        let mut x = vec![0.0; a.dim()];
        let mut solver = CholeskySolver::default();
        assert!(solver.solve(&a, 1, &b, &mut x, false, 0.0).is_err());
        assert_eq!(solver.single_precision_fallbacks, 0);
        assert!(solver.solve(&a, 1, &b, &mut x, true, 0.0).is_err());
        assert_eq!(solver.single_precision_fallbacks, 1);
        assert!(!solver.apply_last_factor(&b, &mut x));
    }

    /// A positive definite matrix too ill-conditioned for single precision (pairs of unknowns
    /// coupled 1 − 1e-10 apart, like two nodes under a stiff contact) is factorised in double
    /// precision when definite forms are expected.
    #[test]
    fn an_ill_conditioned_matrix_falls_back_to_double_precision() {
        let mut a = grid_matrix(30, 0, &[]);
        for r in 0..a.n_blocks {
            for idx in a.row_start[r]..a.row_start[r + 1] {
                let c = a.cols[idx] as usize;
                a.values[idx] = if c == r {
                    [1.0, -(1.0 - 1e-10), 0.0, -(1.0 - 1e-10), 1.0, 0.0, 0.0, 0.0, 1.0]
                } else {
                    [0.0; 9]
                };
            }
        }
        let b: Vec<f64> = (0..a.dim()).map(|i| (i % 5) as f64).collect();
        let mut x = vec![0.0; a.dim()];
        let mut solver = CholeskySolver::default();
        solver.solve(&a, 1, &b, &mut x, true, 0.0).unwrap();
        assert_eq!(solver.single_precision_fallbacks, 1);
        assert!(solver.factored && !solver.single.factored);
        assert!(
            relative_residual(&a, &x, &b) < 1e-8,
            "{}",
            relative_residual(&a, &x, &b)
        );
    }
}
