//! The paper's grasp (§IV-B, Fig. 4): a Franka hand holds a thin PET cup while 14 g steel balls
//! are poured in, until the grasp slips.
//!
//! - Hand: the published Franka hand URDF (`assets/robots/franka_description`, Apache-2.0),
//!   fixed upside down; finger 1 on a force-limited press closing the jaws at 100 mm/s
//!   (relative, 50 mm/s each) with at most 5 N, finger 2 following through the URDF's mimic.
//!   With the mimic, the press force is the sum of the two jaws' normal forces in equilibrium
//!   (virtual work: `F δq = N_left δq + N_right δq`), so the friction capacity is
//!   `μ (N_left + N_right)` = μ · 5 N = 2.5 N, the paper's threshold. The fingers collide through
//!   their URDF boxes (the rubber tips grasp), the hand through its collision STL.
//! - Cup ([`meshes::cup_mesh`]): about 10 cm tall, rim radius 27 mm tapering to 22 mm at the
//!   bottom, a rolled lip of 1.5 mm radius; PET membrane `E·h` = 1e6 N/m (3.3 GPa × 0.3 mm),
//!   ν 0.45, discrete-shell bending 1e-4 N·m, 0.2 kg/m²; no self-contact (as in the original).
//!   The tips grasp just below the lip, which can latch onto them when the cup slips.
//! - The cup stands on a frictionless floor that slides away once the jaws hold it; then balls
//!   (r 7.5 mm, 14 g, steel) are spawned above the cup at a steady rate ([`Simulation::add_spawn`]).
//! - d̂ = 0.5 mm everywhere; μ 0.5 jaw–cup, 0.3 ball–cup and ball–ball.
//!
//! [`Held::RigidBox`] puts a rigid box in the same hand instead of the cup and pulls it down with
//! a force growing at a steady rate: the check that the jaws slip at μ·ΣN.
//!
//! Every step a probe (`<scene>.grasp.jsonl`) records the press force, the normal and friction
//! forces on each jaw (the contact forces of the step's solve summed over the finger's mesh),
//! the vertical load (the weight of the held object and of the balls inside it) and the held
//! object's height; [`grasp_outcome`] finds the slip from the log.

