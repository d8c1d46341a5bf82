//! Linear solvers for the Newton system `H Δv = −∇E`.

// The matrix type lives in energy (assembly fills it; energy sits below solver);
// re-exported here so `solver::linear::block_sparse` keeps working.
pub use crate::energy::block_sparse;
pub mod amg;
pub mod cholesky;
pub mod pcg;
pub mod supernodal;

pub use block_sparse::BlockSparseMatrix;
