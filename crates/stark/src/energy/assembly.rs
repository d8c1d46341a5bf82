//! Assembly of the global gradient and block-sparse Hessian from element outputs.
//!
//! Terms write every element's value, gradient and Hessian blocks into one flat buffer (in
//! parallel, each element its own slice). The global matrix is then *gathered*: each stored block
//! knows the buffer positions of its contributions, so rows are summed in parallel without
//! conflicts and in a fixed order (deterministic for any thread count). The pattern and gather
//! lists are rebuilt only when a term's topology changes.

use super::term::{element_stride, EnergyTerm, EvalMode, NO_DOF};
use crate::solver::linear::BlockSparseMatrix;
use crate::state::EvalState;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

static NEXT_PATTERN_ID: AtomicU64 = AtomicU64::new(1);

/// Identity of the current layout: per term (version, elements, width), and the block count.
type LayoutKey = (Vec<(u64, usize, usize)>, usize);

/// Cached layout and scratch of the assembly.
#[derive(Default)]
pub struct Assembler {
    key: Option<LayoutKey>,
    term_base: Vec<usize>,
    buffer: Vec<f64>,
    grad_ptr: Vec<usize>,
    grad_src: Vec<usize>,
    hess_ptr: Vec<usize>,
    hess_src: Vec<usize>,
    /// For every stored block: `None` for the upper triangle (gathered), or the upper-triangle
    /// block it is the transpose of.
    mirror: Vec<Option<u32>>,
    /// The assembled Hessian (pattern and values).
    pub matrix: BlockSparseMatrix,
    /// Identifies the sparsity pattern of `matrix`; unchanged while the pattern is unchanged.
    pub pattern_id: u64,
    /// Number of pattern rebuilds (for logs).
    pub rebuilds: usize,
    /// Wall time in element evaluation and in gathering, s.
    pub timing: (f64, f64),
}

impl Assembler {
    fn ensure_layout(&mut self, terms: &[&dyn EnergyTerm], state: &EvalState, n_blocks: usize) {
        let key: LayoutKey = (
            terms
                .iter()
                .map(|t| (t.topology_version(), t.num_elements(), t.stencil_width()))
                .collect(),
            n_blocks,
        );
        if self.key.as_ref() == Some(&key) {
            return;
        }
        // Buffer layout and stencils.
        self.term_base.clear();
        let mut total = 0usize;
        let mut stencils: Vec<Vec<u32>> = Vec::with_capacity(terms.len());
        for t in terms {
            self.term_base.push(total);
            let m = t.stencil_width();
            total += t.num_elements() * element_stride(m);
            let mut s = vec![NO_DOF; t.num_elements() * m];
            t.write_stencils(state, &mut s);
            stencils.push(s);
        }
        self.buffer.resize(total, 0.0);

        // (row, col, source) for every Hessian block; (block, source) for every gradient part.
        let mut hess: Vec<(u32, u32, usize)> = Vec::new();
        let mut grad: Vec<(u32, usize)> = Vec::new();
        for (k, t) in terms.iter().enumerate() {
            let m = t.stencil_width();
            let stride = element_stride(m);
            for (e, st) in stencils[k]
                .chunks_exact(m.max(1))
                .enumerate()
                .take(t.num_elements())
            {
                let base = self.term_base[k] + e * stride;
                for a in 0..m {
                    if st[a] == NO_DOF {
                        continue;
                    }
                    grad.push((st[a], base + 1 + 3 * a));
                    for b in 0..m {
                        if st[b] == NO_DOF {
                            continue;
                        }
                        // Only the upper triangle is gathered; the lower one is its transpose.
                        let src = if st[a] <= st[b] {
                            base + 1 + 3 * m + 9 * (a * m + b)
                        } else {
                            usize::MAX
                        };
                        hess.push((st[a], st[b], src));
                    }
                }
            }
        }
        // Every row gets a diagonal block, even without contributions.
        for b in 0..n_blocks as u32 {
            hess.push((b, b, usize::MAX));
        }
        hess.par_sort_unstable();
        grad.par_sort_unstable();

        let mut pairs: Vec<(u32, u32)> = Vec::new();
        self.hess_ptr.clear();
        self.hess_src.clear();
        for &(r, c, src) in &hess {
            if pairs.last() != Some(&(r, c)) {
                pairs.push((r, c));
                self.hess_ptr.push(self.hess_src.len());
            }
            if src != usize::MAX {
                self.hess_src.push(src);
            }
        }
        self.hess_ptr.push(self.hess_src.len());

        self.grad_ptr = vec![0; n_blocks + 1];
        for &(b, _) in &grad {
            self.grad_ptr[b as usize + 1] += 1;
        }
        for i in 0..n_blocks {
            self.grad_ptr[i + 1] += self.grad_ptr[i];
        }
        self.grad_src = grad.iter().map(|&(_, s)| s).collect();

        let matrix = BlockSparseMatrix::from_sorted_pairs(n_blocks, &pairs);
        self.mirror = pairs
            .iter()
            .map(|&(r, c)| {
                (r > c).then(|| {
                    let row = matrix.row_start[c as usize]..matrix.row_start[c as usize + 1];
                    let k = matrix.cols[row.clone()]
                        .binary_search(&r)
                        .expect("symmetric pattern");
                    (row.start + k) as u32
                })
            })
            .collect();
        let same_pattern =
            matrix.row_start == self.matrix.row_start && matrix.cols == self.matrix.cols;
        if !same_pattern || self.pattern_id == 0 {
            self.pattern_id = NEXT_PATTERN_ID.fetch_add(1, Ordering::Relaxed);
        }
        self.matrix = matrix;
        self.key = Some(key);
        self.rebuilds += 1;
    }