use crate::error::{Result, StarkError};
use crate::presets::meshes::{self, CupShape};
use crate::presets::SurfaceMaterial;
use crate::rigidbodies::joints::JointHandle;
use crate::rigidbodies::{RigidBodyHandle, Shape};
use crate::robots::urdf::{Actuator, JointOverride, LinkOverride, RobotOptions};
use crate::settings::Settings;
use crate::simulation::Simulation;
use crate::state::NO_BODY;
use nalgebra::{UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The Franka hand's URDF (the published file, xacro expanded).
pub const FRANKA_HAND_URDF: &str = include_str!("../../assets/robots/franka_description/urdf/franka_hand.urdf");
/// The hand's collision mesh.
const HAND_STL: &[u8] =
    include_bytes!("../../assets/robots/franka_description/meshes/robot_ee/franka_hand_white/collision/hand.stl");

/// Jaw–cup friction coefficient (the paper).
pub const MU_JAW: f64 = 0.5;
/// The press's force cap, N: the sum of the two jaws' normal forces (see the module docs).
pub const GRIP_FORCE_N: f64 = 5.0;
/// Relative closing speed of the jaws, m/s.
pub const CLOSING_SPEED_M_S: f64 = 0.1;
/// Contact activation distance `d̂`, m (each object's thickness is half of it).
pub const DHAT_M: f64 = 5e-4;
/// Steel ball radius, m.
pub const BALL_RADIUS_M: f64 = 0.0075;
/// Steel ball mass, kg (7850 kg/m³ × 4/3 π r³ = 13.9 g).
pub const BALL_MASS_KG: f64 = 0.014;
/// Ball–cup and ball–ball friction.
pub const MU_BALL: f64 = 0.3;
/// Name of the probe log: `<scene>.grasp.jsonl`.
pub const PROBE: &str = "grasp";
/// The cup slips when it has moved this far down relative to the jaws since the pour began, m.
pub const SLIP_M: f64 = 1e-3;
/// Static grasping breaks when the held object first slides down relative to the jaws faster
/// than this, m/s (over [`BREAK_WINDOW_S`]), while the jaws' friction is at its Coulomb limit
/// (at least [`BREAK_FRICTION_FRACTION`] of μ·ΣN): ten times the friction's stick threshold
/// `ε_v` (1e-4 m/s), below which a held object creeps. (The friction condition tells a slide
/// from the jolt of a ball landing on the cup's bottom, which moves the cup's mean height as
/// fast while the jaws' friction is far from its limit.)
pub const BREAK_SPEED_M_S: f64 = 1e-3;
/// See [`BREAK_SPEED_M_S`]: part of the jaws' friction may act sideways, so the vertical
/// friction of a sliding grasp is a little below μ·ΣN.
pub const BREAK_FRICTION_FRACTION: f64 = 0.95;
/// The window over which the sliding speed is measured, s (two 5 ms steps).
pub const BREAK_WINDOW_S: f64 = 0.01;

/// Initial opening of each finger, m (70 mm between the jaws).
const FINGER_OPEN_M: f64 = 0.035;
/// The finger frame is this far below the hand frame, m (URDF joint origin).
const FINGER_OFFSET_M: f64 = 0.0584;
/// The rubber tip's box: centre below the finger frame and half height, m (URDF).
const TIP_CENTRE_M: f64 = 0.04525;
const TIP_HALF_HEIGHT_M: f64 = 0.00925;
/// The tips' top edge is this far below the rim, m: the lip (radius 1.5 mm, reaching 1.5 mm
/// below the rim) overhangs them and can latch.
const TIP_BELOW_RIM_M: f64 = 0.004;

/// What the hand holds.
#[derive(Clone, Debug, PartialEq)]
pub enum Held {
    /// The PET cup.
    Cup(CupShape),
    /// A rigid box (size along x, y (the jaw axis), z, m; mass, kg), pulled down by a force
    /// growing at `pull_rate_n_s` from the pour's start.
    RigidBox {
        /// Size, m.
        size_m: [f64; 3],
        /// Mass, kg.
        mass_kg: f64,
        /// Growth of the downward pull, N/s.
        pull_rate_n_s: f64,
    },
}

/// The scene's schedule and options.
#[derive(Clone, Debug, PartialEq)]
pub struct FrankaCupOptions {
    /// What the hand holds.
    pub held: Held,
    /// The floor slides away (along x) during this interval, s.
    pub floor_away_s: [f64; 2],
    /// The first ball (or the box's pull) starts at this time, s.
    pub pour_start_s: f64,
    /// Time between balls, s.
    pub pour_every_s: f64,
    /// Number of balls.
    pub balls: usize,
    /// Jaw friction coefficient.
    pub mu_jaw: f64,
    /// The press's force cap, N.
    pub grip_force_n: f64,
    /// The cup's discrete-shell bending stiffness, N·m ([`CUP_BENDING_N_M`]).
    pub cup_bending_n_m: f64,
}

impl Default for FrankaCupOptions {
    fn default() -> Self {
        FrankaCupOptions {
            held: Held::Cup(CupShape::default()),
            floor_away_s: [0.6, 1.0],
            pour_start_s: 1.2,
            pour_every_s: 0.2,
            balls: 30,
            mu_jaw: MU_JAW,
            grip_force_n: GRIP_FORCE_N,
            cup_bending_n_m: CUP_BENDING_N_M,
        }
    }
}

/// Duration of the built-in run, s: the grasp, the floor away, 30 balls (the last at 7 s) and the
/// cup left hanging as long again, as the original's 16 s.
pub const DURATION_S: f64 = 16.0;

/// Handles of a built scene.
#[derive(Clone, Debug)]
pub struct FrankaCup {
    /// The options it was built with.
    pub options: FrankaCupOptions,
    /// The finger bodies: left (the press's), right.
    pub fingers: [RigidBodyHandle; 2],
    /// The press on finger 1.
    pub press: JointHandle,
    /// The held object: the cup's nodes or the box's body.
    pub held: HeldHandle,
    /// Its mass, kg.
    pub held_mass_kg: f64,
}

/// The held object in the simulation.
#[derive(Clone, Copy, Debug)]
pub enum HeldHandle {
    /// The cup's nodes.
    Cup(crate::deformables::NodeSetHandle),
    /// The box.
    RigidBox(RigidBodyHandle),
}

/// One line of the probe log.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GraspSample {
    /// The press's force (the jaws' closing force), N.
    pub grip_force_n: f64,
    /// Normal (barrier) force on each jaw along the jaw axis (the squeeze): left, right, N.
    pub normal_force_n: [f64; 2],
    /// Friction force on each jaw, vertical component (positive up), N: the held object pulls
    /// the jaws down through friction.
    pub friction_up_n: [f64; 2],
    /// Friction capacity `μ (N_left + N_right)`, N.
    pub capacity_n: f64,
    /// Total vertical friction the jaws exert on the held object (positive up), N.
    pub friction_on_held_n: f64,
    /// Total vertical contact force (normal and friction) the jaws exert on the held object
    /// (positive up), N: where the shell wraps around a tip's edge, normal forces carry some of
    /// the load too.
    pub support_n: f64,
    /// The vertical load: weight of the held object (and of the balls inside it), plus the box's
    /// pull, N.
    pub load_n: f64,
    /// Balls spawned so far.
    pub balls: usize,
    /// Balls inside the cup (centre within its radius and below its rim).
    pub balls_in_cup: usize,
    /// Height of the held object (the cup's mean node height, or the box's centre), m.
    pub held_z_m: f64,
    /// Height of the jaws (the fingers' centres), m.
    pub jaw_z_m: f64,
}

