//! The paper's robot–towel experiment (§IV-A, Fig. 1, Table I): a Kobuki vacuum robot drives at
//! 0.26 m/s into a towel lying on the floor, in eight towel configurations on two floors
//! (carpet μ 1.0, polished μ 0.2). Each run is classified as the robot pushing the towel (P),
//! driving over it (O) or getting stuck (S) ([`super::robot_towel_outcome`]).
//!
//! The robot is the project's own URDF (`assets/robots/kobuki_paper.urdf`, written from the
//! paper's numbers) imported with overrides: the fitted body mesh `kobuki_collision.obj`, the
//! suspension springs and the wheel motors. The towel is the original's 57 × 101 grid
//! (1.35 × 0.75 m; the paper's text says 1.75 m): the flat grid is the rest shape, a
//! configuration file the initial positions. Both meshes are the original's (Apache-2.0,
//! `assets/paper-scenes`).
//!
//! Two parameter sets ([`ParamSet`]): `original`, the values of the original's code that produced
//! Table I, and `paper`, the values the paper's text states where they differ.

use super::robot_towel_outcome::Sample;
use crate::contact::ContactHandle;
use crate::deformables::NodeSetHandle;
use crate::error::{Result, StarkError};
use crate::presets::{meshes, FixedSurfaceHandle, SurfaceMaterial};
use crate::rigidbodies::joints::JointHandle;
use crate::rigidbodies::{RigidBodyHandle, Shape};
use crate::robots::urdf::{Actuator, JointOverride, LinkOverride, Robot, RobotOptions};
use crate::settings::Settings;
use crate::simulation::Simulation;
use nalgebra::Vector3;
use std::path::Path;

/// The robot's URDF (the project's own).
pub const KOBUKI_URDF: &str = include_str!("../../assets/robots/kobuki_paper.urdf");
/// The fitted collision mesh of the robot's body (the original's, about the body centre).
pub const KOBUKI_COLLISION_OBJ: &str = include_str!("../../assets/paper-scenes/kobuki_collision.obj");
/// The towel's rest shape: the flat grid.
const TOWEL_FLAT_OBJ: &str = include_str!("../../assets/paper-scenes/towel_flat.obj");

/// One towel configuration: a state of the flat grid.
pub struct Configuration {
    /// Short name.
    pub name: &'static str,
    /// The mesh file (in `assets/paper-scenes`).
    pub file: &'static str,
    /// Its text.
    pub obj: &'static str,
}

/// The eight configurations in the paper's order (Table I, Fig. 3).
pub const CONFIGURATIONS: [Configuration; 8] = [
    Configuration {
        name: "flat",
        file: "towel_flat.obj",
        obj: TOWEL_FLAT_OBJ,
    },
    Configuration {
        name: "1 fold",
        file: "towel_1fold.obj",
        obj: include_str!("../../assets/paper-scenes/towel_1fold.obj"),
    },
    Configuration {
        name: "2 folds",
        file: "towel_2folds.obj",
        obj: include_str!("../../assets/paper-scenes/towel_2folds.obj"),
    },
    Configuration {
        name: "3 folds, folded side",
        file: "towel_3folds_foldedside.obj",
        obj: include_str!("../../assets/paper-scenes/towel_3folds_foldedside.obj"),
    },
    Configuration {
        name: "3 folds, open side",
        file: "towel_3folds_openside.obj",
        obj: include_str!("../../assets/paper-scenes/towel_3folds_openside.obj"),
    },
    Configuration {
        name: "rolled, rolled side",
        file: "towel_rolled_rolledside.obj",
        obj: include_str!("../../assets/paper-scenes/towel_rolled_rolledside.obj"),
    },
    Configuration {
        name: "rolled, open side",
        file: "towel_rolled_openside.obj",
        obj: include_str!("../../assets/paper-scenes/towel_rolled_openside.obj"),
    },
    Configuration {
        name: "rolled sideways",
        file: "towel_rolled_side.obj",
        obj: include_str!("../../assets/paper-scenes/towel_rolled_side.obj"),
    },
];

