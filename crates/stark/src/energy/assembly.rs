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
    /// The assembled Hessian (pattern and values).
    pub matrix: BlockSparseMatrix,
    /// Identifies the sparsity pattern of `matrix`; unchanged while the pattern is unchanged.
    pub pattern_id: u64,
    /// Number of pattern rebuilds (for logs).
    pub rebuilds: usize,
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
                        hess.push((st[a], st[b], base + 1 + 3 * m + 9 * (a * m + b)));
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
        let buffer = &self.buffer;
        let (gp, gs) = (&self.grad_ptr, &self.grad_src);
        gradient.par_chunks_mut(3).enumerate().for_each(|(b, g)| {
            let mut acc = [0.0; 3];
            for &src in &gs[gp[b]..gp[b + 1]] {
                acc[0] += buffer[src];
                acc[1] += buffer[src + 1];
                acc[2] += buffer[src + 2];
            }
            g.copy_from_slice(&acc);
        });
        let (hp, hs) = (&self.hess_ptr, &self.hess_src);
        self.matrix
            .values
            .par_iter_mut()
            .enumerate()
            .for_each(|(slot, v)| {
                let mut acc = [0.0; 9];
                for &src in &hs[hp[slot]..hp[slot + 1]] {
                    for (a, b) in acc.iter_mut().zip(&buffer[src..src + 9]) {
                        *a += b;
                    }
                }
                *v = acc;
            });
        (energy, scale)
    }
}