fn bad(message: String) -> StarkError {
    StarkError::InvalidInput(message)
}

/// The cup's bending stiffness of the model (issue 14's value; the paper does not give one), N·m:
/// about 1/50 of a real 0.3 mm PET sheet ([`PET_BENDING_N_M`]).
pub const CUP_BENDING_N_M: f64 = 1e-4;

/// Bending stiffness of a real 0.3 mm PET sheet in the discrete-shell form, N·m: the plate's
/// `D = E h³ / (12 (1 − ν²))` = 9.3e-3 N·m for E = 3.3 GPa, ν = 0.45; the hinge energy
/// `k θ² ‖ē‖/h̄` of a uniformly bent regular mesh is `D/2 ∫ κ²` for `k ≈ D/2`.
pub const PET_BENDING_N_M: f64 = 4.7e-3;

/// The cup's material (see the module docs) with a bending stiffness `bending_n_m` (N·m); `h` 0.3 mm.
pub fn cup_material(bending_n_m: f64) -> SurfaceMaterial {
    let thickness_m = 3e-4;
    let membrane_stiffness_n_per_m = 1e6;
    // A light Rayleigh damping (β = 1 ms) takes out the membrane's ringing without slowing the
    // cup's motion.
    let beta_s = 1e-3;
    SurfaceMaterial {
        inertia: crate::deformables::InertiaParams {
            density: 0.2,
            damping: 0.0,
            quasistatic: false,
        },
        strain: crate::deformables::TriangleStrainParams {
            thickness_m,
            youngs_modulus: membrane_stiffness_n_per_m / thickness_m,
            poissons_ratio: 0.45,
            damping: beta_s * membrane_stiffness_n_per_m,
            ..Default::default()
        },
        bending: crate::presets::Bending::Dihedral(crate::deformables::DihedralBendingParams {
            stiffness: bending_n_m,
            damping: beta_s * bending_n_m,
        }),
        contact_thickness_m: Some(DHAT_M / 2.0),
    }
}

/// Where the balls start, in turn: five places across the opening (the centre and four around
/// it over the bottom), just above the lip. Each is then lowered to [`BALL_DROP_M`] above what it
/// will land on (the cup's bottom or the balls in it,
/// [`Contact::clearance_below`](crate::contact::Contact::clearance_below)) and released at rest,
/// so that the cup is loaded by the balls' weight rather than by impacts. (A ball dropped from
/// the rim onto the bottom, 10 cm, brings 0.02 N·s; stopping it together with the 4 g cup takes
/// the jaws' spare friction, 2.3 N, 9 ms, in which the cup slides about 5 mm: a pour from high
/// above measures impacts, not the static grasp.)
pub fn ball_places(shape: &CupShape, rim_z_m: f64) -> [Vector3<f64>; 5] {
    let ring_m = 0.75 * (shape.bottom_radius_m - BALL_RADIUS_M);
    let z = rim_z_m + shape.lip_radius_m + BALL_RADIUS_M + 1e-3;
    [(0.0, 0.0), (ring_m, 0.0), (0.0, ring_m), (-ring_m, 0.0), (0.0, -ring_m)].map(|(x, y)| Vector3::new(x, y, z))
}

/// Height above its support from which a ball is dropped, m.
pub const BALL_DROP_M: f64 = 2e-3;

