//! Newton's diagnostics on stderr (`STARK_NEWTON_TRACE`, `STARK_NEWTON_TRACE_ELEMENTS`,
//! `STARK_TRACE_TERMS`): which terms and elements make a step fail its line search, and which
//! terms make up the residual where it is largest.

use crate::energy::{EnergyTerm, EvalMode};
use crate::state::{block_kind, BlockKind, DofMap, EvalState};

/// A line-search trial that failed the Armijo condition.
pub(super) struct Cut<'a> {
    /// The step fraction tried.
    pub alpha: f64,
    /// The total energy change, J.
    pub energy_change: f64,
    /// The linear model's change `α ∇E·Δv`, J.
    pub model_change: f64,
    /// Each term's energy at the iterate.
    pub term_energies: &'a [f64],
    /// The Hessian mode of the iteration.
    pub mode: EvalMode,
}

impl Cut<'_> {
    /// One line with the terms whose energy rose most; with `STARK_NEWTON_TRACE_ELEMENTS`, the
    /// four elements whose change exceeds their quadratic model most.
    pub fn print(
        &self,
        terms: &[&mut dyn EnergyTerm],
        here: &EvalState,
        trial: &EvalState,
        dofs: &DofMap,
        step: &[f64],
    ) {
        let mut rises: Vec<(f64, &str)> = terms
            .iter()
            .zip(self.term_energies)
            .map(|(t, e0)| (t.energy(trial) - e0, t.name()))
            .collect();
        rises.sort_by(|a, b| b.0.total_cmp(&a.0));
        let top: Vec<String> = rises.iter().take(3).map(|(d, n)| format!("{n} {d:+.3e}")).collect();
        eprintln!(
            "  cut at {:.3e}: ΔE {:+.3e} (model {:+.3e}); by term: {}",
            self.alpha,
            self.energy_change,
            self.model_change,
            top.join(", ")
        );
        if std::env::var_os("STARK_NEWTON_TRACE_ELEMENTS").is_some() {
            let mut worst: Vec<(f64, String)> = Vec::new();
            for t in terms.iter() {
                worst.extend(element_model_errors(
                    &**t, here, trial, dofs, step, self.alpha, self.mode,
                ));
            }
            worst.sort_by(|a, b| b.0.total_cmp(&a.0));
            for (_, w) in worst.iter().take(4) {
                eprintln!("    {w}");
            }
        }
    }
}

/// Where the step's largest entry is: `node i`, or `body i lin|ang`.
/// Diagnostics: each term's force (its gradient / dt) at the DOF block of the gradient's largest
/// entry.
pub(super) fn print_term_forces(
    terms: &[&dyn EnergyTerm],
    state: &EvalState,
    dofs: &DofMap,
    gradient: &[f64],
    dt: f64,
) {
    let d = (0..gradient.len())
        .max_by(|&a, &b| gradient[a].abs().total_cmp(&gradient[b].abs()))
        .unwrap_or(0);
    let block = 3 * (d / 3);
    let mut parts = Vec::new();
    for &t in terms {
        let mut g = vec![0.0; gradient.len()];
        let mut assembler = crate::energy::assembly::Assembler::default();
        assembler.assemble(&[t], state, dofs, crate::energy::EvalMode::ExactHessian, &mut g);
        let f = [g[block] / dt, g[block + 1] / dt, g[block + 2] / dt];
        if f.iter().any(|c| c.abs() > 1e-3 * gradient[d].abs() / dt) {
            parts.push(format!("{} [{:.3e} {:.3e} {:.3e}]", t.name(), f[0], f[1], f[2]));
        }
    }
    eprintln!("    forces at the residual's block: {}", parts.join(", "));
}

pub(super) fn largest_entry(step: &[f64], dofs: &DofMap, n_nodes: usize) -> String {
    let d = (0..step.len())
        .max_by(|&a, &b| step[a].abs().total_cmp(&step[b].abs()))
        .unwrap_or(0);
    let block = dofs.block_of_dof.get(d / 3).map_or(0, |&b| b as usize);
    match block_kind(n_nodes, block) {
        BlockKind::Node(i) => format!("node {i}"),
        BlockKind::Linear(b) => format!("body {b} lin"),
        BlockKind::Angular(b) => format!("body {b} ang"),
    }
}

/// Diagnostics: the elements of `term` whose energy change from `from` to `to` (the step
/// `alpha·step` over the unknowns) exceeds their quadratic model most, with their DOF blocks.
fn element_model_errors(
    term: &dyn EnergyTerm,
    from: &EvalState,
    to: &EvalState,
    dofs: &DofMap,
    step: &[f64],
    alpha: f64,
    mode: EvalMode,
) -> Vec<(f64, String)> {
    let width = term.stencil_width(from);
    let n = term.num_elements();
    let mut stencils = vec![0u32; n * width];
    term.write_stencils(from, &mut stencils);
    let mut out = vec![0.0; crate::energy::term::element_stride(width)];
    let mut errors: Vec<(f64, String)> = (0..n)
        .map(|e| {
            let stencil = &stencils[e * width..][..width];
            let mut d = vec![0.0; 3 * width];
            for (a, &block) in stencil.iter().enumerate() {
                if let Some(&dof) = dofs.dof_of_block.get(block as usize) {
                    if dof != crate::state::NO_DOF {
                        d[3 * a..][..3].copy_from_slice(&step[3 * dof as usize..][..3]);
                    }
                }
            }
            term.evaluate_element(e, from, mode, &mut out);
            let e0 = out[0];
            let m = 3 * width;
            let linear: f64 = (0..m).map(|i| out[1 + i] * d[i]).sum();
            let mut quadratic = 0.0;
            for a in 0..width {
                for b in 0..width {
                    let block = &out[1 + m + 9 * (a * width + b)..][..9];
                    for i in 0..3 {
                        for j in 0..3 {
                            quadratic += d[3 * a + i] * block[3 * i + j] * d[3 * b + j];
                        }
                    }
                }
            }
            let model = alpha * linear + 0.5 * alpha * alpha * quadratic;
            term.evaluate_element(e, to, mode, &mut out);
            let actual = out[0] - e0;
            (
                actual - model,
                format!(
                    "{} #{e}: ΔE {actual:+.2e} model {model:+.2e} (lin {:+.2e} quad {:+.2e}) {stencil:?}",
                    term.name(),
                    alpha * linear,
                    0.5 * alpha * alpha * quadratic
                ),
            )
        })
        .collect();
    errors.sort_by(|a, b| b.0.total_cmp(&a.0));
    errors.truncate(4);
    errors
}
