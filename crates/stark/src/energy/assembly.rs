//! Assembly of the global gradient and block-sparse Hessian from element contributions.
//!
//! Chunks of consecutive elements are coloured so that no two chunks of one colour share a DOF
//! block. Each colour is
//! evaluated in parallel and every element adds its gradient and Hessian blocks straight into the
//! global arrays: within a colour the writes are disjoint, and across colours the order is fixed,
//! so every entry is summed in the same order whatever the thread count (deterministic results).
//! Only the upper block triangle is accumulated; the lower one is its transpose. The pattern,
//! slot maps and colours are rebuilt only when a term's topology changes.
//!
//! Terms write their stencils in DOF blocks; the assembly maps them to the unknowns
//! ([`DofMap`]), so the gradient and matrix are over the unknowns only.

use super::block_sparse::BlockSparseMatrix;
use super::term::{element_stride, EnergyTerm, EvalMode, NO_DOF};
use crate::state::{DofMap, EvalState, FIXED_NODE};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

static NEXT_PATTERN_ID: AtomicU64 = AtomicU64::new(1);

/// Identity of the current layout: per term (version, elements, width), and the block count.
type LayoutKey = (Vec<(u64, usize, usize)>, usize);

/// No matrix slot (padding, or a block of the lower triangle).
const NO_SLOT: u32 = u32::MAX;

/// A pattern that needs to grow keeps its old blocks while it has fewer than this factor times
/// the blocks in use.
const STICKY_PATTERN_GROWTH: f64 = 1.2;

/// Colours of a greedy colouring; chunks that would need more go to a serial group.
const MAX_COLORS: usize = 64;

/// Colours with fewer chunks than this go to the serial group: contact pairs on rigid bodies
/// share the bodies' blocks, and their chunks spread over dozens of colours of one or two chunks,
/// each a parallel loop that one thread runs while the other waits (boxes_on_cloth at two
/// threads: evaluation 2.62 → 2.06–2.22 s; one thread and twisting_cloth_64 unchanged).
const MIN_CHUNKS_PER_COLOR: usize = 4;

/// Elements of the serial group evaluated in parallel before they are added in order: their
/// outputs (up to `element_stride(8)` values each) stay within a core's cache.
const SERIAL_BATCH: usize = 64;

/// Consecutive elements coloured together: evaluated in order on one thread (elements of a mesh
/// numbered in order are mostly neighbours, so their data stays in cache).
const CHUNK: usize = 128;

/// A term's elements are first cut into this many bands of consecutive elements (at least
/// [`CHUNK`] each): on a mesh numbered in order, a band's elements touch one stretch of matrix
/// rows, and neighbouring bands alternate between two or three colours, so that each colour is
/// a sweep over the matrix in order. With chunks of [`CHUNK`] a grid's colours each skip
/// through the whole matrix, which the hardware cannot prefetch once the matrix leaves the
/// caches (a 128² cloth: evaluation −12 to −14%). Where the bands need the serial group, chunks of
/// [`CHUNK`].
const BANDS_PER_TERM: usize = 16;

/// Elements ahead whose matrix blocks are prefetched (2, 4, 8 and 16 alike on a 128² cloth).
const PREFETCH_AHEAD: usize = 4;

/// Layout of one term.
#[derive(Default)]
struct TermLayout {
    /// (topology version, elements, width) the layout was built for.
    key: Option<(u64, usize, usize)>,
    /// The term's block pairs `(row, column)`, sorted and deduplicated; built only when the
    /// pattern is rebuilt (sorting a contact term's millions of pairs at every change of its
    /// active set cost a tenth of a folded towel's run).
    pairs: Option<Vec<(u32, u32)>>,
    width: usize,
    /// Unknowns of each element (`width` each; its DOF blocks mapped through the [`DofMap`]).
    stencils: Vec<u32>,
    /// Matrix slot of each element block `(a, b)` that lies in the upper triangle (`width²`).
    slots: Vec<u32>,
    /// Element ranges (chunks) per colour.
    colors: Vec<Vec<(u32, u32)>>,
    /// Chunks that did not fit in [`MAX_COLORS`] colours or were in a colour of fewer than
    /// [`MIN_CHUNKS_PER_COLOR`], added serially.
    serial: Vec<(u32, u32)>,
    /// Energy of each element at the last evaluation.
    /// Per element: its energy and the sum of its gradient entries' magnitudes.
    energies: Vec<[f64; 2]>,
}