/// Build the scene with `options` (see the module docs).
pub fn build(mut settings: Settings, options: FrankaCupOptions) -> Result<(Simulation, FrankaCup)> {
    if !(options.cup_bending_n_m >= 0.0 && options.cup_bending_n_m.is_finite()) {
        return Err(bad(format!(
            "cup_bending_n_m = {} must be non-negative",
            options.cup_bending_n_m
        )));
    }
    settings.contact.default_thickness_m = Some(DHAT_M / 2.0);
    // A stiff membrane on light nodes: CG converges slowly where the factorisation is cheap.
    settings.newton.linear_solver = crate::solver::LinearSolver::Cholesky;
    let g = Vector3::from(settings.gravity_m_s2);
    let mut sim = Simulation::new(settings)?;

    // ---- The held object, standing on the floor at z = 0 ----
    let gap = 0.6 * DHAT_M;
    let (held, held_contact, top_z) = match &options.held {
        Held::Cup(shape) => {
            let mesh = meshes::cup_mesh(shape)?;
            let vertices: Vec<_> = mesh.vertices.iter().map(|v| v + Vector3::new(0.0, 0.0, gap)).collect();
            let cup = sim.add_surface("cup", &vertices, &mesh.elements, &cup_material(options.cup_bending_n_m))?;
            let contact = cup.contact.expect("the cup has a contact thickness");
            sim.contact.set_collision(contact, contact, false)?;
            (HeldHandle::Cup(cup.nodes), contact, gap + shape.height_m)
        }
        Held::RigidBox {
            size_m,
            mass_kg,
            pull_rate_n_s,
        } => {
            if !(pull_rate_n_s.is_finite() && *pull_rate_n_s >= 0.0) {
                return Err(bad(format!("pull_rate_n_s = {pull_rate_n_s} must be non-negative")));
            }
            let size = Vector3::from(*size_m);
            let b = sim.add_box(
                "box",
                *mass_kg,
                size,
                Vector3::new(0.0, 0.0, gap + size.z / 2.0),
                UnitQuaternion::identity(),
                None,
            )?;
            // The rigid stand-in for the cup: the tips grasp its top (no lip).
            (HeldHandle::RigidBox(b.body), b.mesh.contact, gap + size.z)
        }
    };

    // ---- Floor: a slab under the object, frictionless, that slides away along +x ----
    let floor_size = Vector3::new(0.2, 0.2, 0.02);
    let mut floor = meshes::box_mesh(floor_size);
    for v in &mut floor.vertices {
        v.z -= floor_size.z / 2.0;
    }
    let floor = sim.add_prescribed_surface("floor", &floor.vertices, &floor.elements, DHAT_M / 2.0, 1e6)?;
    let [away0, away1] = options.floor_away_s;
    if !(away0.is_finite() && away1 > away0) {
        return Err(bad(format!(
            "floor_away_s = {:?} must be an increasing interval",
            options.floor_away_s
        )));
    }
    // At a steady 0.625 m/s along x: 0.25 m, clear of the cup (the scene file's `motion`).
    let motion = crate::io::scene::Motion {
        start_s: away0,
        end_s: away1,
        velocity_m_s: [0.25 / (away1 - away0), 0.0, 0.0],
        ..Default::default()
    };
    let prescribed = floor.prescribed;
    sim.add_time_event(away0, f64::INFINITY, move |sim, t| motion.apply(sim, prescribed, t));

    // ---- Hand: upside down, the tips' top edge `TIP_BELOW_RIM_M` below the rim ----
    let tip_top_below_hand = FINGER_OFFSET_M + TIP_CENTRE_M - TIP_HALF_HEIGHT_M;
    let hand_z = top_z - TIP_BELOW_RIM_M + tip_top_below_hand;
    let hand_mesh = crate::io::mesh_files::parse_stl(HAND_STL, Path::new("hand.stl"))?;
    let mut robot_options = RobotOptions {
        fixed_base: true,
        position_m: Vector3::new(0.0, 0.0, hand_z),
        orientation: UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI),
        self_collision: false,
        contact_thickness_m: Some(DHAT_M / 2.0),
        ..Default::default()
    };
    robot_options.links.insert(
        "fr3_hand".into(),
        LinkOverride {
            collision_shape: Some(Shape::Mesh {
                vertices_m: hand_mesh.vertices,
                triangles: hand_mesh.elements,
                scale: Vector3::repeat(1.0),
            }),
            ..Default::default()
        },
    );
    if !(options.grip_force_n > 0.0 && options.grip_force_n.is_finite()) {
        return Err(bad(format!("grip_force_n = {} must be positive", options.grip_force_n)));
    }
    robot_options.joints.insert(
        "fr3_finger_joint1".into(),
        JointOverride {
            position: Some(FINGER_OPEN_M),
            actuator: Some(Actuator::Press {
                target_m_s: -CLOSING_SPEED_M_S / 2.0,
                max_force_n: Some(options.grip_force_n),
            }),
            ..Default::default()
        },
    );
    robot_options.joints.insert(
        "fr3_finger_joint2".into(),
        JointOverride {
            position: Some(FINGER_OPEN_M),
            ..Default::default()
        },
    );
    let hand = sim.add_robot_from_str(
        "franka",
        FRANKA_HAND_URDF,
        "franka_hand.urdf",
        Path::new("."),
        &robot_options,
    )?;
    let finger = |link: &str| {
        hand.body(link)
            .ok_or_else(|| bad(format!("the hand has no link {link}")))
    };
    let fingers = [finger("fr3_leftfinger")?, finger("fr3_rightfinger")?];
    let press = hand
        .joint("fr3_finger_joint1")
        .cloned()
        .ok_or_else(|| bad("the hand has no fr3_finger_joint1".into()))?;

    // ---- Friction ----
    if !(options.mu_jaw >= 0.0 && options.mu_jaw.is_finite()) {
        return Err(bad(format!("mu_jaw = {} must be non-negative", options.mu_jaw)));
    }
    for m in &hand.collision_meshes {
        let mu = if fingers.contains(&m.body) { options.mu_jaw } else { 0.0 };
        sim.contact.set_friction(m.contact, held_contact, mu)?;
    }

    // ---- The pour (or the box's pull) ----
    if !(options.pour_start_s.is_finite() && options.pour_every_s > 0.0) {
        return Err(bad("pour_start_s must be finite and pour_every_s positive".into()));
    }
    match (&options.held, held) {
        (Held::Cup(shape), HeldHandle::Cup(_)) => {
            let places = ball_places(shape, top_z);
            let ball = meshes::sphere_mesh(BALL_RADIUS_M, 2);
            for k in 1..=options.balls {
                let t = options.pour_start_s + (k - 1) as f64 * options.pour_every_s;
                let start = places[(k - 1) % places.len()];
                let ball = ball.clone();
                let label = format!("ball_{k}");
                sim.add_spawn(t, &label.clone(), move |sim| {
                    // At rest, `BALL_DROP_M` above what it will land on.
                    let vertices: Vec<Vector3<f64>> = ball.vertices.iter().map(|v| v + start).collect();
                    let fall = sim
                        .contact
                        .clearance_below(&sim.nodes.x, &vertices, &ball.elements)
                        .map_or(0.0, |c| (c - BALL_DROP_M).max(0.0));
                    let at = start - Vector3::new(0.0, 0.0, fall);
                    let b = sim.add_sphere(
                        &label,
                        BALL_MASS_KG,
                        BALL_RADIUS_M,
                        2,
                        at,
                        UnitQuaternion::identity(),
                        None,
                    )?;
                    let mine = b.mesh.contact;
                    if let Some(cup) = sim.contact.object_by_label("cup") {
                        sim.contact.set_friction(mine, cup, MU_BALL)?;
                    }
                    for j in 1..k {
                        if let Some(other) = sim.contact.object_by_label(&format!("ball_{j}")) {
                            sim.contact.set_friction(mine, other, MU_BALL)?;
                        }
                    }
                    Ok(())
                })?;
            }
        }
        (Held::RigidBox { pull_rate_n_s, .. }, HeldHandle::RigidBox(body)) => {
            let (start, rate) = (options.pour_start_s, *pull_rate_n_s);
            sim.add_time_event(start, f64::INFINITY, move |sim, t| {
                sim.set_body_force(body, Vector3::new(0.0, 0.0, -rate * (t - start)))
            });
        }
        _ => unreachable!("the handle matches the option"),
    }

    let held_mass_kg = match held {
        HeldHandle::Cup(nodes) => sim.deformables.inertia.node_masses(sim.nodes.len())[nodes.range()]
            .iter()
            .sum(),
        HeldHandle::RigidBox(b) => sim.bodies.mass[b.i()],
    };
    let handles = FrankaCup {
        held_mass_kg,
        options,
        fingers,
        press,
        held,
    };
    let probe = handles.clone();
    sim.add_probe(PROBE, move |sim| probe.sample(sim, g))?;
    Ok((sim, handles))
}