/// The lab's outcomes (Table I), configurations 1–8: carpet, then polished.
pub const LAB_OUTCOMES: [&str; 2] = ["OOOSSSSS", "OOPPPPOS"];
/// The original Stark's outcomes (Table I).
pub const PAPER_SIMULATION_OUTCOMES: [&str; 2] = ["OOOSSSSS", "OOPPPPOS"];

/// The floor.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Floor {
    /// Towel–floor friction 1.0.
    Carpet,
    /// Towel–floor friction 0.2.
    Polished,
}

impl Floor {
    /// Towel–floor friction coefficient.
    pub fn towel_friction(self) -> f64 {
        match self {
            Floor::Carpet => 1.0,
            Floor::Polished => 0.2,
        }
    }
    /// Its name in scene names.
    pub fn name(self) -> &'static str {
        match self {
            Floor::Carpet => "carpet",
            Floor::Polished => "polished",
        }
    }
}

/// Which values to use where the original's code and the paper's text differ.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ParamSet {
    /// The original's code (Table I's simulations): body 2.951 kg (3.551 kg in all), towel
    /// 0.5 kg/m², strain limit 110% (Green strain 1.1, effectively off), strain and bending
    /// damping ratio 0.2.
    Original,
    /// The paper's text: 2.951 kg in all (body 2.351 kg), towel 0.484 kg, strain limit 10%,
    /// damping ratio 0.1.
    Paper,
}

/// One run of the suite.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Case {
    /// The floor.
    pub floor: Floor,
    /// The towel configuration, 1–8.
    pub configuration: usize,
    /// The parameter set.
    pub params: ParamSet,
}

impl Case {
    /// The built-in scene name: `kobuki_towel_<floor>_<configuration>`, with `_paper` for the
    /// parameter set `paper`.
    pub fn name(&self) -> String {
        let suffix = match self.params {
            ParamSet::Original => "",
            ParamSet::Paper => "_paper",
        };
        format!("kobuki_towel_{}_{}{suffix}", self.floor.name(), self.configuration)
    }

    /// The case of a built-in scene name ([`Case::name`]).
    pub fn from_name(name: &str) -> Option<Case> {
        let rest = name.strip_prefix("kobuki_towel_")?;
        let (rest, params) = match rest.strip_suffix("_paper") {
            Some(r) => (r, ParamSet::Paper),
            None => (rest, ParamSet::Original),
        };
        let (floor, c) = rest.rsplit_once('_')?;
        let floor = match floor {
            "carpet" => Floor::Carpet,
            "polished" => Floor::Polished,
            _ => return None,
        };
        let configuration: usize = c.parse().ok()?;
        (1..=8).contains(&configuration).then_some(Case {
            floor,
            configuration,
            params,
        })
    }

    /// The lab's outcome of this case (Table I).
    pub fn lab_outcome(&self) -> char {
        self.table_one(&LAB_OUTCOMES)
    }

    /// The original Stark's outcome of this case (Table I's simulation row).
    pub fn paper_simulation_outcome(&self) -> char {
        self.table_one(&PAPER_SIMULATION_OUTCOMES)
    }

    /// This case's entry in a pair of Table I rows (carpet, polished).
    fn table_one(&self, rows: &[&str; 2]) -> char {
        let row = rows[(self.floor == Floor::Polished) as usize];
        row.as_bytes()[self.configuration - 1] as char
    }
}

/// Simulated duration of a run, s.
pub const DURATION_S: f64 = 6.0;
/// Contact distance d̂ = the towel's thickness, m.
pub const DHAT_M: f64 = 3.25e-3;
/// The towel's offset from the robot's centre along the driving direction, m.
const TOWEL_OFFSET_Y_M: f64 = 0.5;
/// Height of the body centre above the floor at rest (casters on the floor), m. Contact keeps
/// the floor's and the robot's surfaces d̂ apart (their two contact thicknesses), as it keeps the
/// towel d̂ above the floor: heights are measured from there, d̂ above the floor's mesh.
const BODY_HEIGHT_M: f64 = 0.057;
/// The robot starts this far above its resting height, m.
const DROP_M: f64 = 0.005;
/// Wheel motors: target rate (0.26 m/s on r = 0.035 m), rad/s; stall torque, N·m.
pub const MOTOR_TARGET_RAD_S: f64 = 7.43;
/// Stall torque of each drive motor, N·m.
pub const MOTOR_MAX_TORQUE_N_M: f64 = 0.0666;
/// Rate error over which the motor torque rises smoothly to its cap, rad/s.
pub const MOTOR_TRANSITION_RAD_S: f64 = 1.0;
/// Suspension spring stiffness, N/m (its damping, 2 N·s/m, is in the URDF).
const SUSPENSION_STIFFNESS_N_M: f64 = 1.6e3;
/// Mass of the body in the URDF (the `original` set), kg.
const BODY_MASS_KG: f64 = 2.951;
/// Mass of each caster, arm and wheel, kg.
const PART_MASS_KG: f64 = 0.1;

