//! Surfaces, volumes, lines, obstacles, materials, motions, attachments and gravity ramps.

use super::*;

#[test]
fn default_scene_parses_with_the_right_counts() {
    let scene = load_scene_with(&repo_scene("default.toml"), quiet).unwrap();
    assert_eq!(scene.name, "default");
    assert_eq!(scene.duration_s, 3.0);
    let sim = &scene.simulation;
    assert_eq!(sim.nodes.len(), 33 * 33);
    assert_eq!(sim.deformables.triangles.num_elements(), 2 * 32 * 32);
    match &sim.output.meshes[0].cells {
        OutputCells::Triangles(t) => assert_eq!(t.len(), 2 * 32 * 32),
        _ => panic!("the cloth is not a triangle mesh"),
    }
    // Default settings: residual 1e-6 N, dt = 1/30 s.
    assert_eq!(sim.settings.newton.residual_tolerance_n, 1e-6);
    assert_eq!(sim.settings.newton.step_tolerance_m_s, 0.0);
    assert_eq!(sim.settings.time_step_s, 1.0 / 30.0);
    // Two pinned corners at y = +0.5, k = 1e6 N/m.
    assert_eq!(scene.prescribed.len(), 2);
    for (p, x) in scene.prescribed.iter().zip([0.5, -0.5]) {
        assert_eq!(p.nodes, 1);
        let pp = &sim.deformables.prescribed;
        assert_eq!(pp.params(p.handle).unwrap().stiffness, 1e6);
        assert_eq!(pp.targets(p.handle).unwrap()[0], Vector3::new(x, 0.5, 0.0));
    }
}

#[test]
fn every_repository_scene_loads() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let mut n = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml" || e == "json") {
            load_scene_with(&path, quiet).unwrap_or_else(|e| panic!("{e}"));
            n += 1;
        }
    }
    assert!(n >= 3);
}

#[test]
fn the_documented_example_loads() {
    let doc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/scene-format.md")).unwrap();
    let example = doc
        .rsplit("```toml\n")
        .next()
        .and_then(|s| s.split("```").next())
        .unwrap();
    let scene = parse_scene_with(example, "example.toml", Path::new("."), quiet).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.name, "cloth_on_a_block");
    assert_eq!(scene.objects.len(), 3);
    assert_eq!(scene.prescribed[0].nodes, 25);
    assert_eq!(scene.attachments.len(), 1);
}

