//! Broken URDF files give an error naming the file, the line and the element, never a panic, and
//! leave the simulation unchanged.

use stark::robots::RobotOptions;
use stark::{Settings, Simulation};

const GOOD_LINK: &str =
    r#"<inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>"#;

fn robot(body: &str) -> String {
    format!("<?xml version=\"1.0\"?>\n<robot name=\"r\">\n{body}\n</robot>\n")
}

fn link(name: &str) -> String {
    format!("  <link name=\"{name}\">{GOOD_LINK}</link>")
}

fn joint(name: &str, kind: &str, parent: &str, child: &str) -> String {
    format!(
        "  <joint name=\"{name}\" type=\"{kind}\"><parent link=\"{parent}\"/><child link=\"{child}\"/><axis xyz=\"0 0 1\"/></joint>"
    )
}

/// 1-based line of the first line of `text` containing `marker`.
fn line_of(text: &str, marker: &str) -> usize {
    text.lines().position(|l| l.contains(marker)).expect("marker") + 1
}

#[test]
fn broken_urdf_files_name_file_line_and_element() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("pkg_here/meshes")).unwrap();
    let mesh_link = |uri: &str| {
        format!(
            "  <link name=\"a\">{GOOD_LINK}\n    <collision><geometry><mesh filename=\"{uri}\"/></geometry></collision>\n  </link>"
        )
    };
    let cases: Vec<(&str, String, &str, Vec<&str>)> = vec![
        (
            "missing mesh",
            robot(&mesh_link("meshes/none.stl")),
            "<collision>",
            vec!["link 'a' <collision> mesh", "none.stl", "not found"],
        ),
        (
            "unknown package",
            robot(&mesh_link("package://nopkg/meshes/x.stl")),
            "<collision>",
            vec!["link 'a' <collision>", "unknown package 'nopkg'"],
        ),
        (
            "unknown joint type",
            robot(&[link("a"), link("b"), joint("j", "hinge", "a", "b")].join("\n")),
            "joint name",
            vec!["joint 'j'", "unknown joint type 'hinge'"],
        ),
        (
            "joint naming a missing link",
            robot(&[link("a"), joint("j", "revolute", "a", "ghost")].join("\n")),
            "joint name",
            vec!["joint 'j'", "its child link 'ghost' does not exist"],
        ),
        (
            "two roots",
            robot(&[link("a"), link("b")].join("\n")),
            "link name=\"b\"",
            vec!["2 root links (a, b)"],
        ),
        (
            "a cycle",
            robot(
                &[
                    link("a"),
                    link("b"),
                    joint("j1", "fixed", "a", "b"),
                    joint("j2", "fixed", "b", "a"),
                ]
                .join("\n"),
            ),
            "",
            vec!["form a cycle"],
        ),
        (
            "duplicate link names",
            robot(&[link("a"), link("a")].join("\n")),
            "",
            vec!["link 'a'", "duplicate link name"],
        ),
        (
            "inertia not positive definite",
            robot(
                r#"  <link name="a"><inertial><mass value="1"/><inertia ixx="-0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>"#,
            ),
            "link name",
            vec!["link 'a'", "not positive definite"],
        ),
        (
            "inertia breaking the triangle inequality",
            robot(
                r#"  <link name="a"><inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.3"/></inertial></link>"#,
            ),
            "link name",
            vec!["link 'a'", "triangle inequality"],
        ),
        (
            "non-finite number",
            robot(
                &[
                    link("a"),
                    link("b"),
                    joint("j", "revolute", "a", "b").replace("<axis xyz=\"0 0 1\"/>", "<origin xyz=\"0 nan 0\"/>"),
                ]
                .join("\n"),
            ),
            "joint name",
            vec!["joint 'j' <origin xyz>", "`nan` is not a finite number"],
        ),
        (
            "malformed XML",
            robot("  <link name=\"a\">\n  </lnk>"),
            "</lnk>",
            vec!["malformed XML"],
        ),
    ];
    for (what, text, marker, expected) in cases {
        let path = dir.path().join("pkg_here/robot.urdf");
        std::fs::write(&path, &text).unwrap();
        let mut s = Settings::default();
        s.output.frames = false;
        s.output.step_log = false;
        s.contact.default_thickness_m = Some(1e-3);
        let mut sim = Simulation::new(s).unwrap();
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            sim.add_robot("r", &path, &RobotOptions::default())
        }));
        let err = match result {
            Ok(Ok(_)) => panic!("{what}: accepted"),
            Ok(Err(e)) => e.to_string(),
            Err(_) => panic!("{what}: panicked"),
        };
        let located = if marker.is_empty() {
            format!("{}:", path.display())
        } else {
            format!("{}:{}:", path.display(), line_of(&text, marker))
        };
        println!("{what}: {err}");
        assert!(
            err.starts_with(&located),
            "{what}: `{err}` does not start with `{located}`"
        );
        for e in expected {
            assert!(err.contains(e), "{what}: `{err}` does not contain `{e}`");
        }
        assert_eq!(sim.num_rigid_bodies(), 0, "{what}: a rejected robot added bodies");
    }
}