    /// Evaluate all terms at `state`: returns the total energy and the sum of absolute element
    /// energies (the scale of its rounding error), writes the gradient (length `3·n_blocks`) and
    /// assembles the Hessian into [`Assembler::matrix`].
    pub fn assemble(
        &mut self,
        terms: &[&dyn EnergyTerm],
        state: &EvalState,
        n_blocks: usize,
        mode: EvalMode,
        gradient: &mut [f64],
    ) -> (f64, f64) {
        self.ensure_layout(terms, state, n_blocks);
        let t0 = std::time::Instant::now();
        let mut energy = 0.0;
        let mut scale = 0.0;
        for (k, t) in terms.iter().enumerate() {
            let len = t.num_elements() * element_stride(t.stencil_width());
            let base = self.term_base[k];
            let out = &mut self.buffer[base..base + len];
            t.evaluate(state, mode, out);
            let stride = element_stride(t.stencil_width());
            for e in out.iter().step_by(stride) {
                energy += e;
                scale += e.abs();
            }
        }
        let t1 = std::time::Instant::now();
        self.timing.0 += (t1 - t0).as_secs_f64();
        let buffer = &self.buffer;
        let (gp, gs) = (&self.grad_ptr, &self.grad_src);
        const BLOCKS_PER_TASK: usize = 1024;
        gradient
            .par_chunks_mut(3 * BLOCKS_PER_TASK)
            .enumerate()
            .for_each(|(chunk, gs_out)| {
                for (k, g) in gs_out.chunks_exact_mut(3).enumerate() {
                    let b = chunk * BLOCKS_PER_TASK + k;
                    let mut acc = [0.0; 3];
                    for &src in &gs[gp[b]..gp[b + 1]] {
                        acc[0] += buffer[src];
                        acc[1] += buffer[src + 1];
                        acc[2] += buffer[src + 2];
                    }
                    g.copy_from_slice(&acc);
                }
            });
        let (hp, hs) = (&self.hess_ptr, &self.hess_src);
        const SLOTS_PER_TASK: usize = 512;
        let mirror = &self.mirror;
        self.matrix
            .values
            .par_chunks_mut(SLOTS_PER_TASK)
            .enumerate()
            .for_each(|(chunk, values)| {
                for (k, v) in values.iter_mut().enumerate() {
                    let slot = chunk * SLOTS_PER_TASK + k;
                    if mirror[slot].is_some() {
                        continue;
                    }
                    let mut acc = [0.0; 9];
                    for &src in &hs[hp[slot]..hp[slot + 1]] {
                        for (a, b) in acc.iter_mut().zip(&buffer[src..src + 9]) {
                            *a += b;
                        }
                    }
                    *v = acc;
                }
            });
        // Lower triangle: transposes of the upper blocks.
        let values = &mut self.matrix.values;
        for slot in 0..values.len() {
            if let Some(upper) = mirror[slot] {
                let u = values[upper as usize];
                values[slot] = [u[0], u[3], u[6], u[1], u[4], u[7], u[2], u[5], u[8]];
            }
        }
        self.timing.1 += t1.elapsed().as_secs_f64();
        (energy, scale)
    }
}