impl TermLayout {
    /// Number of elements in the serial group.
    fn serial_len(&self) -> usize {
        self.serial.iter().map(|&(start, end)| (end - start) as usize).sum()
    }
}

/// A pointer that may be shared between threads that write disjoint entries.
#[derive(Clone, Copy)]
struct Shared<T>(*mut T);
// SAFETY: only used for writes to disjoint indices (the colouring, and the mirror slots; see
// `assemble`).
unsafe impl<T> Send for Shared<T> {}
unsafe impl<T> Sync for Shared<T> {}

impl<T> Shared<T> {
    /// The pointer (a method, so closures capture the whole `Shared`, which is `Sync`).
    fn ptr(self) -> *mut T {
        self.0
    }
}

/// What one assembly sums besides the gradient and the matrix.
#[derive(Clone, Copy, Debug, Default)]
pub struct Assembled {
    /// Total energy, J.
    pub energy: f64,
    /// Sum of the element energies' magnitudes, J: the total's rounding error is a small
    /// multiple of machine epsilon times this, plus the positions' rounding below.
    pub energy_abs: f64,
    /// Sum of the element gradients' entry magnitudes (DOF space, N·s): positions are rounded
    /// to machine epsilon times their magnitude, which perturbs each element energy by its
    /// gradient times that much (a stiff joint carrying 10 N at 1 m from the origin: ~1e-15 J,
    /// however small its energy).
    pub gradient_abs: f64,
}

/// Cached layout of the assembly.
#[derive(Default)]
pub struct Assembler {
    key: Option<LayoutKey>,
    /// The map the layouts were built with.
    dofs: DofMap,
    layouts: Vec<TermLayout>,
    /// For every stored block: `None` for the upper triangle (accumulated), or the upper block
    /// it is the transpose of.
    mirror: Vec<Option<u32>>,
    /// The assembled Hessian (pattern and values).
    pub matrix: BlockSparseMatrix,
    /// Identifies the sparsity pattern of `matrix`; unchanged while the pattern is unchanged.
    pub pattern_id: u64,
    /// Number of layout rebuilds (for logs).
    pub rebuilds: usize,
    /// The next assembly builds the pattern from the terms alone (set at each step's start).
    pub exact_pattern_next: bool,
    /// Wall time in evaluation (with accumulation) and in completing the matrix, s.
    pub timing: (f64, f64),
    /// Outputs of a batch of the serial group (every entry is written before it is read).
    serial_batch: Vec<f64>,
}

/// Merge two sorted, deduplicated lists into one.
fn merge_sorted(a: &[(u32, u32)], b: &[(u32, u32)]) -> Vec<(u32, u32)> {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        match a[i].cmp(&b[j]) {
            std::cmp::Ordering::Less => {
                out.push(a[i]);
                i += 1;
            }
            std::cmp::Ordering::Greater => {
                out.push(b[j]);
                j += 1;
            }
            std::cmp::Ordering::Equal => {
                out.push(a[i]);
                i += 1;
                j += 1;
            }
        }
    }
    out.extend_from_slice(&a[i..]);
    out.extend_from_slice(&b[j..]);
    out
}