/// The suspension springs' preload: the slider coordinate at which a spring is free (the
/// URDF's zero is the resting pose, axle 0.022 m below the body centre), m.
///
/// The issue gives the spring (rest length 0.035 m, 1.6e3 N/m) and the resting pose (body centre
/// 0.057 m above the floor, casters on it) but not the spring's anchors. With the centre of mass
/// over the axles the two springs carry the whole sprung weight (body and casters) at rest, so
/// each is compressed by `W/2k` there (9.7 mm for `original`: with the rest length 0.035 m,
/// the spring's anchor on the body sits 3.3 mm above the body centre). Reading the rest length
/// from the body centre to the axle instead preloads each spring by 20.8 N at the resting pose,
/// 5 N more than its share: the body rode 2.2 mm high on its drive wheels and rear caster,
/// pitched 0.6–0.9° nose-up, the front of its collision mesh 1.9 cm above the floor where the
/// paper states a clearance of 1.35 cm (1.5 cm at 0.057 m).
fn suspension_free_coordinate_m(params: ParamSet, gravity_m_s2: f64) -> f64 {
    let sprung_kg = body_mass_kg(params) + 2.0 * PART_MASS_KG;
    -sprung_kg * gravity_m_s2 / (2.0 * SUSPENSION_STIFFNESS_N_M)
}

/// Mass of the robot's body, kg: `original` 2.951 kg (3.551 kg in all), `paper` 2.951 kg in all.
fn body_mass_kg(params: ParamSet) -> f64 {
    match params {
        ParamSet::Original => BODY_MASS_KG,
        ParamSet::Paper => BODY_MASS_KG - 6.0 * PART_MASS_KG,
    }
}

/// The robot and towel of a built run, for sampling.
pub struct RobotTowel {
    /// The case.
    pub case: Case,
    /// The robot.
    pub robot: Robot,
    /// The robot's body.
    pub body: RigidBodyHandle,
    /// The body's collision-mesh vertices.
    pub body_mesh: NodeSetHandle,
    /// The towel's nodes.
    pub towel: NodeSetHandle,
    /// The towel's contact object.
    pub towel_contact: ContactHandle,
    /// The drive wheels' contact objects (left, right).
    pub wheel_contacts: [ContactHandle; 2],
    /// The drive motors (left, right).
    pub motors: [JointHandle; 2],
    /// The suspension sliders (left, right).
    pub suspensions: [JointHandle; 2],
    /// The sliders' coordinate at which the springs are free, m.
    pub suspension_free_m: f64,
}

/// Per-step record of a run (a line of the probe log `<scene>.robot_towel.jsonl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Record {
    /// The classifier's sample.
    pub sample: Sample,
    /// Motor torques (left, right), N·m.
    pub motor_torque_n_m: [f64; 2],
    /// Wheel rates relative to their arms (left, right), rad/s; positive forward.
    pub wheel_speed_rad_s: [f64; 2],
    /// Suspension compression (left, right): the spring's free length minus its length, m.
    pub suspension_compression_m: [f64; 2],
    /// Robot body centre, m.
    pub robot_position_m: [f64; 3],
    /// Robot heading: the body's +y axis angle from +y about z, deg.
    pub robot_yaw_deg: f64,
    /// Robot pitch: the body's +y axis angle above the floor, deg (front up positive).
    pub robot_pitch_deg: f64,
    /// Towel centroid, m.
    pub towel_centroid_m: [f64; 3],
}

