//! Physics verification: each file states one claim checked against an analytic answer or an
//! invariant (DESIGN §7). One test binary, one module per claim (in `physics/`).

#[path = "physics/mod.rs"]
mod claims;
