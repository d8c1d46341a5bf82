//! The stress written with the frames matches linear elasticity in uniaxial tension.
//!
//! A block (tets) is put into the homogeneous uniaxial-stress state of linear elasticity,
//! `x = (X(1+ε), Y(1−νε), Z(1−νε))` with ε = 1e-3: then `σ_xx = E ε`, the other stresses vanish
//! and von Mises equals `σ_xx`, to O(ε) relative (the Stable Neo-Hookean model reduces to linear
//! elasticity with the same E and ν at small strain). The same for a membrane in plane stress,
//! `x = (X(1+ε), Y(1−νε), 0)`. Measured: σ_xx within 0.2% of `E ε` in every cell, lateral
//! stresses below 0.2% of it, the largest principal Green strain `ε + ε²/2`.

use nalgebra::Vector3;
use stark::presets::{SurfaceMaterial, VolumeMaterial};
use stark::{Settings, Simulation};

const EPS: f64 = 1e-3;

fn check(fields: &[stark::io::fields::CellFields], e_pa: f64, what: &str) {
    assert!(!fields.is_empty());
    let expected = e_pa * EPS;
    for f in fields {
        let s = f.cauchy_stress_pa;
        assert!(
            (s[(0, 0)] / expected - 1.0).abs() < 2e-3,
            "{what}: σ_xx {} vs E ε {expected}",
            s[(0, 0)]
        );
        for (i, j) in [(1, 1), (2, 2), (0, 1), (1, 2), (0, 2)] {
            assert!(s[(i, j)].abs() < 2e-3 * expected, "{what}: σ[{i}{j}] = {}", s[(i, j)]);
        }
        assert!(
            (f.von_mises_pa / expected - 1.0).abs() < 2e-3,
            "{what}: von Mises {}",
            f.von_mises_pa
        );
        assert!((f.principal_stresses_pa[0] / expected - 1.0).abs() < 2e-3);
        // The largest principal Green strain (triangles give theirs in rest-plane axes).
        let e_max = f.green_strain.symmetric_eigen().eigenvalues.max();
        assert!(
            (e_max - (EPS + 0.5 * EPS * EPS)).abs() < 1e-12,
            "{what}: E_max = {e_max}"
        );
        assert!(!f.strain_limit_active);
    }
}

#[test]
fn stress_fields_match_uniaxial_tension() {
    let mut sim = Simulation::new(Settings::default()).unwrap();
    let volume = VolumeMaterial::soft_rubber();
    let (e, nu) = (volume.strain.youngs_modulus, volume.strain.poissons_ratio);
    let block = sim
        .add_volume_grid("block", [0.2, 0.1, 0.1], [4, 2, 2], &volume)
        .unwrap();
    let surface = SurfaceMaterial::cotton_fabric();
    let (es, nus) = (surface.strain.youngs_modulus, surface.strain.poissons_ratio);
    let sheet = sim.add_surface_grid("sheet", [0.2, 0.1], [4, 2], &surface).unwrap();
    for i in block.nodes.range() {
        let r = sim.nodes.rest[i];
        sim.nodes.x[i] = Vector3::new(r.x * (1.0 + EPS), r.y * (1.0 - nu * EPS), r.z * (1.0 - nu * EPS));
    }
    for i in sheet.nodes.range() {
        let r = sim.nodes.rest[i];
        sim.nodes.x[i] = Vector3::new(r.x * (1.0 + EPS), r.y * (1.0 - nus * EPS), r.z);
    }
    let tets = sim
        .deformables
        .tets
        .potential
        .cell_fields("block", &sim.nodes.x)
        .unwrap();
    assert_eq!(tets.len(), 16 * 12, "12 tets per grid cell");
    check(&tets, e, "tets");
    let tris = sim
        .deformables
        .triangles
        .potential
        .cell_fields("sheet", &sim.nodes.x)
        .unwrap();
    assert_eq!(tris.len(), 4 * 2 * 2);
    check(&tris, es, "triangles");
    assert!(sim
        .deformables
        .tets
        .potential
        .cell_fields("nothing", &sim.nodes.x)
        .is_none());
}
