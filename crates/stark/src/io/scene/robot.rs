//! `[[robot]]` entries of scene files: a URDF robot through [`Simulation::add_robot`].

use super::errors::{At, Ctx, Res};
use super::geometry::{finite, orientation, Rotate};
use crate::robots::{JointOverride, LinkOverride, Robot, RobotOptions};
use crate::simulation::Simulation;
use nalgebra::UnitQuaternion;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RobotEntry {
    pub(super) name: String,
    urdf: String,
    #[serde(default)]
    package_paths: Vec<String>,
    position_m: Option<[f64; 3]>,
    rotate_deg: Option<Rotate>,
    quaternion_wxyz: Option<[f64; 4]>,
    #[serde(default)]
    fixed_base: bool,
    merge_fixed_joints: Option<bool>,
    #[serde(default)]
    visual_meshes: bool,
    contact_thickness_m: Option<f64>,
    adjacent_links_collide: Option<bool>,
    self_collision: Option<bool>,
    #[serde(default)]
    links: BTreeMap<String, LinkOverride>,
    #[serde(default)]
    joints: BTreeMap<String, JointOverride>,
}

/// Build a `[[robot]]`: the URDF file and package paths are relative to the scene file.
pub(super) fn build_robot(sim: &mut Simulation, ctx: &Ctx, base_dir: &Path, at: &At, e: &RobotEntry) -> Res<Robot> {
    let defaults = RobotOptions::default();
    let mut links = e.links.clone();
    for o in links.values_mut() {
        if let Some(m) = &o.collision_mesh {
            o.collision_mesh = Some(base_dir.join(m));
        }
    }
    let options = RobotOptions {
        package_paths: e.package_paths.iter().map(|p| base_dir.join(p)).collect(),
        position_m: finite(ctx, at, "position_m", e.position_m.unwrap_or([0.0; 3]))?,
        orientation: orientation(ctx, at, e.rotate_deg.as_ref(), e.quaternion_wxyz)?
            .unwrap_or_else(UnitQuaternion::identity),
        fixed_base: e.fixed_base,
        merge_fixed_joints: e.merge_fixed_joints.unwrap_or(defaults.merge_fixed_joints),
        visual_meshes: e.visual_meshes,
        contact_thickness_m: e.contact_thickness_m,
        adjacent_links_collide: e.adjacent_links_collide.unwrap_or(defaults.adjacent_links_collide),
        self_collision: e.self_collision.unwrap_or(defaults.self_collision),
        links,
        joints: e.joints.clone(),
        ..defaults
    };
    sim.add_robot(&e.name, base_dir.join(&e.urdf), &options).map_err(|err| {
        let message = err.to_string();
        // An override of a link or joint the file does not have: point at the override.
        let key = |kind: &str| {
            message
                .split_once(&format!("an override names the {kind} '"))
                .and_then(|(_, rest)| rest.split_once('\''))
                .map(|(name, _)| name.to_string())
        };
        let place = match (key("link"), key("joint")) {
            (Some(l), _) => at.keys(&["links", l.as_str()]),
            (None, Some(j)) => at.keys(&["joints", j.as_str()]),
            _ => at.key("urdf"),
        };
        ctx.err(&place, message)
    })
}

#[cfg(test)]
mod tests {
    use crate::error::StarkError;
    use crate::io::scene::{load_scene_with, parse_scene};
    use std::path::Path;

    fn scenes() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
    }

    #[test]
    fn the_franka_box_scene_builds_its_robot_as_objects_and_joints() {
        let scene = load_scene_with(&scenes().join("franka_box.toml"), |s| {
            s.output.frames = false;
            s.output.step_log = false;
        })
        .unwrap();
        let robot = &scene.robots[0];
        assert_eq!(robot.bodies.len(), 3);
        // Links with collision meshes are objects friction can name; the joints are listed.
        for link in ["fr3_hand", "fr3_leftfinger", "fr3_rightfinger"] {
            assert!(scene.rigid_body(&format!("franka/{link}")).is_some(), "{link}");
        }
        assert!(scene.joint("franka/fr3_finger_joint2.mimic").is_some());
        assert!((robot.joint_position(&scene.simulation, "fr3_finger_joint1").unwrap() - 0.035).abs() < 1e-15);
    }

    #[test]
    fn robot_errors_name_the_scene_line_and_the_urdf_element() {
        let dir = scenes();
        let text = |extra: &str| {
            format!(
                "duration_s = 1.0\n[[robot]]\nname = \"franka\"\nurdf = \"../../shared/data/robots/franka_description/urdf/franka_hand.urdf\"\npackage_paths = [\"../../shared/data/robots\"]\n{extra}"
            )
        };
        let err = |t: &str| match parse_scene(t, "test.toml", &dir) {
            Err(StarkError::SceneFile(e)) => e.to_string(),
            Err(e) => panic!("not a scene error: {e}"),
            Ok(_) => panic!("accepted"),
        };
        let e = err(&text("[robot.links.no_such_link]\nmass_kg = 1.0\n"));
        assert!(
            e.starts_with("test.toml:6:") && e.contains("link 'no_such_link'"),
            "{e}"
        );
        let e = err(&text(
            "[robot.joints.fr3_finger_joint1]\nactuator = { type = \"motor\", target_rad_s = 1.0 }\n",
        ));
        assert!(e.contains("does not fit") && e.contains("fr3_finger_joint1"), "{e}");
        let e = err(&text("[robot.joints.fr3_finger_joint1]\npositon = 0.01\n"));
        assert!(
            e.starts_with("test.toml:7:") && e.contains("unknown field `positon`"),
            "{e}"
        );
        let e = err("duration_s = 1.0\n[[robot]]\nname = \"r\"\nurdf = \"missing.urdf\"\n");
        assert!(e.starts_with("test.toml:4:") && e.contains("missing.urdf"), "{e}");
    }
}