#[test]
fn material_overrides_change_single_fields_of_the_preset() {
    let scene = parse(
        r#"
duration_s = 1.0
[[surface]]
name = "a"
grid = { size_m = [1.0, 1.0], quads = [2, 2] }
material = { preset = "cotton_fabric", strain = { youngs_modulus = 1e4 }, inertia = { density = 0.3 }, bending = { flat = { stiffness = 2e-6 } } }
[[surface]]
name = "b"
grid = { size_m = [1.0, 1.0], quads = [2, 2] }
material = { preset = "cotton_fabric", bending = "none" }
[[surface]]
name = "c"
grid = { size_m = [1.0, 1.0], quads = [2, 2] }
material.preset = "cotton_fabric"
material.bending.dihedral = { stiffness = 1e-5 }
[[volume]]
name = "v"
grid = { size_m = [1.0, 1.0, 1.0], cells = [1, 1, 1] }
material = { preset = "soft_rubber", strain = { poissons_ratio = 0.45, strain_limit = inf } }
[[line]]
name = "l"
segments = { begin_m = [0.0, 0.0, 0.0], end_m = [1.0, 0.0, 0.0], count = 4 }
material = { preset = "elastic_rubber_band", strain = { section_radius_m = 0.003 } }
"#,
    );
    let d = &scene.simulation.deformables;
    let cotton = SurfaceMaterial::cotton_fabric();
    let a = surface(&scene, "a");
    let strain = d.triangles.params(a.strain).unwrap();
    assert_eq!(strain.youngs_modulus, 1e4);
    let expected = crate::deformables::TriangleStrainParams {
        youngs_modulus: 1e4,
        ..cotton.strain.clone()
    };
    assert_eq!(strain, &expected);
    let inertia = d.inertia.params(a.inertia).unwrap();
    assert_eq!((inertia.density, inertia.damping), (0.3, 0.1));
    let Some(BendingHandle::Flat(fb)) = a.bending else {
        panic!("a has no flat bending")
    };
    let fb = d.flat_bending.params(fb).unwrap();
    assert_eq!((fb.stiffness, fb.damping), (2e-6, 1e-7));
    assert!(surface(&scene, "b").bending.is_none());
    let Some(BendingHandle::Dihedral(db)) = surface(&scene, "c").bending else {
        panic!("c has no dihedral bending")
    };
    let db = d.dihedral_bending.params(db).unwrap();
    assert_eq!(db.stiffness, 1e-5);
    let Some(SceneObject::Volume(v)) = scene.object("v") else {
        panic!()
    };
    let tet = d.tets.params(v.strain).unwrap();
    assert_eq!(tet.poissons_ratio, 0.45);
    assert_eq!(tet.strain_limit, f64::INFINITY);
    assert_eq!(tet.youngs_modulus, VolumeMaterial::soft_rubber().strain.youngs_modulus);
    let Some(SceneObject::Line(l)) = scene.object("l") else {
        panic!()
    };
    let seg = d.segments.params(l.strain).unwrap();
    assert_eq!(seg.section_radius_m, 0.003);
    assert_eq!(seg.youngs_modulus, 1e4);
    assert_eq!(scene.simulation.nodes.len(), 3 * 9 + 9 + 5);
}

#[test]
fn json_scenes_parse_and_errors_have_lines() {
    let json = r#"{
  "duration_s": 1.0,
  "settings": { "gravity_m_s2": [0.0, -9.81, 0.0] },
  "surface": [
{ "name": "cloth", "grid": { "size_m": [1.0, 1.0], "quads": [4, 4] },
  "material": { "preset": "cotton_fabric", "strain": { "youngs_modulus": 1e4 } } }
  ],
  "prescribed": [ { "object": "cloth", "nodes": [0, 4], "stiffness": 1e6 } ]
}"#;
    let scene = parse_scene_with(json, "scene.json", Path::new("."), quiet).unwrap();
    assert_eq!(scene.simulation.nodes.len(), 25);
    assert_eq!(scene.simulation.settings.gravity_m_s2, [0.0, -9.81, 0.0]);
    assert_eq!(scene.prescribed[0].nodes, 2);
    let h = surface(&scene, "cloth");
    let strain = scene.simulation.deformables.triangles.params(h.strain).unwrap();
    assert_eq!(strain.youngs_modulus, 1e4);

    let bad = json.replace("\"quads\": [4, 4]", "\"quads\": [4, 4], \"colour\": 1");
    let e = scene_error(parse_scene(&bad, "scene.json", Path::new(".")).err().unwrap());
    assert_eq!(e.line, Some(5), "{e}");
    assert!(e.to_string().starts_with("scene.json:5:"), "{e}");
    assert!(e.to_string().contains("unknown field `colour`"), "{e}");
    let bad = json.replace("\"youngs_modulus\": 1e4", "\"youngs_modulu\": 1e4");
    let e = scene_error(parse_scene(&bad, "scene.json", Path::new(".")).err().unwrap());
    assert!(
        e.to_string()
            .contains("unknown field `youngs_modulu` in surface 'cloth' material.strain"),
        "{e}"
    );
    let e = scene_error(
        parse_scene("{ \"duration_s\": 1.0,\n ]", "scene.json", Path::new("."))
            .err()
            .unwrap(),
    );
    assert_eq!(e.line, Some(2), "{e}");
}