/// The block pairs `(row, column)` of `stencils` (`width` each, blocks below `n_blocks`),
/// sorted and deduplicated. The columns are bucketed by row first (a counting sort), so only the
/// short rows are sorted: a global sort of the ~3M pairs of a folded towel's contact took 5% of
/// its run.
fn block_pairs(stencils: &[u32], width: usize, n_blocks: usize) -> Vec<(u32, u32)> {
    let width = width.max(1);
    let mut row_start = vec![0usize; n_blocks + 1];
    for st in stencils.chunks_exact(width) {
        let valid = st.iter().filter(|&&b| b != NO_DOF).count();
        for &r in st.iter().filter(|&&r| r != NO_DOF) {
            row_start[r as usize + 1] += valid;
        }
    }
    for r in 0..n_blocks {
        row_start[r + 1] += row_start[r];
    }
    let mut columns = vec![0u32; row_start[n_blocks]];
    let mut fill = row_start.clone();
    for st in stencils.chunks_exact(width) {
        for &r in st.iter().filter(|&&r| r != NO_DOF) {
            for &c in st.iter().filter(|&&c| c != NO_DOF) {
                columns[fill[r as usize]] = c;
                fill[r as usize] += 1;
            }
        }
    }
    let mut rows: Vec<&mut [u32]> = Vec::with_capacity(n_blocks);
    let mut rest = columns.as_mut_slice();
    for r in 0..n_blocks {
        let (row, tail) = rest.split_at_mut(row_start[r + 1] - row_start[r]);
        rows.push(row);
        rest = tail;
    }
    let unique: Vec<usize> = rows
        .par_iter_mut()
        .map(|row| {
            row.sort_unstable();
            let mut len = 0;
            for k in 0..row.len() {
                if len == 0 || row[k] != row[len - 1] {
                    row[len] = row[k];
                    len += 1;
                }
            }
            len
        })
        .collect();
    let mut pairs = Vec::with_capacity(unique.iter().sum());
    for (r, (row, &len)) in rows.iter().zip(&unique).enumerate() {
        pairs.extend(row[..len].iter().map(|&c| (r as u32, c)));
    }
    pairs
}

/// Whether every block of `stencils` (`width` each) is in the (symmetric) pattern of `matrix`.
fn stencils_fit(matrix: &BlockSparseMatrix, stencils: &[u32], width: usize) -> bool {
    stencils.par_chunks(width.max(1)).all(|st| {
        st.iter().filter(|&&r| r != NO_DOF).all(|&r| {
            st.iter()
                .filter(|&&c| c != NO_DOF && r <= c)
                .all(|&c| matrix.find(r, c).is_some())
        })
    })
}

fn slot_of(matrix: &BlockSparseMatrix, r: u32, c: u32) -> u32 {
    matrix.find(r, c).expect("block in pattern") as u32
}

/// Element ranges per colour, and the ranges of the serial group.
type Coloring = (Vec<Vec<(u32, u32)>>, Vec<(u32, u32)>);

/// Greedy colouring of the chunks of `chunk` consecutive elements (`width` blocks each in
/// `stencils`) so that no two chunks of a colour share a block: the colours' chunks, and the
/// chunks left to the serial group (beyond [`MAX_COLORS`], or in a colour of fewer than
/// [`MIN_CHUNKS_PER_COLOR`]), sorted.
fn color_chunks(stencils: &[u32], width: usize, n_blocks: usize, chunk: usize) -> Coloring {
    let m = width;
    let n = stencils.len().checked_div(m).unwrap_or(0);
    let mut used = vec![0u64; n_blocks];
    let mut colors: Vec<Vec<(u32, u32)>> = Vec::new();
    let mut serial = Vec::new();
    for start in (0..n).step_by(chunk) {
        let end = (start + chunk).min(n);
        let blocks = stencils[start * m..end * m].iter().filter(|&&r| r != NO_DOF);
        let mask = blocks.clone().fold(0u64, |acc, &r| acc | used[r as usize]);
        let color = mask.trailing_ones() as usize;
        let range = (start as u32, end as u32);
        if color >= MAX_COLORS {
            serial.push(range);
            continue;
        }
        if colors.len() <= color {
            colors.resize(color + 1, Vec::new());
        }
        colors[color].push(range);
        for &r in blocks {
            used[r as usize] |= 1 << color;
        }
    }
    // A colour of a few chunks runs on a few threads and ends in a barrier: its chunks go to the
    // serial group (evaluated in parallel batches, added in order) instead.
    let (kept, sparse): (Vec<_>, Vec<_>) = colors.into_iter().partition(|c| c.len() >= MIN_CHUNKS_PER_COLOR);
    serial.extend(sparse.into_iter().flatten());
    serial.sort_unstable();
    (kept, serial)
}

