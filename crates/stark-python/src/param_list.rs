//! The model parameter classes of the module, in the order of the type stubs: the one list the
//! extension (`params.rs` defines a class per entry) and the stub generator
//! (`stark-codegen/src/bin/gen_stubs.rs`, which includes this file) share. The fields and their
//! docs come from the library's tables (`stark::params`).

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