#[test]
fn motions_move_the_targets() {
    let mut scene = parse(
        r#"
duration_s = 2.0
[settings]
gravity_m_s2 = [0.0, 0.0, 0.0]
[[surface]]
name = "cloth"
grid = { size_m = [0.5, 0.5], quads = [4, 4] }
rotate_deg = { angle = 90.0, axis = [1.0, 0.0, 0.0] }
material = "cotton_fabric"
[[prescribed]]
object = "cloth"
inside_box = { center_m = [0.25, 0.0, 0.0], size_m = [0.001, 1.0, 1.0] }
stiffness = 1e6
motion = { start_s = 0.5, end_s = 1.5, angular_velocity_deg_s = 90.0, axis = [2.0, 0.0, 0.0], center_m = [0.0, 0.0, 0.1], velocity_m_s = [0.0, 0.0, 0.2] }
[[prescribed]]
object = "cloth"
inside_box = { center_m = [-0.25, 0.0, 0.0], size_m = [0.001, 1.0, 1.0] }
stiffness = 1e6
motion = { velocity_m_s = [0.0, 0.3, 0.0] }
"#,
    );
    let twist = scene.prescribed[0].clone();
    let slide = scene.prescribed[1].clone();
    assert_eq!((twist.nodes, slide.nodes), (5, 5));
    let sim = &mut scene.simulation;
    let reference: Vec<_> = sim.deformables.prescribed.targets(twist.handle).unwrap().to_vec();
    // The grid was turned into the XZ plane.
    assert!(reference.iter().all(|p| p.x == 0.25 && p.y.abs() < 1e-15));
    let motion = twist.motion.clone().unwrap();
    for (t, tau) in [(0.0, 0.0), (0.5, 0.0), (1.0, 0.5), (1.25, 0.75), (1.5, 1.0), (3.0, 1.0)] {
        motion.apply(sim, twist.handle, t).unwrap();
        let (s, c) = (90.0f64 * tau).to_radians().sin_cos();
        let targets = sim.deformables.prescribed.targets(twist.handle).unwrap();
        for (p, q) in reference.iter().zip(targets) {
            let (y, z) = (p.y, p.z - 0.1);
            let expected = Vector3::new(p.x, c * y - s * z, s * y + c * z + 0.1 + 0.2 * tau);
            assert!((q - expected).norm() < 1e-12, "t = {t}: {q} vs {expected}");
        }
    }
    // Through the event: after one step the sliding edge's targets are at t = dt.
    let slide_ref: Vec<_> = sim.deformables.prescribed.targets(slide.handle).unwrap().to_vec();
    sim.step().unwrap();
    let t = sim.time();
    assert!(t > 0.0);
    let targets = sim.deformables.prescribed.targets(slide.handle).unwrap();
    for (p, q) in slide_ref.iter().zip(targets) {
        assert!((q - (p + Vector3::new(0.0, 0.3 * t, 0.0))).norm() < 1e-14);
    }
}

#[test]
fn twisting_cloth_scene_follows_its_motions() {
    let mut scene = load_scene_with(&repo_scene("twisting_cloth_no_contact.toml"), quiet).unwrap();
    assert_eq!(scene.simulation.gravity(), Vector3::zeros());
    assert_eq!(scene.duration_s, 2.0);
    let edges: Vec<_> = scene.prescribed.iter().map(|p| (p.handle, p.nodes)).collect();
    assert_eq!(edges.iter().map(|e| e.1).collect::<Vec<_>>(), vec![33, 33]);
    let sim = &mut scene.simulation;
    for _ in 0..3 {
        sim.step().unwrap();
    }
    let t = sim.time();
    for ((h, _), sign) in edges.iter().zip([1.0, -1.0]) {
        let pp = &sim.deformables.prescribed;
        assert!(pp.max_violation_m(*h, &sim.nodes.x).unwrap() <= 1e-3);
        // The edge node at the top (z = +0.25 before the motion) turned by ±90°/s · t.
        let (s, c) = (sign * 90.0f64 * t).to_radians().sin_cos();
        let top = pp
            .targets(*h)
            .unwrap()
            .iter()
            .map(|p| (p - Vector3::new(p.x, -0.25 * s, 0.25 * c)).norm())
            .fold(f64::INFINITY, f64::min);
        assert!(top < 1e-12, "{top}");
    }
}