impl RobotTowel {
    /// The state of the run now.
    pub fn record(&self, sim: &Simulation) -> Record {
        let towel = sim.positions(self.towel);
        let n = towel.len().max(1) as f64;
        let centroid = towel.iter().sum::<Vector3<f64>>() / n;
        let far = towel.iter().map(|p| p.y).fold(f64::NEG_INFINITY, f64::max);
        let rear = sim
            .positions(self.body_mesh)
            .iter()
            .map(|p| p.y)
            .fold(f64::INFINITY, f64::min);
        let towel_object = self.towel_contact.0 as u16;
        let on_towel = self.wheel_contacts.iter().any(|w| {
            let w = w.0 as u16;
            sim.contact
                .pairs()
                .iter()
                .any(|p| p.objects == [w, towel_object] || p.objects == [towel_object, w])
        });
        let motor = self.motors.each_ref().map(|m| sim.joint_state(m));
        let suspension = self.suspensions.each_ref().map(|j| sim.joint_state(j));
        let q = sim.body_orientation(self.body);
        let forward = q * Vector3::y();
        let p = sim.body_position(self.body);
        let torque = motor.map(|m| m.driver_effort);
        Record {
            sample: Sample {
                time_s: sim.time(),
                robot_y_m: p.y,
                robot_rear_y_m: rear,
                towel_centroid_y_m: centroid.y,
                towel_far_edge_y_m: far,
                drive_wheel_on_towel: on_towel,
                motor_torque_fraction: 0.5 * (torque[0].abs() + torque[1].abs()) / MOTOR_MAX_TORQUE_N_M,
            },
            motor_torque_n_m: torque,
            wheel_speed_rad_s: motor.map(|m| m.coordinate_rate.unwrap_or(0.0)),
            // The slider coordinate is the arm's rise from the resting pose; the spring is
            // free at `suspension_free_m`.
            suspension_compression_m: suspension.map(|s| s.coordinate.unwrap_or(0.0) - self.suspension_free_m),
            robot_position_m: p.into(),
            robot_yaw_deg: (-forward.x).atan2(forward.y).to_degrees(),
            robot_pitch_deg: forward.z.atan2(forward.xy().norm()).to_degrees(),
            towel_centroid_m: centroid.into(),
        }
    }
}

fn parse(obj: &str, file: &str) -> Result<meshes::Mesh<3>> {
    Ok(crate::io::mesh_files::parse_obj(obj, file)?)
}

/// The towel in configuration `configuration` (1–8): the flat grid (rest shape, with its
/// triangles) and the configuration's positions of the same vertices.
pub fn towel_meshes(configuration: usize) -> Result<(meshes::Mesh<3>, Vec<Vector3<f64>>)> {
    let Some(c) = configuration.checked_sub(1).and_then(|i| CONFIGURATIONS.get(i)) else {
        return Err(StarkError::InvalidInput(format!(
            "towel configuration {configuration} does not exist: the paper's are 1–8"
        )));
    };
    let rest = parse(TOWEL_FLAT_OBJ, "towel_flat.obj")?;
    let initial = parse(c.obj, c.file)?;
    if initial.elements != rest.elements || initial.vertices.len() != rest.vertices.len() {
        return Err(StarkError::InvalidInput(format!(
            "{} and towel_flat.obj must share their connectivity",
            c.file
        )));
    }
    Ok((rest, initial.vertices))
}

