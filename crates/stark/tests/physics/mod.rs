//! The physics claims, one per file.

pub mod cantilever_matches_linear_elasticity;
