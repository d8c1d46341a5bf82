//! Energies and their derivatives: the scalar abstraction, hyper-dual and symbolic
//! differentiation, the kinematic map from world positions to DOFs, PSD projection and assembly.

pub mod assembly;
pub mod block_sparse;
pub mod cell_fields;
pub mod deformation;
pub mod dual;
pub mod jit;
pub mod kinematics;
pub mod potential;
pub mod psd;
pub mod scalar;
pub mod symbolic;
pub mod tensor;
pub mod term;
pub mod testing;
pub mod user_energy;

pub use dual::HyperDual;
pub use potential::{run_kernel, FastDerivatives, Kernel, Node, Potential, PotentialTerm, Stencil};
pub use scalar::Scalar;
pub use tensor::{flat_from_points, points_from_flat, Mat, Mat2, Mat3, Mat32, Vec3};
pub use term::{decode_state, encode_state, restore_vec, EnergyTerm, EvalMode, StepCheck};
pub use user_energy::{trace_element, ElementArgs, UserEnergy, UserEnergyTerm};
