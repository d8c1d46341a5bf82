//! Contact forces for reports: the barrier forces at a state, and the forces a solve balanced.

use super::pairs::{pair_derivatives, ContactPair};
use super::Contact;
use super::PairHessian;
use crate::energy::term::NO_DOF;
use crate::energy::{HyperDual, Scalar};
use nalgebra::Vector3;
use rayon::prelude::*;

impl Contact {
    /// The barrier (normal contact) force on every node at positions `x`, N: minus the gradient
    /// of the barrier energy of the pairs active at `x` (current stiffness κ). Summed over the
    /// mesh nodes of a rigid body it is the contact force on the body (its moment about the
    /// centre of mass the contact torque); summed over an object, the load it carries. Friction
    /// is not included.
    pub fn barrier_forces(&mut self, x: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        let mut forces = vec![Vector3::zeros(); x.len()];
        let pairs = self.detect(x);
        self.add_barrier_forces(&pairs, x, &mut forces);
        forces
    }

    /// Add minus the barrier gradient of `pairs` at `x` to `forces`.
    fn add_barrier_forces(&self, pairs: &[ContactPair], x: &[Vector3<f64>], forces: &mut [Vector3<f64>]) {
        // The pairs' gradients in parallel, added in the pairs' order.
        let gradients: Vec<[[f64; 3]; 4]> = pairs
            .par_iter()
            .with_min_len(256)
            .map_init(
                || HyperDual::<4>::constant(0.0),
                |d, p| {
                    pair_derivatives(
                        p,
                        &Self::stencil_x(&p.nodes, x),
                        p.kappa * p.multiplicity,
                        self.settings.barrier,
                        PairHessian::GaussNewton,
                        d,
                    );
                    d.grad
                },
            )
            .collect();
        scatter_forces(pairs.iter().map(|p| &p.nodes[..]), &gradients, forces);
    }

    /// The contact forces of the last solve on every node at positions `x` (the converged
    /// state, right after a step), N: the normal (barrier) forces of the pairs active at the last
    /// evaluation, and the friction forces of the step's lagged friction elements. These are the
    /// forces the step balanced: summed over a rigid body's mesh nodes, the contact force on the
    /// body. Unlike [`Contact::barrier_forces`] nothing is detected anew.
    pub fn solve_forces(&self, x: &[Vector3<f64>]) -> (Vec<Vector3<f64>>, Vec<Vector3<f64>>) {
        let mut normal = vec![Vector3::zeros(); x.len()];
        let mut friction = vec![Vector3::zeros(); x.len()];
        self.add_barrier_forces(&self.pairs, x, &mut normal);
        let gradients: Vec<[[f64; 3]; 4]> = self
            .friction_elements
            .par_iter()
            .with_min_len(256)
            .map_init(
                || HyperDual::<4>::constant(0.0),
                |d, f| {
                    f.derivatives(&Self::stencil_x(&f.nodes, x), d);
                    d.grad
                },
            )
            .collect();
        scatter_forces(
            self.friction_elements.iter().map(|f| &f.nodes[..f.len]),
            &gradients,
            &mut friction,
        );
        (normal, friction)
    }
}

/// `forces[node] -= gradient` for each element's nodes (in the elements' order: the same sums
/// at any thread count).
fn scatter_forces<'a>(
    stencils: impl Iterator<Item = &'a [u32]>,
    gradients: &[[[f64; 3]; 4]],
    forces: &mut [Vector3<f64>],
) {
    for (nodes, grad) in stencils.zip(gradients) {
        for (&i, g) in nodes.iter().zip(grad) {
            if i != NO_DOF {
                forces[i as usize] -= Vector3::from(*g);
            }
        }
    }
}
