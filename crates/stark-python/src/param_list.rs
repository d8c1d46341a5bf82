//! The settings, model parameter and material classes of the module, in the order of the type
//! stubs: the lists the extension (`params.rs`) and the stub generator
//! (`stark-codegen/src/bin/gen_stubs.rs`, which includes this file) share. The fields' docs come
//! from the library's tables (`stark::params`).

/// Calls `$m! { PythonName => RustStruct, ... }` with every parameter class.
macro_rules! param_classes {
    ($m:ident) => {
        $m! {
            InertiaParams => stark::deformables::InertiaParams,
            TriangleStrainParams => stark::deformables::TriangleStrainParams,
            TetStrainParams => stark::deformables::TetStrainParams,
            SegmentStrainParams => stark::deformables::SegmentStrainParams,
            FlatBendingParams => stark::deformables::FlatBendingParams,
            DihedralBendingParams => stark::deformables::DihedralBendingParams,
            PrescribedParams => stark::deformables::PrescribedParams,
            AttachmentParams => stark::deformables::AttachmentParams,
            RigidBodyParams => stark::rigidbodies::RigidBodyParams,
            JointParams => stark::rigidbodies::joints::JointParams,
        }
    };
}
pub(crate) use param_classes;

/// Calls `$m! { PythonName => RustStruct, ... }` with every settings class (mirror classes
/// whose docs come from the library's `Documented` tables).
macro_rules! settings_classes {
    ($m:ident) => {
        $m! {
            Settings => stark::Settings,
            NewtonSettings => stark::settings::NewtonSettings,
            OutputSettings => stark::settings::OutputSettings,
            ContactSettings => stark::contact::ContactSettings,
        }
    };
}
pub(crate) use settings_classes;

/// Calls `$m! { PythonName => RustStruct, ... }` with every material class (mirror classes
/// whose docs come from the library's `Documented` tables).
macro_rules! material_classes {
    ($m:ident) => {
        $m! {
            LineMaterial => stark::presets::LineMaterial,
            VolumeMaterial => stark::presets::VolumeMaterial,
            SurfaceMaterial => stark::presets::SurfaceMaterial,
        }
    };
}
pub(crate) use material_classes;
