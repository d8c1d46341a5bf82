//! The interface between energies and the solver.
//!
//! [`EnergyTerm`] is what the Newton solver sees: a set of elements, each coupling a few 3-wide
//! DOF blocks, with value, gradient and (projected) Hessian in DOF space. Most energies do not
//! implement it directly: they implement [`Potential`](super::potential::Potential), written in
//! world positions, and are wrapped in [`PotentialTerm`](super::potential::PotentialTerm), which
//! applies the kinematic map, derivatives and projection.

use crate::state::EvalState;
/// Padding value in a stencil: no DOF block (defined with the DOF layout in `state`).
pub use crate::state::NO_DOF;

/// Buffer layout of one element's output with `m` DOF blocks:
/// `[energy, gradient (3m), Hessian blocks (m·m blocks of 9, block (a, b) at 9(a·m + b), row-major)]`.
#[inline]
pub fn element_stride(m: usize) -> usize {
    1 + 3 * m + 9 * m * m
}

/// The number of DOF blocks `m` of an element buffer of length [`element_stride`]`(m)`.
#[inline]
pub fn width_of_stride(len: usize) -> usize {
    // 9m² + 3m + 1 = len
    let m = ((((36 * (len - 1) + 9) as f64).sqrt() - 3.0) / 18.0).round() as usize;
    debug_assert_eq!(element_stride(m), len);
    m
}

/// What the assembler asks of a term.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EvalMode {
    /// Value, gradient and Hessian projected to positive semi-definite per element.
    ProjectedHessian,
    /// Value, gradient and the exact Hessian (tests, and energies known to be convex).
    ExactHessian,
}

/// Result of a term's check of a converged step.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum StepCheck {
    /// Accept the step.
    Accept,
    /// Retry the same step (the term hardened a stiffness); the message says why.
    Retry(String),
}

/// A sum of element energies over DOF blocks, as the solver sees it.
pub trait EnergyTerm: Send + Sync {
    /// Name used in logs and errors.
    fn name(&self) -> &str;

    /// Number of elements.
    fn num_elements(&self) -> usize;

    /// DOF blocks per element (stencils are padded with [`NO_DOF`]). Elements on rigid bodies
    /// have more blocks than nodes (two per body), hence the state.
    fn stencil_width(&self, state: &EvalState) -> usize;

    /// Write the DOF blocks of every element (`num_elements × stencil_width`).
    fn write_stencils(&self, state: &EvalState, out: &mut [u32]);

    /// Changes whenever the set of elements or their DOF blocks change, so that the solver knows
    /// when to rebuild the sparsity pattern.
    fn topology_version(&self) -> u64 {
        0
    }

    /// Total energy at `state`.
    fn energy(&self, state: &EvalState) -> f64;

    /// Value, gradient and Hessian of element `e` in DOF space, in the layout of
    /// [`element_stride`] (`out` has that length; the gradient of a padding slot, whose stencil
    /// entry is `NO_DOF`, must be zero, its Hessian blocks are never read). Called in parallel
    /// for elements that share no DOF block.
    fn evaluate_element(&self, e: usize, state: &EvalState, mode: EvalMode, out: &mut [f64]);

    /// Called once before each time step (lagged quantities, e.g. friction, are set here).
    fn before_step(&mut self, _state: &EvalState) {}

    /// Called before every evaluation (contact updates its active set here).
    fn prepare_evaluation(&mut self, _state: &EvalState) {}

    /// Newton's globalisation: with `true`, a term whose exact Hessian is
    /// indefinite near its active set assembles a positive semi-definite form (contact
    /// barriers, far from the solution and where their exact Hessians made the total
    /// indefinite); with `false` (the default), its exact Hessian. The solver still projects
    /// every term when the total turns out indefinite with `true`. Returns whether the term
    /// assembles anything different now (it has such pairs), so that the solver retries only
    /// when a retry can help.
    fn use_definite_hessian(&mut self, _on: bool) -> bool {
        false
    }

