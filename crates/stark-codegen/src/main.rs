//! Regenerates `crates/stark/src/generated/kernels.rs`, the derivative kernels of the built-in
//! energies. Run after changing an energy: `cargo run -p stark-codegen`.

use std::path::PathBuf;

fn main() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../stark/src/generated/kernels.rs");
    let start = std::time::Instant::now();
    let source = stark::generated::generate_source();
    std::fs::write(&path, &source).unwrap_or_else(|e| panic!("cannot write {}: {e}", path.display()));
    println!(
        "wrote {} ({} kernels, {} lines) in {:.2} s",
        path.display(),
        stark::generated::specs().len(),
        source.lines().count(),
        start.elapsed().as_secs_f64()
    );
}