/// The towel's material in a parameter set: Neo-Hookean membrane E·h = 50 N/m (E = 1.5e4 Pa at
/// h = 3.25 mm), ν 0.3, bending 5e-6, inertial damping 2, contact thickness d̂/2.
///
/// The damping is Rayleigh's, as the paper states it ("an inertial damping factor of 2 and a 0.1
/// ratio relative to the stiffness for both the strain and bending damping"): a ratio β times
/// the stiffness, strain `c = β·h·E` and bending `c = β·k` (the convention of the original's
/// and this project's cloth preset). Read as absolute coefficients, 0.2 N·m·s of bending damping
/// would be 4·10⁴ s times the bending stiffness: folds could not drape.
pub fn towel_material(params: ParamSet) -> SurfaceMaterial {
    let thickness = DHAT_M / 2.0;
    let h = DHAT_M;
    let e = 1.5e4;
    let bending_stiffness = 5e-6;
    let (density, damping_ratio, strain_limit) = match params {
        ParamSet::Original => (0.5, 0.2, 1.1),
        // 0.484 kg over the grid's 1.35 × 0.75 m.
        ParamSet::Paper => (0.484 / (1.35 * 0.75), 0.1, 0.1),
    };
    SurfaceMaterial {
        inertia: crate::deformables::InertiaParams {
            density,
            damping: 2.0,
            quasistatic: false,
        },
        strain: crate::deformables::TriangleStrainParams {
            thickness_m: h,
            youngs_modulus: e,
            poissons_ratio: 0.3,
            damping: damping_ratio * h * e,
            strain_limit,
            ..Default::default()
        },
        bending: crate::presets::Bending::Flat(crate::deformables::FlatBendingParams {
            stiffness: bending_stiffness,
            damping: damping_ratio * bending_stiffness,
        }),
        contact_thickness_m: Some(thickness),
    }
}

/// Build a run of the suite (see the module docs for the model).
pub fn build(mut settings: Settings, case: Case) -> Result<(Simulation, RobotTowel)> {
    let (_, initial) = towel_meshes(case.configuration)?;
    settings.name = case.name();
    build_with_towel(settings, case, &initial)
}

/// [`build`] with the towel's initial positions given (a new configuration, one position per
/// vertex of the flat grid, in its order, the towel's far side along +y as in the paper's files);
/// `case.configuration` is then only a label and `settings.name` is kept.
pub fn build_with_towel(
    mut settings: Settings,
    case: Case,
    towel_positions_m: &[Vector3<f64>],
) -> Result<(Simulation, RobotTowel)> {
    let rest = parse(TOWEL_FLAT_OBJ, "towel_flat.obj")?;
    if towel_positions_m.len() != rest.vertices.len() {
        return Err(StarkError::InvalidInput(format!(
            "a towel configuration has one position per vertex of the flat grid ({}), not {}",
            rest.vertices.len(),
            towel_positions_m.len()
        )));
    }
    let initial = towel_positions_m;
    let thickness = DHAT_M / 2.0;
    settings.time_step_s = 0.005;
    settings.newton.residual_tolerance_n = 1e-6;
    settings.contact.default_thickness_m = Some(thickness);
    // 17k unknowns of stiff joints, light wheels and a soft towel: CG needs thousands of
    // iterations per Newton step where the sparse Cholesky factorisation is cheap.
    settings.newton.linear_solver = crate::solver::LinearSolver::Cholesky;

    // ---- Towel: rest shape the flat grid, initial positions the configuration ----
    let offset = Vector3::new(0.0, TOWEL_OFFSET_Y_M, 0.0);
    let start: Vec<Vector3<f64>> = initial.iter().map(|p| p + offset).collect();
    let z_min = start.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
    let floor_top = z_min - DHAT_M;

    let towel_material = towel_material(case.params);
    let mut sim = Simulation::new(settings)?;
    let towel = sim.add_surface("towel", &rest.vertices, &rest.elements, &towel_material)?;
    for (x, p) in sim.nodes.x[towel.nodes.range()].iter_mut().zip(&start) {
        *x = *p;
    }
    let towel_contact = towel.contact.expect("the towel has a contact thickness");

    let floor = add_floor(&mut sim, floor_top, thickness)?;
    let (robot, suspension_free_m) = add_kobuki(&mut sim, case.params, floor_top + DHAT_M, thickness)?;
    let body = robot.body("base_link").expect("the URDF has base_link");
    let mesh_of = |link: &str| {
        let b = robot.body(link).expect("link of the URDF");
        robot
            .collision_meshes
            .iter()
            .find(|m| m.body == b)
            .copied()
            .expect("the link has a collision mesh")
    };
    let wheels = [mesh_of("wheel_left"), mesh_of("wheel_right")];
    let casters = [mesh_of("caster_front"), mesh_of("caster_back")];
    let base = mesh_of("base_link");

    // ---- Friction ----
    sim.contact.set_friction(towel_contact, towel_contact, 0.4)?;
    sim.contact
        .set_friction(towel_contact, floor.contact, case.floor.towel_friction())?;
    for m in wheels.iter().chain(&casters).chain([&base]) {
        sim.contact.set_friction(m.contact, towel_contact, 1.0)?;
        sim.contact.set_friction(m.contact, floor.contact, 1.0)?;
    }
    let joint = |name: &str| robot.joint(name).cloned().expect("joint of the URDF");
    let handles = RobotTowel {
        case,
        body,
        body_mesh: base.nodes,
        towel: towel.nodes,
        towel_contact,
        wheel_contacts: wheels.map(|w| w.contact),
        motors: [joint("wheel_left_joint"), joint("wheel_right_joint")],
        suspensions: [joint("suspension_left_joint"), joint("suspension_right_joint")],
        suspension_free_m,
        robot,
    };
    Ok((sim, handles))
}

