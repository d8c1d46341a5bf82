//! Material presets with the original Stark's values (`deformables_preset_types.cpp`), and the
//! bundles of energy parameters that make up a line, a surface or a volume.

use crate::deformables::{
    DihedralBendingParams, FlatBendingParams, InertiaParams, SegmentStrainParams, TetStrainParams, TriangleStrainParams,
};
use serde::{Deserialize, Serialize};

/// Bending model of a surface.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Bending {
    /// No bending stiffness.
    None,
    /// Quadratic bending towards the flat state (cloth; Bergou et al. 2006).
    Flat(FlatBendingParams),
    /// Discrete-shell bending towards the rest dihedral angles (curved shells).
    Dihedral(DihedralBendingParams),
}

crate::params::documented_struct! {
    /// Material of a rod or cable made of segments.
    #[derive(Clone, Debug, PartialEq, Serialize, Deserialize, Default)]
    #[serde(default, deny_unknown_fields)]
    pub struct LineMaterial {
        /// Inertia (density in kg/m).
        pub inertia: InertiaParams,
        /// Axial strain.
        pub strain: SegmentStrainParams,
        /// Contact thickness, m; `None` uses `settings.contact.default_thickness_m` (default: none).
        pub contact_thickness_m: Option<f64>,
    }
}

crate::params::documented_struct! {
    /// Material of a shell or cloth made of triangles.
    #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct SurfaceMaterial {
        /// Inertia (density in kg/m²).
        pub inertia: InertiaParams,
        /// Membrane strain.
        pub strain: TriangleStrainParams,
        /// Bending: none, flat (cloth, towards the flat state) or dihedral (curved shells, towards
        /// the rest shape) (default: flat).
        pub bending: Bending,
        /// Contact thickness, m; `None` uses `settings.contact.default_thickness_m` (default: none).
        pub contact_thickness_m: Option<f64>,
    }
}

crate::params::documented_struct! {
    /// Material of a volumetric solid made of tetrahedra.
    #[derive(Clone, Debug, PartialEq, Serialize, Deserialize, Default)]
    #[serde(default, deny_unknown_fields)]
    pub struct VolumeMaterial {
        /// Inertia (density in kg/m³).
        pub inertia: InertiaParams,
        /// Volumetric strain.
        pub strain: TetStrainParams,
        /// Contact thickness, m; `None` uses `settings.contact.default_thickness_m` (default: none).
        pub contact_thickness_m: Option<f64>,
    }
}

impl Default for SurfaceMaterial {
    fn default() -> Self {
        SurfaceMaterial {
            inertia: InertiaParams::default(),
            strain: TriangleStrainParams::default(),
            bending: Bending::Flat(FlatBendingParams::default()),
            contact_thickness_m: None,
        }
    }
}

impl LineMaterial {
    /// Elastic rubber band: 0.05 kg/m, r = 2 mm, E = 1e4 Pa, strain limit 10% (k = 1e5 Pa),
    /// damping 1e-4 Pa·s, inertial damping 0.1/s.
    pub fn elastic_rubber_band() -> Self {
        LineMaterial {
            inertia: InertiaParams {
                density: 0.05,
                damping: 0.1,
                quasistatic: false,
            },
            strain: SegmentStrainParams {
                section_radius_m: 0.002,
                youngs_modulus: 1e4,
                damping: 1e-4,
                strain_limit: 0.1,
                strain_limit_stiffness: 1e5,
                scale: 1.0,
            },
            contact_thickness_m: None,
        }
    }
}

impl SurfaceMaterial {
    /// Cotton fabric: 0.2 kg/m², 1 mm thick, E = 5e3 Pa, ν = 0.3, strain limit 10%
    /// (k = 1e6 Pa), strain damping 0.1·thickness·E = 0.5 Pa·s, flat bending 1e-6 N·m with damping
    /// 1e-7 N·m·s, inertial damping 0.1/s.
    pub fn cotton_fabric() -> Self {
        let thickness = 0.001;
        let e = 5e3;
        SurfaceMaterial {
            inertia: InertiaParams {
                density: 0.2,
                damping: 0.1,
                quasistatic: false,
            },
            strain: TriangleStrainParams {
                thickness_m: thickness,
                youngs_modulus: e,
                poissons_ratio: 0.3,
                damping: 0.1 * thickness * e,
                strain_limit: 0.1,
                strain_limit_stiffness: 1e6,
                inflation_pa: 0.0,
                scale: 1.0,
            },
            bending: Bending::Flat(FlatBendingParams {
                stiffness: 1e-6,
                damping: 1e-7,
            }),
            contact_thickness_m: None,
        }
    }
}

impl VolumeMaterial {
    /// Soft rubber: 1000 kg/m³, E = 1e4 Pa, ν = 0.3, strain limit 100% (k = 100 Pa), inertial
    /// damping 0.1/s.
    pub fn soft_rubber() -> Self {
        VolumeMaterial {
            inertia: InertiaParams {
                density: 1000.0,
                damping: 0.1,
                quasistatic: false,
            },
            strain: TetStrainParams {
                youngs_modulus: 1e4,
                poissons_ratio: 0.3,
                damping: 0.0,
                strain_limit: 1.0,
                strain_limit_stiffness: 1e2,
                scale: 1.0,
            },
            contact_thickness_m: None,
        }
    }
}
