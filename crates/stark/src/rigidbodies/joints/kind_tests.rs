//! Tests of [`JointKind`]: serde round trips, defaults, building every variant, errors and the
//! scene-format listing.

use super::*;
use crate::rigidbodies::joints::JointParams;
use crate::rigidbodies::RigidBodyHandle;
use crate::Settings;
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

/// One value of every variant, optional fields given (non-default) where it has them.
fn one_of_each() -> Vec<JointKind> {
    use JointKind::*;
    let (p, q, axis, axis2) = ([0.1, -0.2, 0.3], [0.4, 0.5, -0.6], [0.0, 0.6, 0.8], [1.0, 0.0, 0.0]);
    vec![
        Ball { point_m: p },
        BallCone {
            point_m: p,
            axis,
            limit_deg: 33.3,
        },
        Hinge { point_m: p, axis },
        HingeLimit {
            point_m: p,
            axis,
            limit_deg: 45.0,
        },
        HingeRange {
            point_m: p,
            axis,
            limits_deg: [-10.0, 20.5],
        },
        Universal {
            point_m: p,
            axis_a: axis,
            axis_b: axis2,
        },
        Slider { point_m: p, axis },
        Prismatic { point_m: p, axis },
        SliderRange {
            point_m: p,
            axis,
            limits_m: [-0.1, 0.2],
        },
        PointOnAxis { point_m: p, axis },
        Planar {
            point_m: p,
            normal: axis,
        },
        PrismaticPress {
            point_m: p,
            axis,
            target_velocity_m_s: -0.05,
            max_force_n: 20.0,
            delay_m_s: 0.002,
        },
        Motor {
            point_m: p,
            axis,
            target_velocity_deg_s: 90.0,
            max_torque_n_m: 1.5,
            delay_deg_s: Some(0.1),
        },
        HingeServo {
            point_m: p,
            axis,
            target_deg: 30.0,
            max_torque_n_m: 2.0,
            response_time_s: 0.1,
        },
        PrismaticServo {
            point_m: p,
            axis,
            target_m: 0.02,
            max_force_n: 10.0,
            response_time_s: 0.2,
        },
        Fix {},
        Attachment {},
        Distance {
            point_a_m: p,
            point_b_m: q,
        },
        DistanceLimits {
            point_a_m: p,
            point_b_m: q,
            min_m: 0.1,
            max_m: 2.0,
        },
        Spring {
            point_a_m: p,
            point_b_m: q,
            spring_stiffness_n_m: 100.0,
            damping_n_s_m: 1.5,
            limits_m: Some([0.1, 2.0]),
        },
        Direction { axis },
        AngleLimit { axis, limit_deg: 10.0 },
        LinearVelocity {
            point_m: p,
            axis,
            target_velocity_m_s: 0.3,
            max_force_n: 5.0,
            delay_m_s: 0.02,
        },
        AngularVelocity {
            axis,
            target_velocity_deg_s: -45.0,
            max_torque_n_m: 2.0,
            delay_deg_s: None,
        },
        JointCoupling {
            joint_a: "hinge".into(),
            joint_b: "slider".into(),
            multiplier: -0.5,
            offset: 0.01,
        },
        JointSpring {
            joint: "hinge".into(),
            spring_stiffness: 3.0,
            rest: 0.2,
            damping: 0.1,
        },
    ]
}

#[test]
fn every_variant_survives_a_serde_round_trip_through_json_and_toml() {
    let kinds = one_of_each();
    // The list has every type once.
    let mut names: Vec<String> = kinds.iter().map(JointKind::type_name).collect();
    names.sort();
    let mut all = JointKind::type_names();
    all.sort();
    assert_eq!(names, all);
    assert_eq!(all.len(), 26);
    for kind in kinds {
        let json = serde_json::to_string(&kind).unwrap();
        assert_eq!(serde_json::from_str::<JointKind>(&json).unwrap(), kind, "{json}");
        let toml = toml::to_string(&kind).unwrap();
        assert_eq!(toml::from_str::<JointKind>(&toml).unwrap(), kind, "{toml}");
    }
}