impl Assembler {
    fn ensure_layout(&mut self, terms: &[&dyn EnergyTerm], state: &EvalState, dofs: &DofMap) {
        let n_blocks = dofs.len();
        if self.dofs != *dofs {
            // Nodes or bodies were added: every stencil moves.
            self.dofs = dofs.clone();
            self.key = None;
            self.layouts.clear();
        }
        let key: LayoutKey = (
            terms
                .iter()
                .map(|t| (t.topology_version(), t.num_elements(), t.stencil_width(state)))
                .collect(),
            n_blocks,
        );
        if self.key.as_ref() == Some(&key) {
            return;
        }
        // Stencils and block pairs, rebuilt only for terms whose topology changed (contact
        // changes often; the elastic terms never do).
        // Body DOF blocks follow the node blocks: a new node count moves them.
        if self.key.as_ref().map(|k| k.1) != Some(n_blocks) || self.layouts.len() != terms.len() {
            self.layouts.clear();
        }
        self.layouts.resize_with(terms.len(), TermLayout::default);
        let mut changed = vec![false; terms.len()];
        for ((layout, t), changed) in self.layouts.iter_mut().zip(terms).zip(changed.iter_mut()) {
            let term_key = (t.topology_version(), t.num_elements(), t.stencil_width(state));
            if layout.key == Some(term_key) {
                continue;
            }
            *changed = true;
            let m = term_key.2;
            let mut stencils = vec![NO_DOF; t.num_elements() * m];
            t.write_stencils(state, &mut stencils);
            stencils.par_iter_mut().filter(|s| **s != NO_DOF).for_each(|s| {
                let dof = dofs.dof_of_block[*s as usize];
                // A fixed node's block is not an unknown: the element's derivatives with respect
                // to it are dropped. Any other block that is not an unknown (a rigid node's) has
                // no place in the system: terms reach rigid nodes through their body's blocks.
                let fixed = state.nodes.body.get(*s as usize) == Some(&FIXED_NODE);
                assert!(
                    dof != NO_DOF || fixed,
                    "'{}' writes DOF block {s}, which is not an unknown",
                    t.name()
                );
                *s = dof;
            });
            *layout = TermLayout {
                key: Some(term_key),
                pairs: None,
                width: m,
                stencils,
                ..Default::default()
            };
        }
        // The pattern only grows while the terms' blocks fit in it: a contact pair that comes
        // and goes between Newton iterations keeps its blocks (as zeros), so the pattern, the
        // other terms' slots and the linear solver's analysis stay.
        // At a step's first assembly the pattern is rebuilt from the terms alone (unless it is
        // exactly theirs already): what the sticky pattern carries over from earlier steps would
        // otherwise change the Cholesky ordering, and a run resumed from a checkpoint would
        // round differently from the uninterrupted one.
        let exact = std::mem::take(&mut self.exact_pattern_next);
        let fits = !exact
            && self.matrix.n_blocks == n_blocks
            && !self.matrix.row_start.is_empty()
            && self
                .layouts
                .iter()
                .zip(&changed)
                .filter(|(_, &c)| c)
                .all(|(layout, _)| stencils_fit(&self.matrix, &layout.stencils, layout.width));
        let mut same_pattern = fits;
        if !fits {
            // Merge the sorted pair lists of all terms and the diagonal; keep the old pattern's
            // blocks too while they are few (the pairs that come and go), not when the contacts
            // have moved on.
            let mut pairs: Vec<(u32, u32)> = (0..n_blocks as u32).map(|b| (b, b)).collect();
            for layout in &mut self.layouts {
                let term_pairs = layout
                    .pairs
                    .get_or_insert_with(|| block_pairs(&layout.stencils, layout.width, n_blocks));
                pairs = merge_sorted(&pairs, term_pairs);
            }
            let old_pairs = (self.matrix.n_blocks == n_blocks).then(|| self.matrix.pattern_pairs());
            same_pattern = exact && old_pairs.as_ref() == Some(&pairs);
            if !exact && (self.matrix.nnz_blocks() as f64) < STICKY_PATTERN_GROWTH * pairs.len() as f64 {
                if let Some(old) = &old_pairs {
                    pairs = merge_sorted(&pairs, old);
                }
            }
            if !same_pattern {
                self.matrix = BlockSparseMatrix::from_sorted_pairs(n_blocks, &pairs);
                let matrix = &self.matrix;
                self.mirror = pairs
                    .par_iter()
                    .map(|&(r, c)| (r > c).then(|| slot_of(matrix, c, r)))
                    .collect();
                self.pattern_id = NEXT_PATTERN_ID.fetch_add(1, Ordering::Relaxed);
            }
        }
        let matrix = &self.matrix;

        // Slot maps (when the pattern or the term changed) and colours (when the term changed).
        for ((layout, t), &changed) in self.layouts.iter_mut().zip(terms).zip(&changed) {
            let m = layout.width;
            let n = t.num_elements();
            if changed || !same_pattern {
                layout.slots = vec![NO_SLOT; n * m * m];
                let stencils = &layout.stencils;
                layout
                    .slots
                    .par_chunks_mut((m * m).max(1))
                    .zip(stencils.par_chunks(m.max(1)))
                    .for_each(|(slots, st)| {
                        for a in 0..m {
                            for b in 0..m {
                                if st[a] != NO_DOF && st[b] != NO_DOF && st[a] <= st[b] {
                                    slots[a * m + b] = slot_of(matrix, st[a], st[b]);
                                }
                            }
                        }
                    });
            }
            if !changed {
                continue;
            }
            layout.energies = vec![[0.0; 2]; n];
            // Bands first (few sweeps over the matrix, each in order); chunks of `CHUNK` when
            // the bands do not colour into parallel sweeps alone.
            let band = n.div_ceil(BANDS_PER_TERM).max(CHUNK);
            let (mut colors, mut serial) = color_chunks(&layout.stencils, m, n_blocks, band);
            if band > CHUNK && !serial.is_empty() {
                (colors, serial) = color_chunks(&layout.stencils, m, n_blocks, CHUNK);
            }
            layout.colors = colors;
            layout.serial = serial;
        }
        self.key = Some(key);
        self.rebuilds += 1;
    }

