//! Linear solvers for the Newton system `H Δv = −∇E`.

pub mod block_sparse;
pub mod cholesky;
pub mod pcg;

pub use block_sparse::BlockSparseMatrix;