#[test]
fn mesh_paths_are_relative_to_the_scene_file() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("meshes")).unwrap();
    std::fs::create_dir_all(dir.path().join("scenes")).unwrap();
    std::fs::write(
        dir.path().join("meshes/square.obj"),
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("meshes/tet.vtk"),
        "# vtk DataFile Version 2.0\ntet\nASCII\nDATASET UNSTRUCTURED_GRID\n\
         POINTS 4 double\n0 0 0\n1 0 0\n0 1 0\n0 0 1\nCELLS 1 5\n4 0 1 2 3\n\
         CELL_TYPES 1\n10\n",
    )
    .unwrap();
    let scene_path = dir.path().join("scenes/meshes.toml");
    std::fs::write(
        &scene_path,
        r#"duration_s = 1.0
[[surface]]
name = "square"
mesh = "../meshes/square.obj"
scale = 2.0
translate_m = [0.0, 0.0, 1.0]
material = "cotton_fabric"
[[volume]]
name = "tet"
mesh = "../meshes/tet.vtk"
material = "soft_rubber"
[[obstacle]]
name = "plate"
mesh = "../meshes/square.obj"
translate_m = [0.0, 0.0, -1.0]
contact_thickness_m = 0.001
"#,
    )
    .unwrap();
    let scene = load_scene_with(&scene_path, quiet).unwrap();
    let sim = &scene.simulation;
    let square = surface(&scene, "square");
    let x = sim.positions(square.nodes);
    assert_eq!(x.len(), 4);
    assert_eq!(x[2], Vector3::new(2.0, 2.0, 1.0));
    assert_eq!(sim.deformables.triangles.num_elements(), 2);
    assert_eq!(sim.deformables.tets.num_elements(), 1);
    assert_eq!(scene.name, "meshes");
    let Some(SceneObject::Obstacle(plate)) = scene.object("plate") else {
        panic!("no obstacle 'plate'")
    };
    assert_eq!(sim.positions(plate.nodes)[2], Vector3::new(1.0, 1.0, -1.0));
    assert_eq!(sim.contact.objects().len(), 1);

    // A volume needs tets; a missing file names the resolved path and the line.
    let text = std::fs::read_to_string(&scene_path)
        .unwrap()
        .replace("../meshes/tet.vtk", "../meshes/square.obj");
    std::fs::write(&scene_path, text).unwrap();
    let e = scene_error(load_scene(&scene_path).err().unwrap()).to_string();
    assert!(e.contains("meshes.toml:10:1:"), "{e}");
    assert!(e.contains("contains no tetrahedra"), "{e}");
    assert!(e.contains("volume 'tet' mesh"), "{e}");
    let text = std::fs::read_to_string(&scene_path)
        .unwrap()
        .replace("../meshes/square.obj\"\nscale", "square.obj\"\nscale");
    std::fs::write(&scene_path, text).unwrap();
    let e = scene_error(load_scene(&scene_path).err().unwrap()).to_string();
    assert!(e.contains("meshes.toml:4:1:"), "{e}");
    assert!(e.contains("scenes/square.obj' not found"), "{e}");
}

