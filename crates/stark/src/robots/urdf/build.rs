//! [`Simulation::add_robot`]: builds a robot's bodies, collision and visual meshes, joints,
//! actuators and contact exclusions from a URDF file.

use super::{
    check_inertia, geometry_shape, pose, resolve_uri, scan, Actuator, BodyMesh, LinkMass, Robot, RobotOptions, Source,
};
use crate::error::{Result, StarkError};
use crate::rigidbodies::joints::{JointHandle, JointKind, JointParams, DEFAULT_CONTROLLER_DELAY};
use crate::rigidbodies::{RigidBodyHandle, Shape};
use crate::simulation::Simulation;
use nalgebra::{Isometry3, Matrix3, Translation3, Unit, UnitQuaternion, Vector3};
use std::collections::{BTreeMap, HashMap, VecDeque};
use std::path::Path;

impl Simulation {
    /// Import the robot of the URDF file `urdf` as `name` (its bodies are labelled
    /// `<name>/<link>`, its joints `<name>/<joint>`; see [`crate::robots::urdf`] for what becomes
    /// what). Every error names the file, the line and the element; nothing is added to the
    /// simulation when the file is rejected before building (bad XML, numbers, structure,
    /// inertias, meshes).
    pub fn add_robot(&mut self, name: &str, urdf: impl AsRef<Path>, options: &RobotOptions) -> Result<Robot> {
        let path = urdf.as_ref();
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path)
            .map_err(|e| StarkError::InvalidInput(format!("cannot read the URDF file '{file}': {e}")))?;
        let dir = path.parent().unwrap_or(Path::new("."));
        self.add_robot_from_str(name, &text, &file, dir, options)
    }

    /// [`Simulation::add_robot`] from the text of a URDF file; `file` names it in errors and
    /// relative mesh paths are resolved against `dir`.
    pub fn add_robot_from_str(
        &mut self,
        name: &str,
        text: &str,
        file: &str,
        dir: &Path,
        options: &RobotOptions,
    ) -> Result<Robot> {
        let src = Source { file };
        if name.is_empty() || name.contains('/') {
            return Err(StarkError::InvalidInput(format!(
                "robot name '{name}' must be non-empty and contain no '/'"
            )));
        }
        let lines = scan(&src, text)?;
        let robot = urdf_rs::read_from_string(text).map_err(|e| src.err(None, "robot", e))?;
        let link_line = |l: &str| lines.links.get(l).and_then(|v| v.first().copied());
        let joint_line = |j: &str| lines.joints.get(j).copied();

        // ---- Structure: unique names, a tree with one root ----
        let mut link_index: HashMap<&str, usize> = HashMap::new();
        for (i, l) in robot.links.iter().enumerate() {
            if link_index.insert(l.name.as_str(), i).is_some() {
                let at = lines.links.get(&l.name).and_then(|v| v.get(1).copied());
                return Err(src.err(at, &format!("link '{}'", l.name), "duplicate link name"));
            }
        }
        if robot.links.is_empty() {
            return Err(src.err(None, "robot", "the robot has no links"));
        }
        let mut joint_names: HashMap<&str, usize> = HashMap::new();
        let mut parent_of: Vec<Option<usize>> = vec![None; robot.links.len()]; // joint index
        for (k, j) in robot.joints.iter().enumerate() {
            let what = format!("joint '{}'", j.name);
            if joint_names.insert(j.name.as_str(), k).is_some() {
                return Err(src.err(joint_line(&j.name), &what, "duplicate joint name"));
            }
            for (role, l) in [("parent", &j.parent.link), ("child", &j.child.link)] {
                if !link_index.contains_key(l.as_str()) {
                    return Err(src.err(
                        joint_line(&j.name),
                        &what,
                        format!("its {role} link '{l}' does not exist"),
                    ));
                }
            }
            let c = link_index[j.child.link.as_str()];
            if let Some(other) = parent_of[c] {
                return Err(src.err(
                    joint_line(&j.name),
                    &what,
                    format!(
                        "link '{}' already has the parent joint '{}' (a URDF is a tree)",
                        j.child.link, robot.joints[other].name
                    ),
                ));
            }
            if j.parent.link == j.child.link {
                return Err(src.err(joint_line(&j.name), &what, "joins a link to itself"));
            }
            parent_of[c] = Some(k);
        }
        let roots: Vec<usize> = (0..robot.links.len()).filter(|&i| parent_of[i].is_none()).collect();
        let root = match roots.as_slice() {
            [r] => *r,
            [] => return Err(src.err(None, "robot", "every link has a parent joint: the joints form a cycle")),
            many => {
                let names: Vec<&str> = many.iter().map(|&i| robot.links[i].name.as_str()).collect();
                return Err(src.err(
                    link_line(names[1]),
                    "robot",
                    format!(
                        "{} root links ({}): a URDF has exactly one",
                        many.len(),
                        names.join(", ")
                    ),
                ));
            }
        };
        // Breadth-first order from the root; links not reached lie on a cycle.
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); robot.links.len()];
        for (k, j) in robot.joints.iter().enumerate() {
            children[link_index[j.parent.link.as_str()]].push(k);
        }
        let mut order = vec![root];
        let mut queue = VecDeque::from([root]);
        while let Some(l) = queue.pop_front() {
            for &k in &children[l] {
                let c = link_index[robot.joints[k].child.link.as_str()];
                order.push(c);
                queue.push_back(c);
            }
        }
        if order.len() < robot.links.len() {
            let lost = (0..robot.links.len())
                .find(|i| !order.contains(i))
                .expect("unreached link");
            let name = &robot.links[lost].name;
            return Err(src.err(link_line(name), &format!("link '{name}'"), "lies on a cycle of joints"));
        }
        for l in options.links.keys() {
            if !link_index.contains_key(l.as_str()) {
                return Err(StarkError::InvalidInput(format!(
                    "robot '{name}': an override names the link '{l}', which {file} does not have"
                )));
            }
        }
        for j in options.joints.keys() {
            if !joint_names.contains_key(j.as_str()) {
                return Err(StarkError::InvalidInput(format!(
                    "robot '{name}': an override names the joint '{j}', which {file} does not have"
                )));
            }
        }

        // ---- Link masses ----
        let mut masses: Vec<Option<LinkMass>> = Vec::with_capacity(robot.links.len());
        for l in &robot.links {
            let what = format!("link '{}'", l.name);
            let o = options.links.get(&l.name);
            let i = &l.inertial;
            let urdf_inertia = Matrix3::new(
                i.inertia.ixx,
                i.inertia.ixy,
                i.inertia.ixz,
                i.inertia.ixy,
                i.inertia.iyy,
                i.inertia.iyz,
                i.inertia.ixz,
                i.inertia.iyz,
                i.inertia.izz,
            );
            let mut mass = i.mass.value;
            if mass < 0.0 {
                return Err(src.err(link_line(&l.name), &what, format!("negative mass {mass} kg")));
            }
            let frame = pose(&i.origin);
            let r = frame.rotation.to_rotation_matrix().into_inner();
            let mut inertia = r * urdf_inertia * r.transpose();
            if let Some(m) = o.and_then(|o| o.mass_kg) {
                if !(m > 0.0 && m.is_finite()) {
                    return Err(StarkError::InvalidInput(format!(
                        "robot '{name}' link '{}': the mass_kg override {m} must be positive",
                        l.name
                    )));
                }
                if mass > 0.0 {
                    inertia *= m / mass;
                }
                mass = m;
            }
            if let Some(j) = o.and_then(|o| o.inertia_kg_m2) {
                inertia = Matrix3::from_row_slice(&j.concat());
                if (inertia - inertia.transpose()).norm() > 1e-9 * inertia.norm()
                    || !inertia.iter().all(|c| c.is_finite())
                {
                    return Err(StarkError::InvalidInput(format!(
                        "robot '{name}' link '{}': the inertia_kg_m2 override must be finite and symmetric",
                        l.name
                    )));
                }
            }
            if mass == 0.0 {
                masses.push(None);
                continue;
            }
            check_inertia(&inertia).map_err(|m| src.err(link_line(&l.name), &what, m))?;
            masses.push(Some(LinkMass {
                mass_kg: mass,
                com: frame.translation.vector,
                inertia,
            }));
        }

        // ---- Poses at the initial configuration ----
        let base = Isometry3::from_parts(Translation3::from(options.position_m), options.orientation);
        let initial = |j: &urdf_rs::Joint| options.joints.get(&j.name).and_then(|o| o.position).unwrap_or(0.0);
        let mut link_pose = vec![Isometry3::identity(); robot.links.len()];
        link_pose[root] = base;
        for &l in order.iter().skip(1) {
            let j = &robot.joints[parent_of[l].expect("non-root")];
            let p = link_pose[link_index[j.parent.link.as_str()]];
            let axis = Vector3::new(j.axis.xyz[0], j.axis.xyz[1], j.axis.xyz[2]);
            let q = initial(j);
            let motion = match j.joint_type {
                urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous if q != 0.0 => Isometry3::from_parts(
                    Translation3::identity(),
                    UnitQuaternion::from_axis_angle(&Unit::new_normalize(axis), q),
                ),
                urdf_rs::JointType::Prismatic if q != 0.0 => {
                    Isometry3::from_parts(Translation3::from(axis.normalize() * q), UnitQuaternion::identity())
                }
                _ => Isometry3::identity(),
            };
            link_pose[l] = p * pose(&j.origin) * motion;
        }

        // ---- Groups of links that form one body ----
        let mut group = (0..robot.links.len()).collect::<Vec<usize>>(); // link → group's top link
        for &l in order.iter().skip(1) {
            let j = &robot.joints[parent_of[l].expect("non-root")];
            let parent = link_index[j.parent.link.as_str()];
            let fixed = j.joint_type == urdf_rs::JointType::Fixed;
            let massless = masses[l].is_none();
            if fixed && (options.merge_fixed_joints || massless || masses[parent].is_none()) {
                group[l] = group[parent];
            } else if massless {
                return Err(src.err(
                    link_line(&robot.links[l].name),
                    &format!("link '{}'", robot.links[l].name),
                    format!(
                        "has no mass but moves on the {:?} joint '{}': give it an <inertial> (or a mass_kg override)",
                        j.joint_type, j.name
                    ),
                ));
            }
        }
        let tops: Vec<usize> = order.iter().copied().filter(|&l| group[l] == l).collect();

        // Mass properties of each group in world coordinates.
        struct Group {
            label_link: usize,
            mass_kg: f64,
            com: Vector3<f64>,
            orientation: UnitQuaternion<f64>,
            inertia_world: Matrix3<f64>,
        }
        let mut groups: HashMap<usize, Group> = HashMap::new();
        for &top in &tops {
            let members: Vec<usize> = order.iter().copied().filter(|&l| group[l] == top).collect();
            let mut mass = 0.0;
            let mut first = Vector3::zeros();
            for &l in &members {
                if let Some(m) = masses[l] {
                    mass += m.mass_kg;
                    first += (link_pose[l] * nalgebra::Point3::from(m.com)).coords * m.mass_kg;
                }
            }
            if mass == 0.0 {
                if top == root && options.fixed_base {
                    continue; // the world
                }
                return Err(src.err(
                    link_line(&robot.links[top].name),
                    &format!("link '{}'", robot.links[top].name),
                    "neither it nor any link fixed to it has a mass (give an <inertial>, a mass_kg override, or fixed_base)",
                ));
            }
            let com = first / mass;
            let mut inertia = Matrix3::zeros();
            for &l in &members {
                if let Some(m) = masses[l] {
                    let r = link_pose[l].rotation.to_rotation_matrix().into_inner();
                    let d = (link_pose[l] * nalgebra::Point3::from(m.com)).coords - com;
                    inertia += r * m.inertia * r.transpose()
                        + (Matrix3::identity() * d.norm_squared() - d * d.transpose()) * m.mass_kg;
                }
            }
            let label_link = members.iter().copied().find(|&l| masses[l].is_some()).unwrap_or(top);
            groups.insert(
                top,
                Group {
                    label_link,
                    mass_kg: mass,
                    com,
                    orientation: link_pose[top].rotation,
                    inertia_world: inertia,
                },
            );
        }

        // ---- Collision and visual geometry (loaded before anything is added) ----
        let roots_paths = &options.package_paths;
        // Per group: body-frame vertices, triangles and a contact thickness override.
        let mut collision: HashMap<usize, BodyMesh> = HashMap::new();
        let mut visuals: Vec<(usize, BodyMesh)> = Vec::new();
        let to_body = |top: usize, p: Vector3<f64>| -> Vector3<f64> {
            match groups.get(&top) {
                Some(g) => g.orientation.inverse() * (p - g.com),
                None => p,
            }
        };
        for &l in &order {
            let link = &robot.links[l];
            let top = group[l];
            let o = options.links.get(&link.name);
            let mut elements: Vec<(Shape, Isometry3<f64>, Option<usize>)> = Vec::new();
            if let Some(shape) = o.and_then(|o| o.collision_shape.as_ref()) {
                elements.push((shape.clone(), Isometry3::identity(), link_line(&link.name)));
            } else if let Some(mesh) = o.and_then(|o| o.collision_mesh.as_ref()) {
                let uri = mesh.to_string_lossy();
                let path = resolve_uri(&uri, dir, roots_paths).map_err(|m| {
                    src.err(
                        link_line(&link.name),
                        &format!("link '{}' collision_mesh", link.name),
                        m,
                    )
                })?;
                elements.push((Shape::mesh_file(path), Isometry3::identity(), link_line(&link.name)));
            } else {
                for (k, c) in link.collision.iter().enumerate() {
                    let at = lines.collisions.get(&link.name).and_then(|v| v.get(k).copied());
                    let shape = geometry_shape(&c.geometry, dir, roots_paths, options.cylinder_slices)
                        .map_err(|m| src.err(at, &format!("link '{}' <collision>", link.name), m))?;
                    elements.push((shape, pose(&c.origin), at));
                }
            }
            for (shape, origin, at) in elements {
                let mesh = shape
                    .surface_mesh()
                    .map_err(|e| src.err(at, &format!("link '{}' <collision> {}", link.name, shape.kind()), e))?;
                let entry = collision.entry(top).or_insert_with(|| (Vec::new(), Vec::new(), None));
                let offset = entry.0.len();
                let frame = link_pose[l] * origin;
                entry.0.extend(
                    mesh.vertices
                        .iter()
                        .map(|v| to_body(top, (frame * nalgebra::Point3::from(*v)).coords)),
                );
                entry.1.extend(mesh.elements.iter().map(|t| t.map(|i| i + offset)));
                if let Some(t) = o.and_then(|o| o.contact_thickness_m) {
                    entry.2 = Some(t);
                }
            }
            if options.visual_meshes && groups.contains_key(&top) {
                for (k, v) in link.visual.iter().enumerate() {
                    let at = lines.visuals.get(&link.name).and_then(|v| v.get(k).copied());
                    let shape = geometry_shape(&v.geometry, dir, roots_paths, options.cylinder_slices)
                        .map_err(|m| src.err(at, &format!("link '{}' <visual>", link.name), m))?;
                    let mesh = shape
                        .surface_mesh()
                        .map_err(|e| src.err(at, &format!("link '{}' <visual> {}", link.name, shape.kind()), e))?;
                    let frame = link_pose[l] * pose(&v.origin);
                    let local = mesh
                        .vertices
                        .iter()
                        .map(|p| to_body(top, (frame * nalgebra::Point3::from(*p)).coords))
                        .collect();
                    visuals.push((top, (local, mesh.elements, None)));
                }
            }
        }
        // Joint checks that need no simulation: axes, actuators fit their joints.
        for j in &robot.joints {
            let what = format!("joint '{}'", j.name);
            let axis = Vector3::new(j.axis.xyz[0], j.axis.xyz[1], j.axis.xyz[2]);
            let moving = !matches!(j.joint_type, urdf_rs::JointType::Fixed | urdf_rs::JointType::Floating);
            if moving && axis.norm() < 1e-12 {
                return Err(src.err(joint_line(&j.name), &what, "the axis is zero"));
            }
            if let Some(m) = &j.mimic {
                if !joint_names.contains_key(m.joint.as_str()) {
                    return Err(src.err(
                        joint_line(&j.name),
                        &what,
                        format!("<mimic> names the joint '{}', which does not exist", m.joint),
                    ));
                }
            }
            if let Some(a) = options.joints.get(&j.name).and_then(|o| o.actuator.as_ref()) {
                let hinge = matches!(
                    j.joint_type,
                    urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous
                );
                let slider = j.joint_type == urdf_rs::JointType::Prismatic;
                let fits = match a {
                    Actuator::Motor { .. } => hinge,
                    Actuator::Press { .. } => slider,
                    Actuator::Servo { .. } | Actuator::SpringDamper { .. } => hinge || slider,
                };
                if !fits {
                    return Err(StarkError::InvalidInput(format!(
                        "robot '{name}': the actuator {a:?} does not fit the {:?} joint '{}' (motors go on revolute and \
                         continuous joints, presses on prismatic ones)",
                        j.joint_type, j.name
                    )));
                }
            }
        }

        // ---- Build ----
        let mut body_of_top: HashMap<usize, RigidBodyHandle> = HashMap::new();
        let mut bodies = Vec::new();
        for &top in &tops {
            let Some(g) = groups.get(&top) else { continue };
            let r = g.orientation.to_rotation_matrix().into_inner();
            let local = r.transpose() * g.inertia_world * r;
            let local = 0.5 * (local + local.transpose());
            let link = &robot.links[g.label_link].name;
            let label = format!("{name}/{link}");
            let body = self.add_rigid_body(&label, g.mass_kg, local, g.com, g.orientation)?;
            body_of_top.insert(top, body);
            bodies.push((link.clone(), body));
        }
        let body_of_link = |l: usize| body_of_top.get(&group[l]).copied();
        let mut collision_meshes = Vec::new();
        for &top in &tops {
            let (Some(body), Some((vertices, triangles, thickness))) = (body_of_top.get(&top), collision.remove(&top))
            else {
                continue;
            };
            match thickness
                .or(options.contact_thickness_m)
                .or(self.settings.contact.default_thickness_m)
            {
                Some(t) => {
                    collision_meshes.push(self.add_rigid_collision_mesh(*body, &vertices, &triangles, Some(t))?);
                }
                None => {
                    self.add_rigid_output_mesh(*body, &vertices, &triangles)?;
                }
            }
        }
        for (top, (vertices, triangles, _)) in visuals {
            if let Some(body) = body_of_top.get(&top) {
                self.add_rigid_output_mesh(*body, &vertices, &triangles)?;
            }
        }

        let params = options.joint_params;
        let mut joints: BTreeMap<String, JointHandle> = BTreeMap::new();
        let mut extra = Vec::new();
        let mut initial_positions = BTreeMap::new();
        let mut adjacent = Vec::new();
        for &l in order.iter().skip(1) {
            let j = &robot.joints[parent_of[l].expect("non-root")];
            let parent = link_index[j.parent.link.as_str()];
            let (a, b) = (body_of_link(parent), body_of_link(l));
            if group[parent] == group[l] {
                continue;
            }
            let Some(b) = b else { continue };
            let label = format!("{name}/{}", j.name);
            let located = |e: StarkError| src.err(joint_line(&j.name), &format!("joint '{}'", j.name), e);
            let frame = link_pose[parent] * pose(&j.origin);
            let point = frame.translation.vector;
            let axis_local = Vector3::new(j.axis.xyz[0], j.axis.xyz[1], j.axis.xyz[2]);
            let axis = if axis_local.norm() > 0.0 {
                frame.rotation * axis_local.normalize()
            } else {
                Vector3::z()
            };
            let o = options.joints.get(&j.name);
            let q0 = initial(j);
            initial_positions.insert(j.name.clone(), q0);
            let effort = |given: Option<f64>| -> Result<f64> {
                let e = given.unwrap_or(j.limit.effort);
                if e > 0.0 && e.is_finite() {
                    Ok(e)
                } else {
                    Err(located(StarkError::InvalidInput(
                        "the actuator needs an effort cap: the URDF <limit effort> is 0 or missing; give one".into(),
                    )))
                }
            };
            let speed = |target: f64| {
                let v = j.limit.velocity;
                if v > 0.0 && v.is_finite() {
                    target.clamp(-v, v)
                } else {
                    target
                }
            };
            let use_hinge = matches!(
                j.joint_type,
                urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous
            );
            let main = match j.joint_type {
                urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous | urdf_rs::JointType::Prismatic => {
                    let actuator = o.and_then(|o| o.actuator.clone());
                    let (point_m, axis_dir) = (point.into(), axis.into());
                    let kind = match (&actuator, use_hinge) {
                        (
                            Some(Actuator::Motor {
                                target_rad_s,
                                max_torque_n_m,
                                delay_rad_s,
                                ..
                            }),
                            _,
                        ) => JointKind::Motor {
                            point_m,
                            axis: axis_dir,
                            target_velocity_deg_s: speed(*target_rad_s).to_degrees(),
                            max_torque_n_m: effort(*max_torque_n_m)?,
                            delay_deg_s: delay_rad_s.map(f64::to_degrees),
                        },
                        (
                            Some(Actuator::Press {
                                target_m_s,
                                max_force_n,
                            }),
                            _,
                        ) => JointKind::PrismaticPress {
                            point_m,
                            axis: axis_dir,
                            target_velocity_m_s: speed(*target_m_s),
                            max_force_n: effort(*max_force_n)?,
                            delay_m_s: DEFAULT_CONTROLLER_DELAY,
                        },
                        (
                            Some(Actuator::Servo {
                                target,
                                max_effort,
                                response_time_s,
                            }),
                            true,
                        ) => JointKind::HingeServo {
                            point_m,
                            axis: axis_dir,
                            target_deg: (target - q0).to_degrees(),
                            max_torque_n_m: effort(*max_effort)?,
                            response_time_s: *response_time_s,
                        },
                        (
                            Some(Actuator::Servo {
                                target,
                                max_effort,
                                response_time_s,
                            }),
                            false,
                        ) => JointKind::PrismaticServo {
                            point_m,
                            axis: axis_dir,
                            target_m: target - q0,
                            max_force_n: effort(*max_effort)?,
                            response_time_s: *response_time_s,
                        },
                        (_, true) => JointKind::Hinge {
                            point_m,
                            axis: axis_dir,
                        },
                        (_, false) => JointKind::Prismatic {
                            point_m,
                            axis: axis_dir,
                        },
                    };
                    let h = self.add_joint(&label, a, Some(b), kind, params).map_err(located)?;
                    if let Some(Actuator::Motor { drive_only: true, .. }) = &actuator {
                        self.set_motor_drive_only(&h, true).map_err(located)?;
                    }
                    let limited = j.joint_type != urdf_rs::JointType::Continuous && j.limit.lower < j.limit.upper;
                    if limited {
                        let (lo, hi) = (j.limit.lower - q0, j.limit.upper - q0);
                        let limit_label = format!("{label}.limits");
                        let range = if !use_hinge {
                            Some(JointKind::SliderRange {
                                point_m,
                                axis: axis_dir,
                                limits_m: [lo, hi],
                            })
                        } else if hi - lo <= std::f64::consts::TAU {
                            Some(JointKind::HingeRange {
                                point_m,
                                axis: axis_dir,
                                limits_deg: [lo.to_degrees(), hi.to_degrees()],
                            })
                        } else {
                            None
                        };
                        if let Some(range) = range {
                            extra.push(
                                self.add_joint(&limit_label, a, Some(b), range, params)
                                    .map_err(located)?,
                            );
                        }
                    }
                    let urdf_damping = j.dynamics.as_ref().map_or(0.0, |d| d.damping);
                    let damping = o.and_then(|o| o.damping).unwrap_or(urdf_damping);
                    let spring = match &actuator {
                        Some(Actuator::SpringDamper {
                            stiffness,
                            rest,
                            damping: d,
                        }) => Some(("spring", *stiffness, rest - q0, d + damping)),
                        _ if damping > 0.0 => Some(("damping", 0.0, 0.0, damping)),
                        _ => None,
                    };
                    if let Some((what, spring_stiffness, rest, damping)) = spring {
                        let kind = JointKind::JointSpring {
                            joint: h.label.clone(),
                            spring_stiffness,
                            rest,
                            damping,
                        };
                        let spring_label = format!("{label}.{what}");
                        let params = JointParams::default();
                        extra.push(
                            self.add_joint(&spring_label, None, None, kind, params)
                                .map_err(located)?,
                        );
                    }
                    Some(h)
                }
                urdf_rs::JointType::Fixed => {
                    // Not merged (merge_fixed_joints off): glue the two bodies.
                    let kind = match a {
                        Some(_) => JointKind::Attachment {},
                        None => JointKind::Fix {},
                    };
                    Some(self.add_joint(&label, a, Some(b), kind, params).map_err(located)?)
                }
                urdf_rs::JointType::Floating => None,
                urdf_rs::JointType::Planar => {
                    let kind = JointKind::Planar {
                        point_m: point.into(),
                        normal: axis.into(),
                    };
                    Some(self.add_joint(&label, a, Some(b), kind, params).map_err(located)?)
                }
                urdf_rs::JointType::Spherical => {
                    let kind = JointKind::Ball { point_m: point.into() };
                    Some(self.add_joint(&label, a, Some(b), kind, params).map_err(located)?)
                }
            };
            if let Some(h) = main {
                joints.insert(j.name.clone(), h);
            }
            if let Some(a) = a {
                adjacent.push((a, b));
            }
        }
        // Mimic couplings, once every joint exists.
        for j in &robot.joints {
            let Some(m) = &j.mimic else { continue };
            let located = |e: StarkError| src.err(joint_line(&j.name), &format!("joint '{}' <mimic>", j.name), e);
            let (Some(hb), Some(ha)) = (joints.get(&j.name), joints.get(&m.joint)) else {
                return Err(located(StarkError::InvalidInput(format!(
                    "both '{}' and '{}' must be moving joints",
                    j.name, m.joint
                ))));
            };
            let multiplier = m.multiplier.unwrap_or(1.0);
            let q0a = initial_positions.get(&m.joint).copied().unwrap_or(0.0);
            let q0b = initial_positions.get(&j.name).copied().unwrap_or(0.0);
            // URDF: q_b = m·q_a + c in URDF coordinates; the joints measure from their start.
            let offset = m.offset.unwrap_or(0.0) + multiplier * q0a - q0b;
            let kind = JointKind::JointCoupling {
                joint_a: ha.label.clone(),
                joint_b: hb.label.clone(),
                multiplier,
                offset,
            };
            let mimic_label = format!("{name}/{}.mimic", j.name);
            let h = self
                .add_joint(&mimic_label, None, None, kind, options.mimic_params)
                .map_err(located)?;
            extra.push(h);
        }
        if options.fixed_base {
            if let Some(body) = body_of_link(root) {
                let label = format!("{name}/fixed_base");
                extra.push(self.add_joint(&label, None, Some(body), JointKind::Fix {}, params)?);
            }
        }
        // Contact between the robot's own links.
        if !options.self_collision {
            for (i, (_, a)) in bodies.iter().enumerate() {
                for (_, b) in &bodies[i + 1..] {
                    self.set_bodies_collision(*a, *b, false)?;
                }
            }
        } else if !options.adjacent_links_collide {
            for (a, b) in adjacent {
                self.set_bodies_collision(a, b, false)?;
            }
        }
        let links = robot
            .links
            .iter()
            .enumerate()
            .map(|(i, l)| (l.name.clone(), body_of_link(i)))
            .collect();
        Ok(Robot {
            name: name.to_string(),
            links,
            joints,
            extra_joints: extra,
            bodies,
            initial_positions,
            collision_meshes,
        })
    }
}