/// The floor: a slab fixed in the world with its top at `top_z_m`, under the towel and the
/// robot's path (the original: a frozen box).
fn add_floor(sim: &mut Simulation, top_z_m: f64, thickness_m: f64) -> Result<FixedSurfaceHandle> {
    let floor_size = Vector3::new(2.0, 3.0, 0.05);
    let mut floor = meshes::box_mesh(floor_size);
    for v in &mut floor.vertices {
        *v += Vector3::new(0.0, 1.0, top_z_m - floor_size.z / 2.0);
    }
    sim.add_fixed_surface("floor", &floor.vertices, &floor.elements, thickness_m)
}

/// Gravity's magnitude, m/s².
fn gravity(sim: &Simulation) -> f64 {
    Vector3::from(sim.settings.gravity_m_s2).norm()
}

/// The robot, facing +y, its body centre [`BODY_HEIGHT_M`] + [`DROP_M`] above `support_z_m`
/// (where contact holds its wheels: d̂ above the floor's mesh), with the fitted body mesh, the
/// suspension springs and the drive motors; with the sliders' coordinate at which the springs
/// are free, m.
fn add_kobuki(sim: &mut Simulation, params: ParamSet, support_z_m: f64, thickness: f64) -> Result<(Robot, f64)> {
    let body_mesh = parse(KOBUKI_COLLISION_OBJ, "kobuki_collision.obj")?;
    let suspension_free_m = suspension_free_coordinate_m(params, gravity(sim));
    let mut options = RobotOptions {
        position_m: Vector3::new(0.0, 0.0, support_z_m + BODY_HEIGHT_M + DROP_M),
        // No contact inside the robot (body, arms, wheels, casters).
        self_collision: false,
        contact_thickness_m: Some(thickness),
        ..Default::default()
    };
    options.links.insert(
        "base_link".into(),
        LinkOverride {
            collision_shape: Some(Shape::Mesh {
                vertices_m: body_mesh.vertices,
                triangles: body_mesh.elements,
                scale: Vector3::repeat(1.0),
            }),
            mass_kg: Some(body_mass_kg(params)),
            ..Default::default()
        },
    );
    for side in ["left", "right"] {
        options.joints.insert(
            format!("suspension_{side}_joint"),
            JointOverride {
                actuator: Some(Actuator::SpringDamper {
                    stiffness: SUSPENSION_STIFFNESS_N_M,
                    rest: suspension_free_m,
                    damping: 0.0,
                }),
                ..Default::default()
            },
        );
        options.joints.insert(
            format!("wheel_{side}_joint"),
            JointOverride {
                actuator: Some(Actuator::Motor {
                    target_rad_s: MOTOR_TARGET_RAD_S,
                    max_torque_n_m: Some(MOTOR_MAX_TORQUE_N_M),
                    delay_rad_s: Some(MOTOR_TRANSITION_RAD_S),
                    // Driving only: the motors never brake the wheels.
                    drive_only: true,
                }),
                ..Default::default()
            },
        );
    }
    let robot = sim.add_robot_from_str("kobuki", KOBUKI_URDF, "kobuki_paper.urdf", Path::new("."), &options)?;
    Ok((robot, suspension_free_m))
}