#[test]
fn attachments_and_gravity_ramps() {
    let mut scene = parse(
        r#"
duration_s = 1.0
[[surface]]
name = "a"
grid = { size_m = [1.0, 1.0], quads = [2, 2] }
material = "cotton_fabric"
[[surface]]
name = "b"
grid = { size_m = [1.0, 1.0], quads = [2, 2] }
translate_m = [0.0, 0.0, 0.5]
material = "cotton_fabric"
[[line]]
name = "rope"
vertices_m = [[0.5, 0.5, 0.0], [0.5, 0.5, -0.5]]
elements = [[0, 1]]
material = "elastic_rubber_band"
[[attachment]]
a = "a"
b = "b"
nodes_a = [0, 8]
nodes_b = [0, 8]
stiffness = 1e5
[[attachment]]
name = "knot"
a = "rope"
b = "a"
within_m = 1e-9
[[attachment]]
a = "rope"
b = "b"
nodes_a = [1]
triangles_b = [[0, 1, 2]]
barycentric_b = [[0.2, 0.3, 0.5]]
[[gravity_ramp]]
start_s = 0.0
end_s = 1.0
to_m_s2 = [0.0, 0.0, -1.0]
"#,
    );
    let labels: Vec<_> = scene.attachments.iter().map(|(l, _)| l.as_str()).collect();
    assert_eq!(labels, ["a-b", "knot", "rope-b"]);
    let sim = &mut scene.simulation;
    let knot = scene.attachments[1].1;
    // The rope's top node coincides with the cloth's corner (0.5, 0.5, 0).
    let gap = sim.deformables.attachments.max_gap_m(knot, &sim.nodes.x).unwrap();
    assert_eq!(gap, 0.0);
    sim.step().unwrap();
    let t = sim.time();
    let expected = -9.81 + (9.81 - 1.0) * t;
    assert!((sim.gravity().z - expected).abs() < 1e-12);
}

/// A sheet pierced by a blade (an obstacle), three more obstacles, friction and a disabled
/// collision.
const OBSTACLES: &str = r#"
duration_s = 1.0
[settings]
contact.default_thickness_m = 0.001
[[surface]]
name = "sheet"
vertices_m = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]]
elements = [[0, 1, 2]]
material = "cotton_fabric"
[[obstacle]]
name = "blade"
vertices_m = [[0.0, 0.0, -1.0], [0.5, 0.0, 1.0], [-0.5, 0.0, 1.0]]
triangles = [[0, 1, 2]]
[[obstacle]]
name = "crate"
box = { size_m = [0.2, 0.4, 0.6] }
translate_m = [5.0, 0.0, 0.0]
contact_thickness_m = 0.003
stiffness = 1e5
[[obstacle]]
name = "drum"
cylinder = { radius_m = 0.1, height_m = 0.3 }
rotate_deg = { angle = 90.0, axis = [1.0, 0.0, 0.0] }
translate_m = [-5.0, 0.0, 0.0]
[[obstacle]]
name = "floor"
grid = { size_m = [2.0, 2.0], quads = [2, 2] }
scale = 2.0
translate_m = [0.0, 0.0, -3.0]
[[friction]]
objects = ["sheet", "sheet"]
mu = 0.3
[[friction]]
objects = ["sheet", "floor"]
mu = 0.5
[[disable_collision]]
objects = ["sheet", "blade"]
"#;

