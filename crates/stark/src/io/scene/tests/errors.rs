//! Every error names the file, line and column, the entry and the field.

use super::*;

const CLOTH: &str = "duration_s = 1.0\n[[surface]]\nname = \"cloth\"\n\
                     grid = { size_m = [1.0, 1.0], quads = [2, 2] }\n";

/// A cloth with contact (lines 2–5), a rope without (6–9) and an obstacle (10–14).
const CONTACT: &str = "duration_s = 1.0\n[[surface]]\nname = \"cloth\"\n\
                       grid = { size_m = [1.0, 1.0], quads = [2, 2] }\n\
                       material = { preset = \"cotton_fabric\", contact_thickness_m = 0.002 }\n\
                       [[line]]\nname = \"rope\"\n\
                       segments = { begin_m = [0.0, 0.0, 1.0], end_m = [0.0, 0.0, 2.0], count = 2 }\n\
                       material = \"elastic_rubber_band\"\n\
                       [[obstacle]]\nname = \"ball\"\nsphere = { radius_m = 0.1, subdivisions = 1 }\n\
                       translate_m = [0.0, 0.0, -0.5]\ncontact_thickness_m = 0.002\n";

/// The start of an obstacle entry; its geometry goes on line 4.
const OBSTACLE: &str = "duration_s = 1.0\n[[obstacle]]\nname = \"ball\"\n";