impl FrankaCup {
    /// The grasp's readouts at the last accepted step.
    pub fn sample(&self, sim: &Simulation, gravity: Vector3<f64>) -> GraspSample {
        let x = &sim.nodes.x;
        let (normal, friction) = sim.contact.solve_forces(x);
        let mut n_jaw = [Vector3::zeros(); 2];
        let mut f_jaw = [Vector3::zeros(); 2];
        for i in 0..x.len() {
            let b = sim.nodes.body[i];
            if b == NO_BODY {
                continue;
            }
            for k in 0..2 {
                if b as usize == self.fingers[k].i() {
                    n_jaw[k] += normal[i];
                    f_jaw[k] += friction[i];
                }
            }
        }
        // The squeeze: the normal forces along the jaw axis (world y).
        let normal_force_n = [n_jaw[0].y.abs(), n_jaw[1].y.abs()];
        let support_n = -(n_jaw[0].z + n_jaw[1].z + f_jaw[0].z + f_jaw[1].z);
        let g = gravity.norm();
        let jaw_z_m = 0.5 * (sim.body_position(self.fingers[0]).z + sim.body_position(self.fingers[1]).z);
        let balls = sim.rigid_bodies.labels.iter().filter(|l| l.starts_with("ball")).count();
        let (held_z_m, load_n, balls_in_cup) = match self.held {
            HeldHandle::Cup(nodes) => {
                let p = sim.positions(nodes);
                let n = p.len() as f64;
                let centre: Vector3<f64> = p.iter().sum::<Vector3<f64>>() / n;
                let bottom = p.iter().map(|v| v.z).fold(f64::INFINITY, f64::min);
                let Held::Cup(shape) = &self.options.held else {
                    unreachable!("a cup handle comes with a cup")
                };
                let rim = bottom + shape.height_m;
                let inside = (0..sim.num_rigid_bodies())
                    .filter(|&b| sim.rigid_bodies.labels[b].starts_with("ball"))
                    .filter(|&b| {
                        let c = sim.bodies.position[b];
                        c.z < rim && c.z > bottom && (c.xy() - centre.xy()).norm() < shape.rim_radius_m
                    })
                    .count();
                (centre.z, g * (self.held_mass_kg + inside as f64 * BALL_MASS_KG), inside)
            }
            HeldHandle::RigidBox(body) => {
                let pull = -sim.bodies.force[body.i()].z;
                (sim.body_position(body).z, g * self.held_mass_kg + pull, 0)
            }
        };
        GraspSample {
            grip_force_n: sim.joint_state(&self.press).driver_effort.abs(),
            normal_force_n,
            friction_up_n: [f_jaw[0].z, f_jaw[1].z],
            capacity_n: self.options.mu_jaw * (normal_force_n[0] + normal_force_n[1]),
            friction_on_held_n: -(f_jaw[0].z + f_jaw[1].z),
            support_n,
            load_n,
            balls,
            balls_in_cup,
            held_z_m,
            jaw_z_m,
        }
    }
}