#[test]
fn obstacles_friction_and_disabled_collisions() {
    let scene = parse(OBSTACLES);
    let sim = &scene.simulation;
    let names: Vec<_> = scene.objects.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["sheet", "blade", "crate", "drum", "floor"]);
    let obstacle = |name: &str| match scene.object(name) {
        Some(SceneObject::Obstacle(h)) => *h,
        other => panic!("{name} is {other:?}"),
    };
    // Geometry counts: a closed box (8, 12), a capped cylinder (16·2 + 2, 64), a 2×2 grid.
    let contact = &sim.contact;
    let count = |name: &str| obstacle(name).nodes.len;
    assert_eq!(
        [count("blade"), count("crate"), count("drum"), count("floor")],
        [3, 8, 34, 9]
    );
    let floor = sim.positions(obstacle("floor").nodes);
    assert!(floor
        .iter()
        .all(|p| p.z == -3.0 && p.x.abs() <= 2.0 && p.y.abs() <= 2.0));
    assert!(floor.iter().any(|p| p.x == 2.0));
    let drum = sim.positions(obstacle("drum").nodes);
    // Turned about X: the axis is along Y.
    assert!(drum
        .iter()
        .all(|p| ((p.x + 5.0).powi(2) + p.z.powi(2)).sqrt() <= 0.1 + 1e-12));
    // Thickness: given, else the default; stiffness: given, else 1e6; all self-collision off.
    let thickness: Vec<_> = contact.objects().iter().map(|o| o.thickness_m).collect();
    assert_eq!(thickness, [0.001, 0.001, 0.003, 0.001, 0.001]);
    let pp = &sim.deformables.prescribed;
    assert_eq!(pp.params(obstacle("crate").prescribed).unwrap().stiffness, 1e5);
    assert_eq!(pp.params(obstacle("drum").prescribed).unwrap().stiffness, 1e6);
    assert_eq!(
        pp.params(obstacle("crate").prescribed).unwrap().tolerance_m,
        1e-4 * 0.003
    );
    // Friction, including self-friction.
    let sheet = scene.object("sheet").unwrap().contact().unwrap();
    let mu = |h: ContactHandle| contact.friction(sheet, h).unwrap();
    assert_eq!(mu(sheet), 0.3);
    assert_eq!(mu(obstacle("floor").contact), 0.5);
    assert_eq!(mu(obstacle("blade").contact), 0.0);
    assert_eq!(contact.friction(obstacle("floor").contact, sheet).unwrap(), 0.5);
    // The blade pierces the sheet: only with the collision on is that an intersection.
    assert!(contact.find_intersections(&sim.nodes.x).is_empty());
    let on = parse(&OBSTACLES.replace("[[disable_collision]]\nobjects = [\"sheet\", \"blade\"]\n", ""));
    let found = on.simulation.contact.find_intersections(&on.simulation.nodes.x);
    assert!(!found.is_empty());
}

#[test]
fn obstacle_motions_move_the_obstacle() {
    let mut scene = parse(
        r#"
duration_s = 1.0
[settings]
gravity_m_s2 = [0.0, 0.0, 0.0]
[[obstacle]]
name = "crate"
box = { size_m = [0.2, 0.2, 0.2] }
contact_thickness_m = 0.001
motion = { velocity_m_s = [0.0, 0.0, 0.3], angular_velocity_deg_s = 90.0, axis = [0.0, 0.0, 1.0], center_m = [0.1, 0.0, 0.0] }
"#,
    );
    let Some(SceneObject::Obstacle(crate_)) = scene.object("crate").copied() else {
        panic!()
    };
    let sim = &mut scene.simulation;
    let reference = sim.positions(crate_.nodes).to_vec();
    sim.step().unwrap();
    let t = sim.time();
    assert!(t > 0.0);
    let (s, c) = (90.0f64 * t).to_radians().sin_cos();
    let targets = sim.deformables.prescribed.targets(crate_.prescribed).unwrap().to_vec();
    for (p, q) in reference.iter().zip(&targets) {
        let (x, y) = (p.x - 0.1, p.y);
        let expected = Vector3::new(c * x - s * y + 0.1, s * x + c * y, p.z + 0.3 * t);
        assert!((q - expected).norm() < 1e-12, "{q} vs {expected}");
    }
    // The nodes follow within the hardening tolerance (1e-4 of the thickness).
    let gap = sim
        .deformables
        .prescribed
        .max_violation_m(crate_.prescribed, &sim.nodes.x)
        .unwrap();
    assert!(gap <= 1e-7 * (1.0 + 1e-9), "{gap}");
}