    /// Make the layout (stencils, pattern, slots) of an assembly of `terms` at `state` without
    /// evaluating anything: [`Assembler::matrix`]'s pattern and [`Assembler::pattern_id`] are
    /// then the next [`Assembler::assemble`]'s.
    pub fn prepare_layout(&mut self, terms: &[&dyn EnergyTerm], state: &EvalState, dofs: &DofMap) {
        self.ensure_layout(terms, state, dofs);
    }

    /// Evaluate all terms at `state`: returns the total energy and the scales of its rounding
    /// error (see [`Assembled`]), writes the gradient over the unknowns (length `3·dofs.len()`)
    /// and assembles the Hessian into [`Assembler::matrix`].
    pub fn assemble(
        &mut self,
        terms: &[&dyn EnergyTerm],
        state: &EvalState,
        dofs: &DofMap,
        mode: EvalMode,
        gradient: &mut [f64],
    ) -> Assembled {
        self.ensure_layout(terms, state, dofs);
        let t0 = std::time::Instant::now();
        gradient.par_iter_mut().with_min_len(4096).for_each(|g| *g = 0.0);
        self.matrix
            .values
            .par_iter_mut()
            .with_min_len(4096)
            .for_each(|v| *v = [0.0; 9]);
        let grad_ptr = Shared(gradient.as_mut_ptr());
        let values_ptr = Shared(self.matrix.values.as_mut_ptr());
        let mut sum = Assembled::default();
        let batch = &mut self.serial_batch;
        for (layout, term) in self.layouts.iter_mut().zip(terms) {
            let m = layout.width;
            let stride = element_stride(m);
            let energies_ptr = Shared(layout.energies.as_mut_ptr());
            let (stencils, slots) = (&layout.stencils, &layout.slots);
            let add = |e: usize, out: &[f64]| {
                let st = &stencils[e * m..(e + 1) * m];
                // SAFETY: elements of one colour share no DOF block, so they write disjoint
                // gradient entries and disjoint matrix blocks (a block's slot is determined by
                // its two DOF blocks); energies are indexed by the element. Colours run one
                // after the other. The serial group runs on one thread.
                unsafe {
                    let grad_abs: f64 = out[1..1 + 3 * m].iter().map(|g| g.abs()).sum();
                    *energies_ptr.ptr().add(e) = [out[0], grad_abs];
                    for a in 0..m {
                        if st[a] == NO_DOF {
                            continue;
                        }
                        let g = grad_ptr.ptr().add(3 * st[a] as usize);
                        for i in 0..3 {
                            *g.add(i) += out[1 + 3 * a + i];
                        }
                        for b in 0..m {
                            let slot = slots[(e * m + a) * m + b];
                            if slot == NO_SLOT {
                                continue;
                            }
                            let blk = &mut *values_ptr.ptr().add(slot as usize);
                            let src = &out[1 + 3 * m + 9 * (a * m + b)..][..9];
                            for k in 0..9 {
                                blk[k] += src[k];
                            }
                        }
                    }
                }
            };
            // The matrix blocks of an element a few ahead, requested while this one is evaluated:
            // its rows are scattered over the matrix (a grid's next row of nodes is a matrix row
            // 130 rows on), and once the matrix leaves the caches each block added waits for
            // memory (a 128² cloth: evaluation −32 to −35%, the folded towel's −14 to −15%).
            // Nothing past `end`, the element range's end.
            let prefetch = |e: usize, end: usize| {
                if e >= end {
                    return;
                }
                #[cfg(target_arch = "x86_64")]
                // SAFETY: a prefetch is a hint that never faults; the addresses are those of the
                // element's blocks in the matrix's values (a block's 72 bytes span two lines).
                unsafe {
                    use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
                    for &slot in &slots[e * m * m..(e + 1) * m * m] {
                        if slot != NO_SLOT {
                            let p = values_ptr.ptr().add(slot as usize) as *const i8;
                            _mm_prefetch(p, _MM_HINT_T0);
                            _mm_prefetch(p.add(64), _MM_HINT_T0);
                        }
                    }
                }
                #[cfg(not(target_arch = "x86_64"))]
                let _ = e;
            };
            for color in &layout.colors {
                color.par_iter().for_each_init(
                    || vec![0.0; stride],
                    |buf, &(start, end)| {
                        for e in start as usize..end as usize {
                            prefetch(e + PREFETCH_AHEAD, end as usize);
                            term.evaluate_element(e, state, mode, buf);
                            add(e, buf);
                        }
                    },
                );
            }
            // Elements no colour could take (those sharing a rigid body's blocks with many
            // others): evaluated in parallel a batch at a time, added in order on this thread.
            let batch_len = SERIAL_BATCH.min(layout.serial_len()) * stride;
            if batch.len() < batch_len {
                batch.resize(batch_len, 0.0);
            }
            for &(start, end) in &layout.serial {
                let mut first = start as usize;
                while first < end as usize {
                    let last = (first + SERIAL_BATCH).min(end as usize);
                    let outs = &mut batch[..(last - first) * stride];
                    outs.par_chunks_mut(stride).enumerate().for_each(|(k, out)| {
                        term.evaluate_element(first + k, state, mode, out);
                    });
                    for (k, out) in outs.chunks_exact(stride).enumerate() {
                        prefetch(first + k + PREFETCH_AHEAD, last);
                        add(first + k, out);
                    }
                    first = last;
                }
            }
            for &[e, g] in &layout.energies {
                sum.energy += e;
                sum.energy_abs += e.abs();
                sum.gradient_abs += g;
            }
        }
        let t1 = std::time::Instant::now();
        self.timing.0 += (t1 - t0).as_secs_f64();
        // Lower triangle: transposes of the upper blocks.
        let values = Shared(self.matrix.values.as_mut_ptr());
        self.mirror
            .par_iter()
            .enumerate()
            .with_min_len(4096)
            .for_each(|(slot, mirror)| {
                if let Some(upper) = *mirror {
                    // SAFETY: a lower slot is written only here, once, and is never an upper
                    // slot read by another (mirrors point from below the diagonal to above).
                    unsafe {
                        let u = *values.ptr().add(upper as usize);
                        *values.ptr().add(slot) = [u[0], u[3], u[6], u[1], u[4], u[7], u[2], u[5], u[8]];
                    }
                }
            });
        self.timing.1 += t1.elapsed().as_secs_f64();
        sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::state::{BodyArrays, NodeArrays};
    use nalgebra::Vector3;

    /// Bands and chunks alike: every element in exactly one range, no two ranges of a colour
    /// sharing a block, every colour with enough chunks; a grid's triangles numbered row by row
    /// colour into bands without the serial group, and a stencil every element shares (a rigid
    /// body's block) leaves the bands for the serial group.
    #[test]
    fn chunks_of_a_colour_share_no_block() {
        let m = 64;
        let node = |i: usize, j: usize| (i * (m + 1) + j) as u32;
        let mut triangles = Vec::new();
        for i in 0..m {
            for j in 0..m {
                triangles.extend([node(i, j), node(i + 1, j), node(i, j + 1)]);
                triangles.extend([node(i + 1, j), node(i + 1, j + 1), node(i, j + 1)]);
            }
        }
        let n_blocks = (m + 1) * (m + 1) + 1;
        let mut on_body = triangles.clone();
        on_body
            .chunks_exact_mut(3)
            .step_by(2)
            .for_each(|t| t[2] = (n_blocks - 1) as u32);
        let n = triangles.len() / 3;
        let band = n.div_ceil(BANDS_PER_TERM);
        for (stencils, chunk, bands_colour) in [
            (&triangles, band, true),
            (&triangles, CHUNK, true),
            (&on_body, band, false),
            (&on_body, CHUNK, false),
        ] {
            let (colors, serial) = color_chunks(stencils, 3, n_blocks, chunk);
            assert_eq!(serial.is_empty(), bands_colour, "chunk {chunk}: serial {serial:?}");
            let mut covered = vec![0u8; n];
            for ranges in colors.iter().chain(std::iter::once(&serial)) {
                for &(start, end) in ranges {
                    covered[start as usize..end as usize].iter_mut().for_each(|c| *c += 1);
                }
            }
            assert!(covered.iter().all(|&c| c == 1), "chunk {chunk}: each element once");
            for ranges in &colors {
                assert!(ranges.len() >= MIN_CHUNKS_PER_COLOR);
                let mut owner = vec![u32::MAX; n_blocks];
                for (k, &(start, end)) in ranges.iter().enumerate() {
                    for &b in &stencils[3 * start as usize..3 * end as usize] {
                        assert!(
                            owner[b as usize] == u32::MAX || owner[b as usize] == k as u32,
                            "chunk {chunk}: block {b} in two ranges of one colour"
                        );
                        owner[b as usize] = k as u32;
                    }
                }
            }
            if chunk == band && bands_colour {
                assert!(colors.len() <= 3, "bands in {} colours", colors.len());
            }
        }
    }

    /// The bucketed pair list equals the plainly sorted and deduplicated one.
    #[test]
    fn block_pairs_are_sorted_and_unique() {
        let width = 4;
        let n_blocks = 40;
        let stencils: Vec<u32> = (0..500u32)
            .flat_map(|e| {
                (0..width as u32).map(move |k| {
                    let b = (e * 7 + k * 13 + (e * k) % 5) % (n_blocks as u32 + 3);
                    if b >= n_blocks as u32 {
                        NO_DOF
                    } else {
                        b
                    }
                })
            })
            .collect();
        let mut expected = Vec::new();
        for st in stencils.chunks_exact(width) {
            for &r in st.iter().filter(|&&r| r != NO_DOF) {
                for &c in st.iter().filter(|&&c| c != NO_DOF) {
                    expected.push((r, c));
                }
            }
        }
        expected.sort_unstable();
        expected.dedup();
        assert_eq!(block_pairs(&stencils, width, n_blocks), expected);
    }

    /// Springs `½|v_a − v_b|²` between the given node pairs; the pairs may change (like contact).
    struct Springs {
        pairs: Vec<[u32; 2]>,
        version: u64,
    }

    impl EnergyTerm for Springs {
        fn name(&self) -> &str {
            "springs"
        }
        fn num_elements(&self) -> usize {
            self.pairs.len()
        }
        fn stencil_width(&self, _state: &EvalState) -> usize {
            2
        }
        fn write_stencils(&self, _state: &EvalState, out: &mut [u32]) {
            for (o, p) in out.chunks_exact_mut(2).zip(&self.pairs) {
                o.copy_from_slice(p);
            }
        }
        fn topology_version(&self) -> u64 {
            self.version
        }
        fn energy(&self, state: &EvalState) -> f64 {
            self.pairs
                .iter()
                .map(|&[a, b]| 0.5 * (state.v[a as usize] - state.v[b as usize]).norm_squared())
                .sum()
        }
        fn evaluate_element(&self, e: usize, state: &EvalState, _mode: EvalMode, out: &mut [f64]) {
            let [a, b] = self.pairs[e];
            let d = state.v[a as usize] - state.v[b as usize];
            out.iter_mut().for_each(|o| *o = 0.0);
            out[0] = 0.5 * d.norm_squared();
            for i in 0..3 {
                out[1 + i] = d[i];
                out[4 + i] = -d[i];
                // Blocks (0,0), (1,1): +I; (0,1), (1,0): −I.
                for (blk, sign) in [(0, 1.0), (1, -1.0), (2, -1.0), (3, 1.0)] {
                    out[7 + 9 * blk + 4 * i] = sign;
                }
            }
        }
    }

    fn assemble(assembler: &mut Assembler, term: &Springs, nodes: &NodeArrays) -> Vec<Vec<f64>> {
        let bodies = BodyArrays::default();
        let v: Vec<Vector3<f64>> = (0..nodes.len())
            .map(|i| Vector3::new(i as f64, 1.0, -(i as f64)))
            .collect();
        let state = EvalState {
            dt: 0.01,
            time: 0.01,
            gravity: Vector3::zeros(),
            nodes,
            v: &v,
            x: &nodes.x,
            bodies: &bodies,
            poses: &[],
        };
        let dofs = DofMap::new(nodes, &bodies);
        let mut gradient = vec![0.0; 3 * dofs.len()];
        assembler.assemble(
            &[term as &dyn EnergyTerm],
            &state,
            &dofs,
            EvalMode::ExactHessian,
            &mut gradient,
        );
        assembler.matrix.to_dense()
    }

    /// Pairs that come and go keep the pattern (their blocks stay, as zeros): the linear solver's
    /// analysis is reused. The matrix is the one a fresh assembly gives; a new block grows it.
    #[test]
    fn the_pattern_keeps_blocks_that_come_and_go_and_grows_for_new_ones() {
        let mut nodes = NodeArrays::default();
        nodes.push(&[Vector3::zeros(); 5]);
        let mut term = Springs {
            pairs: vec![[0, 1], [1, 2], [3, 4]],
            version: 1,
        };
        let mut sticky = Assembler::default();
        let fresh = |term: &Springs| assemble(&mut Assembler::default(), term, &nodes);
        assert_eq!(assemble(&mut sticky, &term, &nodes), fresh(&term));
        let first = sticky.pattern_id;
        let blocks = sticky.matrix.nnz_blocks();

        term.pairs = vec![[0, 1], [3, 4]];
        term.version = 2;
        assert_eq!(assemble(&mut sticky, &term, &nodes), fresh(&term));
        assert_eq!(sticky.pattern_id, first, "a subset keeps the pattern");
        assert_eq!(sticky.matrix.nnz_blocks(), blocks);

        term.pairs = vec![[0, 1], [1, 2], [3, 4]];
        term.version = 3;
        assert_eq!(assemble(&mut sticky, &term, &nodes), fresh(&term));
        assert_eq!(sticky.pattern_id, first, "a pair that comes back finds its blocks");

        // A new block grows the pattern; the old blocks stay while they are few.
        term.pairs = vec![[0, 4], [1, 2], [3, 4]];
        term.version = 4;
        assert_eq!(assemble(&mut sticky, &term, &nodes), fresh(&term));
        let grown = sticky.pattern_id;
        assert_ne!(grown, first, "a new block changes the pattern");
        assert!(sticky.matrix.find(0, 4).is_some() && sticky.matrix.find(0, 1).is_some());

        // When the contacts have moved on (most of the pattern unused), it is rebuilt tight.
        term.pairs = vec![[0, 2]];
        term.version = 5;
        assert_eq!(assemble(&mut sticky, &term, &nodes), fresh(&term));
        assert_ne!(sticky.pattern_id, grown);
        assert_eq!(sticky.matrix.nnz_blocks(), 5 + 2);
    }
}