/// The slip found in a probe log.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GraspOutcome {
    /// The reference: the last step before the pour (or pull) starts, s.
    pub reference_time_s: f64,
    /// The held object's height relative to the jaws then, m.
    pub reference_height_m: f64,
    /// The first time the held object is `SLIP_M` lower relative to the jaws than at the
    /// reference, s; `None`: it held.
    pub slip_time_s: Option<f64>,
    /// The sample at the slip (or at the end of the log).
    pub at: GraspSample,
    /// The first time after the reference that the held object slides down relative to the
    /// jaws faster than [`BREAK_SPEED_M_S`] (static grasping breaks), s; `None`: it never did.
    pub break_time_s: Option<f64>,
    /// The sample when static grasping breaks.
    pub at_break: Option<GraspSample>,
    /// Load over capacity at the slip (or at the end).
    pub load_over_capacity: f64,
    /// The largest load over capacity while it held (before the slip), and when, s.
    pub max_held_ratio: (f64, f64),
    /// The cup's drop relative to the jaws at the end of the log, m.
    pub final_drop_m: f64,
}

#[derive(Deserialize)]
struct ProbeLine {
    time_s: f64,
    grasp: GraspSample,
}

/// The jaws' vertical friction is at its Coulomb limit (see [`BREAK_SPEED_M_S`]).
fn at_friction_limit(s: &GraspSample) -> bool {
    s.capacity_n > 0.0 && s.friction_on_held_n >= BREAK_FRICTION_FRACTION * s.capacity_n
}

/// Finds where static grasping breaks, from the probe's samples in time order: the held object
/// slides down relative to the jaws faster than [`BREAK_SPEED_M_S`] over the last
/// [`BREAK_WINDOW_S`] while the jaws' friction is at its limit. [`grasp_outcome`] and
/// [`SlipWatch`] both use it.
#[derive(Clone, Debug, Default)]
pub struct BreakDetector {
    /// (time, height of the held object relative to the jaws), s and m: the samples of the last
    /// window and the one before it.
    recent: std::collections::VecDeque<(f64, f64)>,
}