/// Name of the probe log a built-in run writes: `<scene>.robot_towel.jsonl`.
pub const PROBE: &str = "robot_towel";

/// The built-in scene of a case: [`build`], recording a [`Record`] every step in the probe log
/// `<scene>.robot_towel.jsonl` (classified by [`classify_log`]).
pub fn builtin(settings: Settings, case: Case) -> Result<Simulation> {
    let (mut sim, run) = build(settings, case)?;
    sim.add_probe(PROBE, move |sim| run.record(sim))?;
    Ok(sim)
}

/// The records of a run's probe log (`<dir>/<scene>.robot_towel.jsonl`).
pub fn read_log(path: &Path) -> Result<Vec<Record>> {
    let text = std::fs::read_to_string(path).map_err(|e| StarkError::Output {
        path: path.display().to_string(),
        source: e,
    })?;
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            #[derive(serde::Deserialize)]
            struct Line {
                robot_towel: Record,
            }
            serde_json::from_str::<Line>(l)
                .map(|line| line.robot_towel)
                .map_err(|e| StarkError::InvalidInput(format!("{}:{}: {e}", path.display(), i + 1)))
        })
        .collect()
}

/// Classify a run from its probe log.
pub fn classify_log(path: &Path) -> Result<super::robot_towel_outcome::Classification> {
    let samples: Vec<Sample> = read_log(path)?.iter().map(|r| r.sample).collect();
    super::robot_towel_outcome::classify(&samples, &Default::default())
        .map_err(|e| StarkError::InvalidInput(format!("{}: {e}", path.display())))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quiet() -> Settings {
        let mut s = Settings::default();
        s.output.frames = false;
        s.output.step_log = false;
        s.threads = 1;
        s
    }

    #[test]
    fn every_case_builds_with_the_papers_geometry() {
        for floor in [Floor::Carpet, Floor::Polished] {
            for configuration in 1..=8 {
                let case = Case {
                    floor,
                    configuration,
                    params: ParamSet::Original,
                };
                let (sim, run) = build(quiet(), case).unwrap();
                let r = run.record(&sim);
                // Body centre 57 mm + 5 mm above where the towel lies (the floor's mesh + d̂).
                let towel = sim.positions(run.towel);
                let z_min = towel.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
                let height = r.robot_position_m[2] - z_min;
                assert!((height - 0.062).abs() < 1e-12, "{height}");
                // The towel starts ahead of the robot's front.
                let near = towel.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
                assert!(near > 0.18 + 0.3, "{}: near edge {near}", case.name());
                assert_eq!(towel.len(), 5757);
            }
        }
    }

    /// The robot alone on the floor, driving: its body settles 57 mm above the floor (casters
    /// on it, level), the springs carrying the sprung weight with the casters, and its
    /// collision mesh about 1.5 cm above the floor (the paper: a clearance of 1.35 cm).
    #[test]
    fn the_robot_rests_at_its_stated_height() {
        for params in [ParamSet::Original, ParamSet::Paper] {
            let mut settings = quiet();
            settings.time_step_s = 0.005;
            settings.newton.residual_tolerance_n = 1e-6;
            let thickness = DHAT_M / 2.0;
            settings.contact.default_thickness_m = Some(thickness);
            let mut sim = Simulation::new(settings).unwrap();
            let floor = add_floor(&mut sim, 0.0, thickness).unwrap();
            let (robot, free_m) = add_kobuki(&mut sim, params, DHAT_M, thickness).unwrap();
            for m in &robot.collision_meshes {
                sim.contact.set_friction(m.contact, floor.contact, 1.0).unwrap();
            }
            let body = robot.body("base_link").unwrap();
            let body_mesh = robot.collision_meshes.iter().find(|m| m.body == body).unwrap().nodes;
            let springs = ["suspension_left_joint", "suspension_right_joint"].map(|j| robot.joint(j).cloned().unwrap());
            sim.run(0.5).unwrap();
            let z_m = sim.body_position(body).z - DHAT_M;
            // The barrier holds the wheels a fraction of a millimetre inside d̂.
            assert!((z_m - BODY_HEIGHT_M).abs() < 1e-3, "{params:?}: body centre at {z_m} m");
            let forward = sim.body_orientation(body) * Vector3::y();
            assert!(forward.z.abs() < 0.1f64.to_radians(), "{params:?}: pitch {}", forward.z);
            let spring_force_n: f64 = springs
                .iter()
                .map(|j| SUSPENSION_STIFFNESS_N_M * (sim.joint_state(j).coordinate.unwrap() - free_m))
                .sum();
            let sprung_weight_n = (body_mass_kg(params) + 2.0 * PART_MASS_KG) * gravity(&sim);
            assert!(
                spring_force_n > 0.8 * sprung_weight_n && spring_force_n <= sprung_weight_n,
                "{params:?}: springs {spring_force_n} N of {sprung_weight_n} N"
            );
            // The mesh reaches 41.9 mm below the body centre: 15.1 mm of clearance at 57 mm.
            let mesh_bottom_m = sim
                .positions(body_mesh)
                .iter()
                .map(|p| p.z)
                .fold(f64::INFINITY, f64::min)
                - DHAT_M;
            assert!(
                (mesh_bottom_m - 0.0151).abs() < 1e-3,
                "{params:?}: clearance {mesh_bottom_m}"
            );
        }
    }

    #[test]
    fn a_new_towel_configuration_takes_one_position_per_vertex() {
        let case = Case {
            floor: Floor::Carpet,
            configuration: 1,
            params: ParamSet::Original,
        };
        let (_, lifted) = towel_meshes(2).unwrap();
        let lifted: Vec<_> = lifted.iter().map(|p| p + Vector3::new(0.0, 0.0, 0.1)).collect();
        let mut settings = quiet();
        settings.name = "my_towel".into();
        let (sim, run) = build_with_towel(settings, case, &lifted).unwrap();
        assert_eq!(sim.settings.name, "my_towel");
        // The floor follows the towel: the same layout as the file's configuration.
        let (builtin, builtin_run) = build(
            quiet(),
            Case {
                configuration: 2,
                ..case
            },
        )
        .unwrap();
        let ours = sim.positions(run.towel);
        for (a, b) in ours.iter().zip(builtin.positions(builtin_run.towel)) {
            assert!((a - b - Vector3::new(0.0, 0.0, 0.1)).norm() < 1e-12);
        }
        let e = build_with_towel(quiet(), case, &lifted[1..]).err().unwrap().to_string();
        assert!(e.contains("one position per vertex") && e.contains("5756"), "{e}");
    }

    #[test]
    fn masses_follow_the_parameter_set() {
        for (params, total) in [(ParamSet::Original, 3.551), (ParamSet::Paper, 2.951)] {
            let case = Case {
                floor: Floor::Carpet,
                configuration: 1,
                params,
            };
            let (sim, run) = build(quiet(), case).unwrap();
            let robot: f64 = run.robot.bodies.iter().map(|(_, b)| sim.bodies.mass[b.i()]).sum();
            assert!((robot - total).abs() < 1e-9, "{params:?}: {robot}");
        }
    }

    #[test]
    fn builtin_names_round_trip() {
        for scene in crate::scenes::builtin_scenes() {
            if let Some(case) = Case::from_name(scene.name) {
                assert_eq!(case.name(), scene.name);
            }
        }
        let n = crate::scenes::builtin_scenes()
            .iter()
            .filter(|s| Case::from_name(s.name).is_some())
            .count();
        assert_eq!(n, 32);
        assert_eq!(Case::from_name("kobuki_towel_carpet_9"), None);
        assert_eq!(Case::from_name("kobuki_towel_grass_1"), None);
    }

    #[test]
    fn lab_outcomes_are_table_one() {
        let case = |floor, configuration| Case {
            floor,
            configuration,
            params: ParamSet::Original,
        };
        assert_eq!(case(Floor::Carpet, 4).lab_outcome(), 'S');
        assert_eq!(case(Floor::Polished, 3).lab_outcome(), 'P');
        assert_eq!(case(Floor::Polished, 7).lab_outcome(), 'O');
    }
}