#[test]
fn json_contact_entries_are_labelled() {
    let json = r#"{
  "duration_s": 1.0,
  "settings": { "contact": { "default_thickness_m": 0.001 } },
  "surface": [ { "name": "cloth", "grid": { "size_m": [1.0, 1.0], "quads": [2, 2] }, "material": "cotton_fabric" } ],
  "obstacle": [ { "name": "ball", "sphere": { "radius_m": 0.1 }, "translate_m": [0.0, 0.0, -0.5] } ],
  "friction": [ { "objects": ["cloth", "ball"], "mu": 0.2 } ]
}"#;
    let scene = parse_scene_with(json, "scene.json", Path::new("."), quiet).unwrap();
    let c = &scene.simulation.contact;
    assert_eq!(c.objects().len(), 2);
    assert_eq!(c.friction(ContactHandle(0), ContactHandle(1)).unwrap(), 0.2);
    assert_eq!(scene.simulation.nodes.len(), 9 + 162);
    let bad = json.replace("[\"cloth\", \"ball\"]", "[\"cloth\", \"bal\"]");
    let e = scene_error(parse_scene(&bad, "scene.json", Path::new(".")).err().unwrap());
    assert!(
        e.to_string()
            .contains("unknown object 'bal' in friction #1 ('cloth' and 'bal') objects[1]"),
        "{e}"
    );
}

#[test]
fn every_documented_scene_loads() {
    let doc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/scene-format.md")).unwrap();
    let blocks: Vec<_> = doc
        .split("```toml\n")
        .skip(1)
        .filter_map(|s| s.split("```").next())
        .filter(|b| b.contains("duration_s"))
        .collect();
    assert!(blocks.len() >= 2, "{}", blocks.len());
    for b in blocks {
        parse_scene_with(b, "doc.toml", Path::new("."), quiet).unwrap_or_else(|e| panic!("{e}\n{b}"));
    }
}

/// `fixed = true`: an obstacle fixed in the world, whose nodes are no unknowns and never move; a
/// `stiffness` or `motion` on it, or prescribing its nodes, is an error naming the field.
#[test]
fn fixed_obstacles_stay_put_and_refuse_motion() {
    let text = r#"
duration_s = 0.1
[settings]
contact.default_thickness_m = 0.001
time_step_s = 0.01
[[surface]]
name = "sheet"
grid = { size_m = [0.2, 0.2], quads = [2, 2] }
translate_m = [0.0, 0.0, 0.003]
material = "cotton_fabric"
[[obstacle]]
name = "floor"
grid = { size_m = [1.0, 1.0], quads = [1, 1] }
fixed = true
[[friction]]
objects = ["sheet", "floor"]
mu = 0.5
"#;
    let mut scene = parse(text);
    let Some(SceneObject::FixedObstacle(floor)) = scene.object("floor").copied() else {
        panic!("'floor' is not a fixed obstacle")
    };
    assert_eq!(scene.object("floor").unwrap().kind(), "fixed obstacle");
    let sheet = surface(&scene, "sheet");
    let sim = &mut scene.simulation;
    let start = bits(sim.positions(floor.nodes));
    for _ in 0..10 {
        sim.step().unwrap();
        assert_eq!(bits(sim.positions(floor.nodes)), start);
    }
    // The sheet's 9 nodes are the only unknowns; it came down onto the floor.
    assert_eq!(sim.summary().unknowns, 27);
    assert!(sim.positions(sheet.nodes).iter().all(|p| p.z < 0.003 && p.z > 0.0));

    let e = parse_err(&text.replace("fixed = true", "fixed = true\nstiffness = 1e5")).to_string();
    assert!(
        e.contains("obstacle 'floor' is fixed (`fixed = true`): it has no `stiffness`"),
        "{e}"
    );
    let moving = text.replace(
        "fixed = true",
        "fixed = true\nmotion = { center_m = [0.0, 0.0, 0.0], velocity_m_s = [0.1, 0.0, 0.0] }",
    );
    let e = parse_err(&moving).to_string();
    assert!(e.contains("it has no `motion`"), "{e}");
    let prescribed = format!("{text}[[prescribed]]\nobject = \"floor\"\nall = true\n");
    let e = parse_err(&prescribed).to_string();
    assert!(e.contains("'floor' is a fixed obstacle: its nodes never move"), "{e}");
}
