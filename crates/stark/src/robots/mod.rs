//! Robots described in URDF, imported onto the typed descriptions of the library: links become
//! rigid bodies ([`Shape`](crate::rigidbodies::Shape) collision meshes and mass properties),
//! joints become the library's joints, mimic tags the joint coupling energy, and actuators are
//! attached by joint name ([`Simulation::add_robot`](crate::Simulation::add_robot)).

pub mod urdf;

pub use urdf::{Actuator, JointOverride, LinkOverride, Robot, RobotOptions, PACKAGE_PATH_ENV};