impl BreakDetector {
    /// Add the sample at `time_s`; true if the object slides with the friction at its limit.
    pub fn push(&mut self, time_s: f64, sample: &GraspSample) -> bool {
        let rel = sample.held_z_m - sample.jaw_z_m;
        self.recent.push_back((time_s, rel));
        // Keep the latest sample at least a window old as the front.
        while self.recent.len() > 1 && self.recent[1].0 <= time_s - BREAK_WINDOW_S + 1e-9 {
            self.recent.pop_front();
        }
        let (t0, rel0) = self.recent[0];
        let window_s = time_s - t0;
        window_s >= BREAK_WINDOW_S - 1e-9 && (rel0 - rel) / window_s > BREAK_SPEED_M_S && at_friction_limit(sample)
    }
}

/// Read a probe log (`<scene>.grasp.jsonl`) into (time, sample) pairs.
fn read_probe_log(log: &Path) -> Result<Vec<ProbeLine>> {
    let text =
        std::fs::read_to_string(log).map_err(|e| bad(format!("cannot read the grasp log {}: {e}", log.display())))?;
    let mut lines = Vec::new();
    for (i, l) in text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let line: ProbeLine = serde_json::from_str(l)
            .map_err(|e| bad(format!("{}:{}: not a grasp probe line: {e}", log.display(), i + 1)))?;
        lines.push(line);
    }
    Ok(lines)
}

/// Read a probe log and find the slip (see [`GraspOutcome`]); `pour_start_s` from the options.
pub fn grasp_outcome(log: &Path, pour_start_s: f64) -> Result<GraspOutcome> {
    outcome_of_lines(&read_probe_log(log)?, log, pour_start_s)
}

/// [`grasp_outcome`] of the lines read from `log`.
fn outcome_of_lines(lines: &[ProbeLine], log: &Path, pour_start_s: f64) -> Result<GraspOutcome> {
    let reference = lines.iter().rev().find(|l| l.time_s < pour_start_s).ok_or_else(|| {
        bad(format!(
            "{}: no step before the pour at {pour_start_s} s",
            log.display()
        ))
    })?;
    let rel = |s: &GraspSample| s.held_z_m - s.jaw_z_m;
    let rel0 = rel(&reference.grasp);
    let slip = lines
        .iter()
        .find(|l| l.time_s > reference.time_s && rel0 - rel(&l.grasp) > SLIP_M);
    let mut detector = BreakDetector::default();
    let broken = lines
        .iter()
        .find(|l| detector.push(l.time_s, &l.grasp) && l.time_s > reference.time_s);
    let last = lines.last().expect("the reference is a line");
    let at = slip.unwrap_or(last);
    let ratio = |s: &GraspSample| {
        if s.capacity_n > 0.0 {
            s.load_n / s.capacity_n
        } else {
            f64::INFINITY
        }
    };
    let max_held_ratio = lines
        .iter()
        .filter(|l| l.time_s >= reference.time_s && slip.is_none_or(|s| l.time_s < s.time_s))
        .map(|l| (ratio(&l.grasp), l.time_s))
        .fold((0.0, reference.time_s), |a, b| if b.0 > a.0 { b } else { a });
    Ok(GraspOutcome {
        reference_time_s: reference.time_s,
        reference_height_m: rel0,
        slip_time_s: slip.map(|l| l.time_s),
        at: at.grasp.clone(),
        break_time_s: broken.map(|l| l.time_s),
        at_break: broken.map(|l| l.grasp.clone()),
        load_over_capacity: ratio(&at.grasp),
        max_held_ratio,
        final_drop_m: rel0 - rel(&last.grasp),
    })
}

/// Watches a run of this scene for the break and the slip while it runs (to act on them: `stark
/// run` draws the state), with the criteria of [`grasp_outcome`].
#[derive(Clone, Debug)]
pub struct SlipWatch {
    pour_start_s: f64,
    fingers: [RigidBodyHandle; 2],
    held: HeldHandle,
    /// Height of the held object relative to the jaws at the last step before the pour, m.
    reference_m: Option<f64>,
    slipped: bool,
    broke: bool,
    breaks: BreakDetector,
}

/// What [`SlipWatch::update`] saw at a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GraspEvent {
    /// Static grasping broke: the held object first slid faster than [`BREAK_SPEED_M_S`] with
    /// the jaws' friction at its limit.
    Break,
    /// The held object first reached [`SLIP_M`] below its height before the pour.
    Slip,
}