/// Each error names the file, the line (and column) and the offending field.
#[test]
fn deformable_and_contact_entries_name_file_line_and_field() {
    let cases: Vec<(&str, String, Vec<&str>)> = vec![
        (
            "syntax",
            "duration_s = 1.0\n[[surface]\n".into(),
            vec!["test.toml:2:"],
        ),
        (
            "missing field",
            "[settings]\nthreads = 1\n".into(),
            vec!["=test.toml:1:1: missing field `duration_s`"],
        ),
        (
            "unknown field in an override",
            format!("{CLOTH}[surface.material]\npreset = \"cotton_fabric\"\nstrain = {{ youngs_modulu = 1e4 }}\n"),
            vec![
                "test.toml:7:12: unknown field `youngs_modulu` in surface 'cloth' material.strain, expected one of",
                "`youngs_modulus`",
            ],
        ),
        (
            "unknown field in an object",
            format!("{CLOTH}material = \"cotton_fabric\"\ncolour = \"red\"\n"),
            vec!["test.toml:6:1: unknown field `colour` in surface 'cloth', expected one of"],
        ),
        (
            "unknown top-level table",
            format!("{CLOTH}material = \"cotton_fabric\"\n[[surfaces]]\nname = \"x\"\n"),
            vec!["test.toml:6:", "unknown field `surfaces`"],
        ),
        (
            "unknown setting",
            "duration_s = 1.0\n[settings.newton]\nresidual_tolerance = 1e-6\n".into(),
            vec!["test.toml:3:1: unknown field `residual_tolerance` in settings.newton"],
        ),
        (
            "type error in a generator",
            "duration_s = 1.0\n[[surface]]\nname = \"cloth\"\ngrid = { size_m = [1.0, 1.0], quads = [2, \"x\"] }\nmaterial = \"cotton_fabric\"\n".into(),
            vec!["test.toml:4:", "in surface 'cloth' grid.quads[1]", "invalid type"],
        ),
        (
            "type error in an override",
            format!("{CLOTH}material = {{ preset = \"cotton_fabric\", strain = {{ youngs_modulus = \"soft\" }} }}\n"),
            vec!["test.toml:5:", "invalid type: string \"soft\" in surface 'cloth' material.strain.youngs_modulus"],
        ),
        (
            "unknown variant",
            format!("{CLOTH}material = {{ preset = \"cotton_fabric\", bending = \"flatt\" }}\n"),
            vec!["test.toml:5:", "unknown variant `flatt`", "material.bending"],
        ),
        (
            "unknown preset",
            format!("{CLOTH}material = \"soft_rubber\"\n"),
            vec!["test.toml:5:", "unknown surface material preset 'soft_rubber'", "cotton_fabric", "surface 'cloth' material"],
        ),
        (
            "bad parameter value in an override",
            format!("{CLOTH}material = {{ preset = \"cotton_fabric\", strain = {{ youngs_modulus = -1.0 }} }}\n"),
            vec!["test.toml:5:", "`youngs_modulus` = -1", "surface 'cloth' material.strain.youngs_modulus"],
        ),
        (
            "bad setting value",
            "duration_s = 1.0\n[settings]\ntime_step_s = -1.0\n".into(),
            vec!["test.toml:3:1:", "`time_step_s` = -1", "settings.time_step_s"],
        ),
        (
            "bad duration",
            "duration_s = 0.0\n".into(),
            vec!["test.toml:1:1:", "duration_s"],
        ),
        (
            "duplicate names",
            format!("{CLOTH}material = \"cotton_fabric\"\n[[volume]]\nname = \"cloth\"\ngrid = {{ size_m = [1.0, 1.0, 1.0], cells = [1, 1, 1] }}\nmaterial = \"soft_rubber\"\n"),
            vec!["test.toml:7:1: duplicate object name 'cloth' (already used by surface #1) in volume 'cloth' name"],
        ),
        (
            "no geometry",
            "duration_s = 1.0\n[[surface]]\nname = \"cloth\"\nmaterial = \"cotton_fabric\"\n".into(),
            vec!["test.toml:2:", "no geometry", "surface 'cloth'"],
        ),
        (
            "two geometries",
            format!("{CLOTH}mesh = \"cloth.obj\"\nmaterial = \"cotton_fabric\"\n"),
            vec!["test.toml:5:1:", "more than one geometry (grid, mesh)", "surface 'cloth' mesh"],
        ),
        (
            "bad grid",
            "duration_s = 1.0\n[[surface]]\nname = \"cloth\"\ngrid = { size_m = [1.0, 1.0], quads = [0, 2] }\nmaterial = \"cotton_fabric\"\n".into(),
            vec!["test.toml:4:31:", "quads = [0, 2] must be positive", "surface 'cloth' grid.quads"],
        ),
        (
            "missing mesh file",
            "duration_s = 1.0\n[[surface]]\nname = \"cloth\"\nmesh = \"no/such/cloth.obj\"\nmaterial = \"cotton_fabric\"\n".into(),
            vec!["test.toml:4:1:", "cloth.obj' not found", "surface 'cloth' mesh"],
        ),
        (
            "unknown object",
            format!("{CLOTH}material = \"cotton_fabric\"\n[[prescribed]]\nobject = \"clth\"\nall = true\n"),
            vec!["test.toml:7:1: unknown object 'clth' in prescribed #1 (object 'clth') object, expected one of cloth"],
        ),
        (
            "empty box",
            format!("{CLOTH}material = \"cotton_fabric\"\n[[prescribed]]\nobject = \"cloth\"\ninside_box = {{ center_m = [5.0, 0.0, 0.0], size_m = [0.1, 0.1, 0.1] }}\n"),
            vec!["test.toml:8:1:", "no node of 'cloth' lies inside the box", "prescribed #1 (object 'cloth') inside_box"],
        ),
        (
            "no selection",
            format!("{CLOTH}material = \"cotton_fabric\"\n[[prescribed]]\nobject = \"cloth\"\n"),
            vec!["test.toml:6:", "no node selection", "prescribed #1"],
        ),
        (
            "node out of range",
            format!("{CLOTH}material = \"cotton_fabric\"\n[[prescribed]]\nobject = \"cloth\"\nnodes = [0, 99]\n"),
            vec!["test.toml:8:1:", "node 99 does not exist", "prescribed #1 (object 'cloth') nodes"],
        ),
        (
            "bad stiffness",
            format!("{CLOTH}material = \"cotton_fabric\"\n[[prescribed]]\nobject = \"cloth\"\nall = true\nstiffness = -5.0\n"),
            vec!["test.toml:9:1:", "`stiffness` = -5", "prescribed #1 (object 'cloth') stiffness"],
        ),
        (
            "motion without axis",
            format!("{CLOTH}material = \"cotton_fabric\"\n[[prescribed]]\nobject = \"cloth\"\nall = true\nmotion = {{ angular_velocity_deg_s = 90.0 }}\n"),
            vec!["test.toml:9:12:", "needs an `axis`", "prescribed #1 (object 'cloth') motion.angular_velocity_deg_s"],
        ),
        (
            "unknown motion field",
            format!("{CLOTH}material = \"cotton_fabric\"\n[[prescribed]]\nobject = \"cloth\"\nall = true\nmotion = {{ velocity = [1.0, 0.0, 0.0] }}\n"),
            vec!["test.toml:9:12:", "unknown field `velocity` in prescribed #1 (object 'cloth') motion, expected"],
        ),
        (
            "attachment to an unknown object",
            format!("{CLOTH}material = \"cotton_fabric\"\n[[attachment]]\na = \"cloth\"\nb = \"box\"\nnodes_a = [0]\nnodes_b = [0]\n"),
            vec!["test.toml:8:1:", "unknown object 'box'", "attachment #1 ('cloth' to 'box') b"],
        ),
        (
            "bad contact setting",
            "duration_s = 1.0\n[settings.contact]\nfriction_iterations = 0\n".into(),
            vec!["=test.toml:3:1: `friction_iterations` = 0 on 'settings.contact' must be at least 1 in settings.contact.friction_iterations"],
        ),
        (
            "unknown contact setting",
            "duration_s = 1.0\n[settings]\ncontact = { thickness_m = 0.001 }\n".into(),
            vec!["test.toml:3:13: unknown field `thickness_m` in settings.contact, expected"],
        ),
        (
            "friction with an unknown object",
            format!("{CONTACT}[[friction]]\nobjects = [\"cloth\", \"bal\"]\nmu = 0.5\n"),
            vec!["=test.toml:16:21: unknown object 'bal' in friction #1 ('cloth' and 'bal') objects[1], expected one of cloth, rope, ball"],
        ),
        (
            "friction with an object without contact",
            format!("{CONTACT}[[friction]]\nobjects = [\"rope\", \"ball\"]\nmu = 0.5\n"),
            vec![
                "test.toml:16:12: object 'rope' takes no part in contact: it has no contact thickness",
                "objects with contact: cloth, ball in friction #1 ('rope' and 'ball') objects[0]",
            ],
        ),
        (
            "disabled collision of an object without contact",
            format!("{CONTACT}[[disable_collision]]\nobjects = [\"cloth\", \"rope\"]\n"),
            vec!["test.toml:16:21: object 'rope' takes no part in contact", "in disable_collision #1 ('cloth' and 'rope') objects[1]"],
        ),
        (
            "disabled collision with an unknown object",
            format!("{CONTACT}[[disable_collision]]\nobjects = [\"clth\", \"cloth\"]\n"),
            vec!["test.toml:16:12: unknown object 'clth' in disable_collision #1 ('clth' and 'cloth') objects[0]"],
        ),
        (
            "negative friction",
            format!("{CONTACT}[[friction]]\nobjects = [\"cloth\", \"ball\"]\nmu = -0.5\n"),
            vec!["=test.toml:17:1: mu = -0.5 must be non-negative and finite in friction #1 ('cloth' and 'ball') mu"],
        ),
        (
            "unknown field in a friction entry",
            format!("{CONTACT}[[friction]]\nobjects = [\"cloth\", \"ball\"]\nmu = 0.5\nstatic_mu = 0.6\n"),
            vec!["test.toml:18:1: unknown field `static_mu` in friction #1 ('cloth' and 'ball'), expected"],
        ),
        (
            "one object in a friction entry",
            format!("{CONTACT}[[friction]]\nobjects = [\"cloth\"]\nmu = 0.5\n"),
            vec!["test.toml:16:", "invalid length 1", "friction #1 objects"],
        ),
        (
            "unknown field in a disable_collision entry",
            format!("{CONTACT}[[disable_collision]]\nobjects = [\"cloth\", \"ball\"]\nmu = 0.5\n"),
            vec!["test.toml:17:1: unknown field `mu` in disable_collision #1 ('cloth' and 'ball'), expected `objects`"],
        ),
        (
            "prescribed obstacle",
            format!("{CONTACT}[[prescribed]]\nobject = \"ball\"\nall = true\n"),
            vec!["test.toml:16:1: 'ball' is an obstacle, whose nodes are prescribed already", "in prescribed #1 (object 'ball') object"],
        ),
        (
            "duplicate obstacle name",
            format!("{CLOTH}material = \"cotton_fabric\"\n[[obstacle]]\nname = \"cloth\"\nsphere = {{ radius_m = 0.1 }}\n"),
            vec!["=test.toml:7:1: duplicate object name 'cloth' (already used by surface #1) in obstacle 'cloth' name"],
        ),
        (
            "unknown field in an obstacle",
            format!("{CONTACT}colour = \"red\"\n"),
            vec!["test.toml:15:1: unknown field `colour` in obstacle 'ball', expected"],
        ),
        (
            "unknown field in an obstacle generator",
            format!("{OBSTACLE}sphere = {{ radius = 0.1 }}\ncontact_thickness_m = 0.002\n"),
            vec!["test.toml:4:12: unknown field `radius` in obstacle 'ball' sphere, expected"],
        ),
        (
            "obstacle without geometry",
            format!("{OBSTACLE}contact_thickness_m = 0.002\n"),
            vec!["test.toml:2:", "no geometry: give one of `sphere`, `box`, `cylinder`, `grid`, `mesh` or `vertices_m` + `triangles` in obstacle 'ball'"],
        ),
        (
            "obstacle with two geometries",
            format!("{OBSTACLE}sphere = {{ radius_m = 0.1 }}\nbox = {{ size_m = [1.0, 1.0, 1.0] }}\ncontact_thickness_m = 0.002\n"),
            vec!["test.toml:5:1: more than one geometry (sphere, box)", "in obstacle 'ball' box"],
        ),
        (
            "obstacle without contact thickness",
            format!("{OBSTACLE}sphere = {{ radius_m = 0.1 }}\n"),
            vec!["test.toml:2:", "obstacle 'ball' has no contact thickness: give `contact_thickness_m`", "in obstacle 'ball'"],
        ),
        (
            "negative obstacle contact thickness",
            format!("{OBSTACLE}sphere = {{ radius_m = 0.1 }}\ncontact_thickness_m = -0.002\n"),
            vec!["=test.toml:5:1: contact_thickness_m = -0.002 must be positive and finite (m) in obstacle 'ball' contact_thickness_m"],
        ),
        (
            "bad obstacle stiffness",
            format!("{OBSTACLE}sphere = {{ radius_m = 0.1 }}\ncontact_thickness_m = 0.002\nstiffness = 0.0\n"),
            vec!["=test.toml:6:1: stiffness = 0 must be positive and finite (N/m) in obstacle 'ball' stiffness"],
        ),
        (
            "bad sphere radius",
            format!("{OBSTACLE}sphere = {{ radius_m = -0.1 }}\ncontact_thickness_m = 0.002\n"),
            vec!["=test.toml:4:12: radius_m = -0.1 must be positive and finite (m) in obstacle 'ball' sphere.radius_m"],
        ),
        (
            "too many sphere subdivisions",
            format!("{OBSTACLE}sphere = {{ radius_m = 0.1, subdivisions = 12 }}\ncontact_thickness_m = 0.002\n"),
            vec!["test.toml:4:28: subdivisions = 12 is too many (at most 7", "in obstacle 'ball' sphere.subdivisions"],
        ),
        (
            "bad box",
            format!("{OBSTACLE}box = {{ size_m = [1.0, 0.0, 1.0] }}\ncontact_thickness_m = 0.002\n"),
            vec!["test.toml:4:9: size_m.y = 0 must be positive and finite (m) in obstacle 'ball' box.size_m"],
        ),
        (
            "bad cylinder",
            format!("{OBSTACLE}cylinder = {{ radius_m = 0.1, height_m = 0.2, slices = 2 }}\ncontact_thickness_m = 0.002\n"),
            vec!["test.toml:4:", "slices = 2 must be at least 3 in obstacle 'ball' cylinder.slices"],
        ),
        (
            "inline obstacle triangle out of range",
            format!("{OBSTACLE}vertices_m = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]\ntriangles = [[0, 1, 2], [0, 1, 3]]\ncontact_thickness_m = 0.002\n"),
            vec!["=test.toml:5:25: triangle 1 refers to vertex 3, but there are 3 vertices in obstacle 'ball' triangles[1]"],
        ),
        (
            "inline obstacle without triangles",
            format!("{OBSTACLE}vertices_m = [[0.0, 0.0, 0.0]]\ncontact_thickness_m = 0.002\n"),
            vec!["test.toml:4:1: `vertices_m` needs `triangles` (inline geometry gives both) in obstacle 'ball' vertices_m"],
        ),
        (
            "missing obstacle mesh",
            format!("{OBSTACLE}mesh = \"no/such/ball.obj\"\ncontact_thickness_m = 0.002\n"),
            vec!["test.toml:4:1:", "ball.obj' not found", "obstacle 'ball' mesh"],
        ),
        (
            "obstacle motion without axis",
            format!("{CONTACT}motion = {{ angular_velocity_deg_s = 90.0 }}\n"),
            vec!["test.toml:15:12:", "needs an `axis`", "obstacle 'ball' motion.angular_velocity_deg_s"],
        ),
    ];
    let mut failures = Vec::new();
    for (what, text, expected) in cases {
        let e = parse_err(&text);
        let shown = e.to_string();
        for s in expected {
            // A leading `=` asks for the whole message.
            let ok = match s.strip_prefix('=') {
                Some(whole) => shown == whole,
                None => shown.contains(s),
            };
            if !ok {
                failures.push(format!("{what}: `{shown}` does not contain `{s}`"));
            }
        }
        if e.file != "test.toml" || e.line.is_none() {
            failures.push(format!("{what}: no file or line in {e:?}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn rigid_body_and_joint_entries_name_file_line_and_field() {
    const BODY: &str =
        "duration_s = 1.0\n[[rigid_body]]\nname = \"link\"\nbox = { size_m = [0.1, 0.1, 0.1] }\nmass_kg = 1.0\n";
    const BODIES: &str = "duration_s = 1.0\n\
                          [[rigid_body]]\nname = \"a\"\nbox = { size_m = [0.1, 0.1, 0.1] }\nmass_kg = 1.0\n\
                          [[rigid_body]]\nname = \"b\"\nbox = { size_m = [0.1, 0.1, 0.1] }\nmass_kg = 1.0\nposition_m = [0.0, 0.0, -0.2]\n\
                          [[surface]]\nname = \"cloth\"\ngrid = { size_m = [1.0, 1.0], quads = [1, 1] }\nmaterial = \"cotton_fabric\"\n";
    // Line 15 is the `[[joint]]` header, line 16 its `type`, 17 `a`, 18 `b`, 19 `point_m`.
    let hinge = "[[joint]]\ntype = \"hinge\"\na = \"a\"\nb = \"b\"\npoint_m = [0.0, 0.0, -0.1]\n";
    let cases: Vec<(&str, String, Vec<&str>)> = vec![
        (
            "unknown field in a body",
            format!("{BODY}colour = \"red\"\n"),
            vec!["test.toml:6:1: unknown field `colour` in rigid_body 'link', expected one of"],
        ),
        (
            "no mass",
            "duration_s = 1.0\n[[rigid_body]]\nname = \"link\"\nbox = { size_m = [0.1, 0.1, 0.1] }\n".into(),
            vec!["test.toml:2:", "rigid body 'link' needs a mass: give `mass_kg` or `density_kg_m3` in rigid_body 'link'"],
        ),
        (
            "two masses",
            format!("{BODY}density_kg_m3 = 10.0\n"),
            vec!["=test.toml:6:1: give the mass once: `mass_kg` or `density_kg_m3` in rigid_body 'link' density_kg_m3"],
        ),
        (
            "negative mass",
            "duration_s = 1.0\n[[rigid_body]]\nname = \"link\"\nbox = { size_m = [0.1, 0.1, 0.1] }\nmass_kg = -1.0\n".into(),
            vec!["=test.toml:5:1: mass_kg = -1 must be positive and finite (kg) in rigid_body 'link' mass_kg"],
        ),
        (
            "no shape",
            "duration_s = 1.0\n[[rigid_body]]\nname = \"link\"\nmass_kg = 1.0\n".into(),
            vec!["test.toml:2:", "no geometry: give one of `box`, `sphere`, `cylinder`, `capsule`, `torus`, `mesh` or `vertices_m` + `triangles`"],
        ),
        (
            "scale of a primitive",
            format!("{BODY}scale = 2.0\n"),
            vec!["test.toml:6:1: `scale` applies to `mesh` and inline geometry; give the box's size instead"],
        ),
        (
            "two orientations",
            format!("{BODY}rotate_deg = {{ angle = 90.0, axis = [0.0, 0.0, 1.0] }}\nquaternion_wxyz = [1.0, 0.0, 0.0, 0.0]\n"),
            vec!["test.toml:7:1: give the orientation once", "rigid_body 'link' quaternion_wxyz"],
        ),
        (
            "zero quaternion",
            format!("{BODY}quaternion_wxyz = [0.0, 0.0, 0.0, 0.0]\n"),
            vec!["test.toml:6:1: quaternion_wxyz = [0.0, 0.0, 0.0, 0.0] must be finite and non-zero"],
        ),
        (
            "bad inertia",
            format!("{BODY}inertia_kg_m2 = [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]\n"),
            vec!["test.toml:6:1:", "must be symmetric positive definite", "rigid_body 'link' inertia_kg_m2"],
        ),
        (
            "open mesh without inertia",
            "duration_s = 1.0\n[[rigid_body]]\nname = \"plate\"\nvertices_m = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]\ntriangles = [[0, 1, 2]]\nmass_kg = 1.0\n".into(),
            vec!["test.toml:4:1:", "the mesh is not closed", "(give `mass_kg` and `inertia_kg_m2` for an open mesh) in rigid_body 'plate' vertices_m"],
        ),
        (
            "bad torus",
            "duration_s = 1.0\n[[rigid_body]]\nname = \"ring\"\ntorus = { major_radius_m = 0.1, minor_radius_m = 0.2 }\nmass_kg = 1.0\n".into(),
            vec!["test.toml:4:", "minor_radius_m = 0.2 must be smaller than major_radius_m = 0.1", "rigid_body 'ring' torus.minor_radius_m"],
        ),
        (
            "contact without thickness",
            format!("{BODY}contact = true\n"),
            vec!["test.toml:6:1: rigid body 'link' takes part in contact but has no contact thickness"],
        ),
        (
            "motion of a body that is not fixed",
            format!("{BODY}fixed = false\nmotion = {{ velocity_m_s = [0.0, 0.0, 1.0] }}\n"),
            vec!["test.toml:7:1: a scripted `motion` drives a fixed body: remove `fixed = false` in rigid_body 'link' motion"],
        ),
        (
            "motion without axis",
            format!("{BODY}motion = {{ angular_velocity_deg_s = 90.0 }}\n"),
            vec!["test.toml:6:12:", "needs an `axis`", "rigid_body 'link' motion.angular_velocity_deg_s"],
        ),
        (
            "keyframes out of order",
            format!("{BODY}keyframes = [{{ time_s = 1.0 }}, {{ time_s = 0.5 }}]\n"),
            vec!["test.toml:6:", "time_s = 0.5 must be finite and after the previous keyframe (1 s", "rigid_body 'link' keyframes[1].time_s"],
        ),
        (
            "body called world",
            "duration_s = 1.0\n[[rigid_body]]\nname = \"world\"\nbox = { size_m = [0.1, 0.1, 0.1] }\nmass_kg = 1.0\n".into(),
            vec!["test.toml:3:1: 'world' names the fixed world in joints"],
        ),
        (
            "prescribed rigid body",
            format!("{BODY}[[prescribed]]\nobject = \"link\"\nall = true\n"),
            vec!["test.toml:7:1: 'link' is a rigid body: hold it with `fixed = true`", "prescribed #1 (object 'link') object"],
        ),
        (
            "bad joint type",
            format!("{BODIES}[[joint]]\ntype = \"hing\"\nb = \"b\"\n"),
            vec!["test.toml:16:8: unknown variant `hing` in joint #1 (hing 'world' to 'b') type, expected one of `ball`, `ball_cone`, `hinge`"],
        ),
        (
            "missing axis",
            format!("{BODIES}{hinge}"),
            vec!["=test.toml:16:1: a hinge joint needs `axis` (it takes `point_m`, `axis`) in joint #1 (hinge 'a' to 'b') type"],
        ),
        (
            "unknown body label",
            format!("{BODIES}{}axis = [0.0, 1.0, 0.0]\n", hinge.replace("a = \"a\"", "a = \"c\"")),
            vec!["=test.toml:17:1: unknown rigid body 'c' in joint #1 (hinge 'c' to 'b') a, expected one of world, a, b"],
        ),
        (
            "a deformable object in a joint",
            format!("{BODIES}{}axis = [0.0, 1.0, 0.0]\n", hinge.replace("b = \"b\"", "b = \"cloth\"")),
            vec!["test.toml:18:1: 'cloth' is a surface, not a rigid body", "in joint #1 (hinge 'a' to 'cloth') b, expected one of world, a, b"],
        ),
        (
            "the world as b",
            format!("{BODIES}{}axis = [0.0, 1.0, 0.0]\n", hinge.replace("b = \"b\"", "b = \"world\"")),
            vec!["test.toml:18:1: joint 'hinge a-world': `b` must be a rigid body"],
        ),
        (
            "a field of another joint type",
            format!("{BODIES}{hinge}axis = [0.0, 1.0, 0.0]\nlimit_deg = 30.0\n"),
            vec!["test.toml:21:1: `limit_deg` does not apply to a hinge joint, which takes `point_m`, `axis`, `stiffness`"],
        ),
        (
            "zero axis",
            format!("{BODIES}{hinge}axis = [0.0, 0.0, 0.0]\n"),
            vec!["=test.toml:20:1: joint 'hinge a-b': `axis` = [0.0, 0.0, 0.0] must be finite and non-zero in joint #1 (hinge 'a' to 'b') axis"],
        ),
        (
            "bad joint stiffness",
            format!("{BODIES}{hinge}axis = [0.0, 1.0, 0.0]\nstiffness = -1.0\n"),
            vec!["test.toml:21:1:", "`stiffness` = -1", "joint #1 (hinge 'a' to 'b') stiffness"],
        ),
        (
            "bad cone limit",
            format!("{BODIES}{}axis = [0.0, 0.0, 1.0]\nlimit_deg = 200.0\n", hinge.replace("hinge", "ball_cone")),
            vec!["test.toml:21:1:", "`limit_deg` = 200", "in joint #1 (ball_cone 'a' to 'b') limit_deg"],
        ),
        (
            "motor without target",
            format!("{BODIES}{}axis = [0.0, 1.0, 0.0]\nmax_torque_n_m = 1.0\n", hinge.replace("hinge", "motor")),
            vec!["test.toml:16:1: a motor joint needs `target_velocity_deg_s` or a `target_schedule`"],
        ),
        (
            "motor with negative torque",
            format!("{BODIES}{}axis = [0.0, 1.0, 0.0]\nmax_torque_n_m = -1.0\ntarget_velocity_deg_s = 10.0\n", hinge.replace("hinge", "motor")),
            vec!["test.toml:21:1:", "in joint #1 (motor 'a' to 'b') max_torque_n_m"],
        ),
        (
            "schedule out of order",
            format!("{BODIES}{}axis = [0.0, 1.0, 0.0]\nmax_torque_n_m = 1.0\ntarget_schedule = [[1.0, 0.0], [0.5, 1.0]]\n", hinge.replace("hinge", "motor")),
            vec!["test.toml:22:", "needs finite values and times that increase", "joint #1 (motor 'a' to 'b') target_schedule[1]"],
        ),
        (
            "universal axes not perpendicular",
            format!("{BODIES}{}axis_a = [1.0, 0.0, 0.0]\naxis_b = [1.0, 1.0, 0.0]\n", hinge.replace("hinge", "universal")),
            vec!["test.toml:21:1: joint 'universal a-b': `axis_b` = [1.0, 1.0, 0.0] must be perpendicular to `axis_a`"],
        ),
        (
            "fix joint with a body a",
            format!("{BODIES}[[joint]]\ntype = \"fix\"\na = \"a\"\nb = \"b\"\n"),
            vec!["test.toml:17:1: joint 'fix a-b': a fix joint holds body b in the world"],
        ),
        (
            "distance limits around the wrong distance",
            format!("{BODIES}[[joint]]\ntype = \"distance_limits\"\na = \"a\"\nb = \"b\"\npoint_a_m = [0.0, 0.0, 0.0]\npoint_b_m = [0.0, 0.0, -0.2]\nmin_m = 0.5\nmax_m = 1.0\n"),
            vec!["test.toml:21:1:", "current distance", "joint #1 (distance_limits 'a' to 'b') min_m"],
        ),
        (
            "a joint between a body and itself",
            format!("{BODIES}{}axis = [0.0, 1.0, 0.0]\n", hinge.replace("a = \"a\"", "a = \"b\"")),
            vec!["test.toml:18:1: joint 'hinge b-b' connects 'b' to itself"],
        ),
        (
            "misspelt field of a motor",
            format!("{BODIES}{}axis = [0.0, 1.0, 0.0]\nmax_torque_nm = 1.0\ntarget_velocity_deg_s = 10.0\n", hinge.replace("hinge", "motor")),
            vec!["=test.toml:21:1: unknown field `max_torque_nm` in joint #1 (motor 'a' to 'b'), expected one of `point_m`, `axis`, `target_velocity_deg_s`, `max_torque_n_m`, `delay_deg_s`, `stiffness`, `tolerance_m`, `tolerance_deg`, `target_schedule`"],
        ),
        (
            "a joint field of the wrong type",
            format!("{BODIES}{hinge}axis = \"up\"\n"),
            vec!["test.toml:20:1: `axis`: invalid type: string \"up\"", "in joint #1 (hinge 'a' to 'b') axis"],
        ),
        (
            "a typo in a joint type",
            format!("{BODIES}[[joint]]\ntype = \"ball_con\"\nb = \"b\"\n"),
            vec!["test.toml:16:8: unknown variant `ball_con` in joint #1 (ball_con 'world' to 'b') type, expected one of `ball`, `ball_cone`"],
        ),
        (
            "a schedule on a joint without a target",
            format!("{BODIES}{hinge}axis = [0.0, 1.0, 0.0]\ntarget_schedule = [[0.0, 1.0]]\n"),
            vec!["=test.toml:21:1: a hinge joint has no target to schedule in joint #1 (hinge 'a' to 'b') target_schedule"],
        ),
        (
            "a coupling of an unknown joint",
            format!("{BODIES}[[joint]]\ntype = \"joint_coupling\"\njoint_a = \"x\"\njoint_b = \"y\"\n"),
            vec!["test.toml:17:1: joint 'joint_coupling': `joint_a`: no joint is labelled 'x'; the joints are none yet"],
        ),
        (
            "unknown field in a joint",
            format!("{BODIES}{hinge}axis = [0.0, 1.0, 0.0]\nspeed = 1.0\n"),
            vec!["test.toml:21:1: unknown field `speed` in joint #1 (hinge 'a' to 'b'), expected one of"],
        ),
    ];
    let mut failures = Vec::new();
    for (what, text, expected) in cases {
        let e = parse_err(&text);
        let shown = e.to_string();
        for s in expected {
            let ok = match s.strip_prefix('=') {
                Some(whole) => shown == whole,
                None => shown.contains(s),
            };
            if !ok {
                failures.push(format!("{what}: `{shown}` does not contain `{s}`"));
            }
        }
        if e.file != "test.toml" || e.line.is_none() {
            failures.push(format!("{what}: no file or line in {e:?}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
