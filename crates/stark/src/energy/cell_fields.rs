//! Per-cell strain and stress measures that the strain energies report for output.

use nalgebra::Matrix3;

/// Strain and stress of one cell (tet or triangle).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellFields {
    /// Green strain `E = ½(FᵀF − I)` (for triangles the 2×2 rest-plane strain in the upper-left
    /// block), unitless.
    pub green_strain: Matrix3<f64>,
    /// Cauchy stress, Pa.
    pub cauchy_stress_pa: Matrix3<f64>,
    /// Von Mises stress `√(½((σ₁−σ₂)² + (σ₂−σ₃)² + (σ₃−σ₁)²))`, Pa.
    pub von_mises_pa: f64,
    /// Principal stresses, largest first, Pa.
    pub principal_stresses_pa: [f64; 3],
    /// The strain-limiting penalty acts on the cell.
    pub strain_limit_active: bool,
}

impl CellFields {
    /// The measures of a strain and a Cauchy stress.
    pub fn new(green_strain: Matrix3<f64>, cauchy_stress_pa: Matrix3<f64>, strain_limit_active: bool) -> Self {
        let sym = 0.5 * (cauchy_stress_pa + cauchy_stress_pa.transpose());
        let mut p: [f64; 3] = sym.symmetric_eigen().eigenvalues.into();
        p.sort_by(|a, b| b.total_cmp(a));
        let von_mises = (0.5 * ((p[0] - p[1]).powi(2) + (p[1] - p[2]).powi(2) + (p[2] - p[0]).powi(2))).sqrt();
        CellFields {
            green_strain,
            cauchy_stress_pa: sym,
            von_mises_pa: von_mises,
            principal_stresses_pa: p,
            strain_limit_active,
        }
    }
}