impl SlipWatch {
    /// For a simulation built by [`build`] (found by its labels: the fingers of robot `franka`
    /// and a deformable `cup` or a rigid body `box`); `None` for other simulations.
    pub fn find(sim: &Simulation, pour_start_s: f64) -> Option<Self> {
        let left = sim.rigid_bodies.by_label("franka/fr3_leftfinger")?;
        let right = sim.rigid_bodies.by_label("franka/fr3_rightfinger")?;
        let held = match (sim.deformables.set_by_label("cup"), sim.rigid_bodies.by_label("box")) {
            (Some(cup), _) => HeldHandle::Cup(cup),
            (None, Some(b)) => HeldHandle::RigidBox(b),
            (None, None) => return None,
        };
        Some(SlipWatch {
            pour_start_s,
            fingers: [left, right],
            held,
            reference_m: None,
            slipped: false,
            broke: false,
            breaks: BreakDetector::default(),
        })
    }

    /// Continue a resumed run from its probe log: the reference, whether it broke and slipped
    /// already, and the break detector's window (nothing to do when the log has no step of the
    /// pour yet).
    pub fn resume_from_log(&mut self, log: &Path) -> Result<()> {
        // Before the pour the reference is taken again by `update` at every step anyway.
        if log.exists() {
            let lines = read_probe_log(log)?;
            if let Ok(outcome) = outcome_of_lines(&lines, log, self.pour_start_s) {
                self.reference_m = Some(outcome.reference_height_m);
                self.slipped = outcome.slip_time_s.is_some();
                self.broke = outcome.break_time_s.is_some();
            }
            for l in &lines {
                self.breaks.push(l.time_s, &l.grasp);
            }
        }
        Ok(())
    }

    fn relative_height(&self, sim: &Simulation) -> f64 {
        let jaw = 0.5 * (sim.body_position(self.fingers[0]).z + sim.body_position(self.fingers[1]).z);
        let held = match self.held {
            HeldHandle::Cup(nodes) => {
                let p = sim.positions(nodes);
                p.iter().map(|v| v.z).sum::<f64>() / p.len() as f64
            }
            HeldHandle::RigidBox(b) => sim.body_position(b).z,
        };
        held - jaw
    }

    /// Call after every step: the events of this step (each comes once; both may come at the
    /// same step). The break needs the step's probe record (the jaws' friction), so step logs
    /// must be on for it.
    pub fn update(&mut self, sim: &Simulation) -> Vec<GraspEvent> {
        let t = sim.time();
        let mut events = Vec::new();
        let sample = sim
            .last_probe_record(PROBE)
            .and_then(|r| GraspSample::deserialize(r).ok());
        let slides = sample.is_some_and(|s| self.breaks.push(t, &s));
        let rel = self.relative_height(sim);
        if t < self.pour_start_s {
            self.reference_m = Some(rel);
            return events;
        }
        if !self.broke && slides {
            self.broke = true;
            events.push(GraspEvent::Break);
        }
        if let Some(reference) = self.reference_m {
            if !self.slipped && reference - rel > SLIP_M {
                self.slipped = true;
                events.push(GraspEvent::Slip);
            }
        }
        events
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A probe log of a held object that creeps (at `ε_v`), is jolted at 3 mm/s for 10 ms at 1.5 s
    /// with the friction far from its limit (a ball landing), then slides at 3 mm/s from 2.0 s for
    /// 0.1 s with the friction at μ·ΣN and then holds again: static grasping breaks at the slide,
    /// not at the jolt, and the 1 mm slip is never reached.
    #[test]
    fn the_grasp_breaks_where_the_object_slides_not_where_it_creeps() {
        let dir = tempfile::tempdir().unwrap();
        let log = dir.path().join("x.grasp.jsonl");
        let mut text = String::new();
        let mut z = 0.05;
        for step in 0..500 {
            let t = 0.005 * (step + 1) as f64;
            let sliding = (2.0..2.1).contains(&t);
            if t > 1.2 {
                let jolt = (1.5..1.51).contains(&t);
                z -= 0.005 * if sliding || jolt { 3e-3 } else { 1e-4 };
            }
            let sample = GraspSample {
                capacity_n: 2.5,
                friction_on_held_n: if sliding { 2.5 } else { 1.0 },
                load_n: 1.0 + t,
                held_z_m: z,
                jaw_z_m: 0.1,
                ..Default::default()
            };
            let line = serde_json::json!({"time_s": t, "grasp": sample, "step": step});
            text.push_str(&format!("{line}\n"));
        }
        std::fs::write(&log, text).unwrap();
        let o = grasp_outcome(&log, 1.2).unwrap();
        let t = o.break_time_s.expect("it slid");
        assert!((2.0..2.02).contains(&t), "broke at {t}");
        assert!((o.at_break.unwrap().load_n - (1.0 + t)).abs() < 1e-12);
        assert_eq!(
            o.slip_time_s, None,
            "0.3 mm of slide and 0.13 mm of creep stay below 1 mm"
        );
    }
}