    /// Newton's steps under the definite form were cut short again and again in this time step:
    /// a term whose definite form is a cheap approximation (contact's Gauss–Newton barrier
    /// Hessians) switches to its closer form (projected) until the next time step. Returns
    /// whether the term assembles anything different now.
    fn tighten_definite_form(&mut self) -> bool {
        false
    }

    /// Whether [`use_definite_hessian`](Self::use_definite_hessian) can change what this term
    /// assembles (it has such a form and elements to use it on).
    fn has_definite_form(&self) -> bool {
        false
    }

    /// Called when Newton accepts the iterate `to` (after the line search) coming from `from`:
    /// a term with auxiliary unknowns of its own updates them here (friction's dual
    /// variables, `contact::friction`).
    fn accept_iterate(&mut self, _from: &EvalState, _to: &EvalState) {}

    /// Keep what [`accept_iterate`](Self::accept_iterate) changes, for
    /// [`restore_iterate`](Self::restore_iterate): the line search accepts its first trial
    /// tentatively to assemble there (the next iteration's Hessian needs the accepted duals).
    fn save_iterate(&mut self) {}

    /// Undo the [`accept_iterate`](Self::accept_iterate) calls since
    /// [`save_iterate`](Self::save_iterate).
    fn restore_iterate(&mut self) {}

    /// Called once per step after the first assembly, with the total gradient (DOF space) at
    /// `state`: a term may re-scale itself to balance the others (contact raises its barrier
    /// stiffness to carry the load it is under). Returns whether it changed, so that the solver
    /// assembles again.
    fn rebalance(&mut self, _state: &EvalState, _gradient: &[f64]) -> bool {
        false
    }

    /// Largest fraction `α ∈ (0, 1]` of the step `state → state + Δ` that is valid (CCD).
    /// `trial` is the state at the full step.
    fn max_step_fraction(&mut self, _state: &EvalState, _trial: &EvalState) -> f64 {
        1.0
    }

    /// Whether a line-search trial state is admissible. CCD checks straight chords; points of
    /// rigid bodies move on arcs, so contact also tests trial states for intersections.
    fn is_valid_state(&mut self, _state: &EvalState) -> bool {
        true
    }

    /// Checked after Newton converged; may harden a stiffness and ask for a retry.
    fn check_converged_step(&mut self, _state: &EvalState) -> StepCheck {
        StepCheck::Accept
    }

    /// Called once a step is accepted.
    fn after_step(&mut self, _state: &EvalState) {}

    /// The term's mutable state — whatever the next step depends on that building the scene
    /// again does not recreate (hardened stiffnesses, targets, parameters changed at run time,
    /// adaptive stiffness) — as bytes for a checkpoint. The default, for terms without such
    /// state, is empty.
    fn save_state(&self) -> Vec<u8> {
        Vec::new()
    }

    /// Restore what [`save_state`](Self::save_state) returned, on a term built the same way
    /// (the error says what does not fit).
    fn restore_state(&mut self, _bytes: &[u8]) -> Result<(), String> {
        Ok(())
    }
}

/// Encode a term's state for [`EnergyTerm::save_state`] (postcard, like the checkpoint file).
pub fn encode_state<T: serde::Serialize + ?Sized>(state: &T) -> Vec<u8> {
    postcard::to_allocvec(state).expect("term state is serialisable")
}

/// Decode a term's state in [`EnergyTerm::restore_state`].
pub fn decode_state<T: serde::de::DeserializeOwned>(bytes: &[u8]) -> Result<T, String> {
    postcard::from_bytes(bytes).map_err(|e| format!("its saved state does not decode ({e})"))
}

/// Restore per-group parameters saved with [`encode_state`], checking the group count.
pub fn restore_vec<T>(into: &mut Vec<T>, from: Vec<T>, what: &str) -> Result<(), String> {
    if into.len() != from.len() {
        return Err(format!(
            "{} {what} saved, {} in the rebuilt scene",
            from.len(),
            into.len()
        ));
    }
    *into = from;
    Ok(())
}