#[test]
fn optional_fields_take_their_documented_defaults() {
    let kind: JointKind =
        toml::from_str("type = \"motor\"\npoint_m = [0, 0, 0]\naxis = [0, 0, 1]\nmax_torque_n_m = 1").unwrap();
    let expected = JointKind::Motor {
        point_m: [0.0; 3],
        axis: [0.0, 0.0, 1.0],
        target_velocity_deg_s: 0.0,
        max_torque_n_m: 1.0,
        delay_deg_s: None,
    };
    assert_eq!(kind, expected);
    let kind: JointKind = serde_json::from_str(
        r#"{"type": "linear_velocity", "point_m": [0, 0, 0], "axis": [1, 0, 0], "max_force_n": 2}"#,
    )
    .unwrap();
    assert!(
        matches!(kind, JointKind::LinearVelocity { delay_m_s, target_velocity_m_s, .. }
        if delay_m_s == DEFAULT_CONTROLLER_DELAY && target_velocity_m_s == 0.0)
    );
    let kind: JointKind =
        serde_json::from_str(r#"{"type": "joint_coupling", "joint_a": "x", "joint_b": "y"}"#).unwrap();
    assert!(matches!(kind, JointKind::JointCoupling { multiplier, offset, .. } if multiplier == 1.0 && offset == 0.0));
    // Unknown fields are errors that list the type's fields.
    let e =
        serde_json::from_str::<JointKind>(r#"{"type": "hinge", "point_m": [0, 0, 0], "axis": [0, 0, 1], "limit": 3}"#)
            .unwrap_err()
            .to_string();
    assert!(e.contains("unknown field `limit`, expected `point_m` or `axis`"), "{e}");
    assert_eq!(JointKind::fields_of("fix"), Some(vec![]));
    assert_eq!(
        JointKind::fields_of("spring").unwrap(),
        [
            "point_a_m",
            "point_b_m",
            "spring_stiffness_n_m",
            "damping_n_s_m",
            "limits_m"
        ]
    );
    assert_eq!(JointKind::fields_of("hing"), None);
}

fn two_bodies() -> (Simulation, RigidBodyHandle, RigidBodyHandle) {
    let mut s = Settings::default();
    s.output.frames = false;
    s.output.step_log = false;
    let mut sim = Simulation::new(s).unwrap();
    let q = UnitQuaternion::identity();
    let a = sim
        .add_rigid_body("a", 1.0, Matrix3::identity(), Vector3::zeros(), q)
        .unwrap();
    let b = sim
        .add_rigid_body("b", 1.0, Matrix3::identity(), Vector3::new(0.0, 0.0, -0.5), q)
        .unwrap();
    (sim, a, b)
}

#[test]
fn every_variant_builds_through_add_joint_and_registers_its_label() {
    let (mut sim, a, b) = two_bodies();
    let p = JointParams::default();
    for kind in one_of_each() {
        let label = kind.type_name();
        // The couplings name the hinge and the slider built before them.
        let label = match &kind {
            JointKind::Hinge { .. } => "hinge".to_string(),
            JointKind::Slider { .. } => "slider".to_string(),
            _ => label,
        };
        let (ja, jb) = match kind {
            JointKind::JointCoupling { .. } | JointKind::JointSpring { .. } => (None, None),
            JointKind::Fix {} => (None, Some(b)),
            _ => (Some(a), Some(b)),
        };
        let h = sim
            .add_joint(&label, ja, jb, kind, p)
            .unwrap_or_else(|e| panic!("{label}: {e}"));
        assert_eq!(sim.joint_by_label(&label).unwrap(), h);
    }
    assert_eq!(sim.rigid_bodies.named_joints.len(), 26);
    // The couplings' elements act between the bodies of their joints.
    let coupling = sim.joint_by_label("joint_coupling").unwrap();
    let e = &sim.rigid_bodies.joints.potential.elements[coupling.elements[0] as usize];
    assert_eq!(e.bodies, [Some(0), Some(1)]);
}

#[test]
fn errors_name_the_joint_and_the_field() {
    let (mut sim, a, b) = two_bodies();
    let p = JointParams::default();
    let err = |sim: &mut Simulation, a, b, kind| sim.add_joint("j", a, b, kind, p).unwrap_err().to_string();
    let hinge = JointKind::Hinge {
        point_m: [0.0; 3],
        axis: [0.0, 0.0, 0.0],
    };
    let e = err(&mut sim, Some(a), Some(b), hinge.clone());
    assert_eq!(e, "joint 'j': `axis` = [0.0, 0.0, 0.0] must be finite and non-zero");
    let e = err(&mut sim, Some(a), None, hinge);
    assert!(e.contains("joint 'j': `b` must be a rigid body"), "{e}");
    let e = err(&mut sim, Some(a), Some(b), JointKind::Fix {});
    assert!(
        e.contains("joint 'j': a fix joint holds body b in the world: `a` must be the world"),
        "{e}"
    );
    let motor = JointKind::Motor {
        point_m: [0.0; 3],
        axis: [0.0, 0.0, 1.0],
        target_velocity_deg_s: 0.0,
        max_torque_n_m: -1.0,
        delay_deg_s: None,
    };
    let e = err(&mut sim, None, Some(b), motor);
    assert!(e.contains("`max_torque_n_m` = -1 on 'j'"), "{e}");
    let spring = JointKind::JointSpring {
        joint: "pivot".into(),
        spring_stiffness: 1.0,
        rest: 0.0,
        damping: 0.0,
    };
    let e = err(&mut sim, Some(a), None, spring.clone());
    assert!(e.contains("`a` and `b` must be None"), "{e}");
    let e = err(&mut sim, None, None, spring.clone());
    assert!(
        e.contains("joint 'j': `joint`: no joint is labelled 'pivot'; the joints are none yet"),
        "{e}"
    );
    sim.add_ball_joint("ball", None, b, Vector3::zeros(), p).unwrap();
    let e = err(&mut sim, None, None, spring);
    assert!(e.contains("the joints are 'ball'"), "{e}");
    let spring = JointKind::JointSpring {
        joint: "ball".into(),
        spring_stiffness: 1.0,
        rest: 0.0,
        damping: 0.0,
    };
    let e = err(&mut sim, None, None, spring);
    assert!(e.contains("`joint` = 'ball' has no coordinate"), "{e}");
    // Nothing was added by the failed calls.
    assert_eq!(sim.rigid_bodies.named_joints.len(), 1);
    assert_eq!(sim.rigid_bodies.joints.potential.elements.len(), 1);
}

/// docs/scene-format.md lists every joint type with exactly the fields of its variant.
#[test]
fn the_scene_format_lists_every_type_with_its_fields() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/scene-format.md");
    let doc = std::fs::read_to_string(path).unwrap();
    let section = doc.split("\n## `[[joint]]`").nth(1).unwrap();
    let section = section.split("\n## ").next().unwrap();
    let types = JointKind::type_names();
    let mut listed = Vec::new();
    for line in section.lines() {
        // `| type | required | optional | call |`: cells 1 to 4.
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        if cells.len() < 5 {
            continue;
        }
        let cells = &cells[1..];
        let Some(t) = cells[0].strip_prefix('`').and_then(|c| c.strip_suffix('`')) else {
            continue;
        };
        if !types.iter().any(|x| x == t) {
            continue;
        }
        let fields = JointKind::fields_of(t).unwrap();
        let named: Vec<String> = cells[1..3]
            .iter()
            .flat_map(|c| c.split('`').skip(1).step_by(2))
            .map(|f| f.split(' ').next().unwrap_or_default().to_string())
            .filter(|f| f != "a" && f != "b")
            .collect();
        for f in &fields {
            assert!(named.contains(f), "docs: `{t}` does not list its field `{f}`");
        }
        for f in &named {
            assert!(fields.contains(f), "docs: `{t}` lists `{f}`, which it does not take");
        }
        listed.push(t.to_string());
    }
    assert_eq!(
        listed, types,
        "docs: the types table lists other types or another order"
    );
}
