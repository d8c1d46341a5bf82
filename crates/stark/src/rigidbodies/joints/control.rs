//! Run-time control of joints (enable, stiffness, tolerances, targets, springs, fixed transforms)
//! and their readouts ([`JointState`], per-primitive [`JointReadout`]s).

use super::{check_axis, check_vec, JointElement, JointHandle, JointReadout, JointState, Measure, Poses, Primitive};
use crate::energy::Node;
use crate::error::{check_param, Result, StarkError};
use crate::rigidbodies::RigidBodyHandle;
use crate::simulation::Simulation;
use nalgebra::{Unit, UnitQuaternion, Vector3};

impl Simulation {
    // ---- Run-time control and readouts ----

    fn joint_elements_mut(&mut self, h: &JointHandle) -> Result<Vec<&mut JointElement>> {
        let n = self.rigid_bodies.joints.potential.elements.len();
        if let Some(&bad) = h.elements.iter().find(|&&e| e as usize >= n) {
            return Err(StarkError::InvalidHandle {
                kind: "joint element",
                index: bad as usize,
                len: n,
            });
        }
        let wanted: std::collections::HashSet<u32> = h.elements.iter().copied().collect();
        Ok(self
            .rigid_bodies
            .joints
            .potential
            .elements
            .iter_mut()
            .enumerate()
            .filter(|(i, _)| wanted.contains(&(*i as u32)))
            .map(|(_, e)| e)
            .collect())
    }

    fn driver_mut(&mut self, h: &JointHandle) -> Result<&mut JointElement> {
        let e = h
            .driver
            .ok_or_else(|| StarkError::InvalidInput(format!("joint '{}' has no driver", h.label)))?;
        self.rigid_bodies
            .joints
            .potential
            .elements
            .get_mut(e as usize)
            .ok_or(StarkError::InvalidHandle {
                kind: "joint element",
                index: e as usize,
                len: 0,
            })
    }

    /// Enable or disable a joint (a disabled joint has no energy).
    pub fn set_joint_enabled(&mut self, h: &JointHandle, enabled: bool) -> Result<()> {
        for e in self.joint_elements_mut(h)? {
            e.enabled = enabled;
        }
        Ok(())
    }

    /// Set the stiffness (N/m) of a joint's hard constraints.
    pub fn set_joint_stiffness(&mut self, h: &JointHandle, stiffness: f64) -> Result<()> {
        check_param(
            &h.label,
            "stiffness",
            stiffness,
            stiffness > 0.0 && stiffness.is_finite(),
            "must be positive (N/m)",
        )?;
        for e in self.joint_elements_mut(h)? {
            if e.primitive.is_hard() {
                e.stiffness = stiffness;
            }
        }
        Ok(())
    }

    /// Set the tolerances of a joint's hard constraints (m for points, degrees for directions).
    pub fn set_joint_tolerance(&mut self, h: &JointHandle, tolerance_m: f64, tolerance_deg: f64) -> Result<()> {
        check_param(
            &h.label,
            "tolerance_m",
            tolerance_m,
            tolerance_m > 0.0,
            "must be positive (m)",
        )?;
        check_param(
            &h.label,
            "tolerance_deg",
            tolerance_deg,
            tolerance_deg > 0.0,
            "must be positive (degrees)",
        )?;
        for e in self.joint_elements_mut(h)? {
            if e.primitive.is_hard() {
                e.tolerance = if e.primitive.is_angular() {
                    tolerance_deg.to_radians()
                } else {
                    tolerance_m
                };
            }
        }
        Ok(())
    }

    /// Largest stiffness of a joint's hard constraints (after hardening), N/m.
    pub fn joint_stiffness(&self, h: &JointHandle) -> f64 {
        h.elements
            .iter()
            .filter_map(|&e| self.rigid_bodies.joints.potential.elements.get(e as usize))
            .filter(|e| e.primitive.is_hard())
            .map(|e| e.stiffness)
            .fold(0.0, f64::max)
    }

    /// Set the target speed of a motor or velocity controller (rad/s), or of a press (m/s).
    pub fn set_joint_target_velocity(&mut self, h: &JointHandle, target: f64) -> Result<()> {
        check_param(
            &h.label,
            "target velocity",
            target,
            target.is_finite(),
            "must be finite",
        )?;
        let el = self.driver_mut(h)?;
        el.servo = None;
        match &mut el.primitive {
            Primitive::AngularVelocity { target_rad_s, .. } => *target_rad_s = target,
            Primitive::LinearVelocity { target_m_s, .. } => *target_m_s = target,
            _ => {
                return Err(StarkError::InvalidInput(format!(
                    "joint '{}' has no velocity controller",
                    h.label
                )))
            }
        }
        Ok(())
    }

    /// Set the largest torque (N·m) or force (N) of a joint's controller.
    pub fn set_joint_max_effort(&mut self, h: &JointHandle, max: f64) -> Result<()> {
        check_param(
            &h.label,
            "max effort",
            max,
            max >= 0.0 && max.is_finite(),
            "must be non-negative",
        )?;
        let el = self.driver_mut(h)?;
        match &mut el.primitive {
            Primitive::AngularVelocity { max_torque_n_m, .. } => *max_torque_n_m = max,
            Primitive::LinearVelocity { max_force_n, .. } => *max_force_n = max,
            _ => {
                return Err(StarkError::InvalidInput(format!(
                    "joint '{}' has no velocity controller",
                    h.label
                )))
            }
        }
        Ok(())
    }

    /// Make a motor (or angular velocity controller) drive only: its torque never opposes the
    /// direction of its target, so it does not brake a joint turning faster than the target
    /// (see [`Primitive::AngularVelocity`]). Set it when building the scene (it is part of the
    /// scene, not of a checkpoint).
    pub fn set_motor_drive_only(&mut self, h: &JointHandle, drive_only: bool) -> Result<()> {
        let el = self.driver_mut(h)?;
        match &mut el.primitive {
            Primitive::AngularVelocity { drive_only: d, .. } => *d = drive_only,
            _ => {
                return Err(StarkError::InvalidInput(format!(
                    "joint '{}' has no motor (angular velocity controller)",
                    h.label
                )))
            }
        }
        Ok(())
    }

    /// Set the target of a servo: degrees for a hinge servo, m for a prismatic one.
    pub fn set_servo_target(&mut self, h: &JointHandle, target: f64) -> Result<()> {
        check_param(&h.label, "servo target", target, target.is_finite(), "must be finite")?;
        let el = self.driver_mut(h)?;
        let servo = el
            .servo
            .as_mut()
            .ok_or_else(|| StarkError::InvalidInput(format!("joint '{}' is not a servo", h.label)))?;
        servo.target = match servo.measure {
            Measure::Angle { .. } => target.to_radians(),
            Measure::Position { .. } => target,
        };
        Ok(())
    }

    /// Set the rest length (m) and damping (N·s/m) of a spring.
    pub fn set_spring(&mut self, h: &JointHandle, rest_length: f64, damping: f64) -> Result<()> {
        check_param(
            &h.label,
            "rest length",
            rest_length,
            rest_length >= 0.0 && rest_length.is_finite(),
            "must be non-negative (m)",
        )?;
        check_param(
            &h.label,
            "damping",
            damping,
            damping >= 0.0 && damping.is_finite(),
            "must be non-negative (N·s/m)",
        )?;
        let el = self.driver_mut(h)?;
        match &mut el.primitive {
            Primitive::Spring {
                rest_length_m,
                damping_n_s_m,
            } => {
                *rest_length_m = rest_length;
                *damping_n_s_m = damping;
                Ok(())
            }
            _ => Err(StarkError::InvalidInput(format!("joint '{}' is not a spring", h.label))),
        }
    }

    /// Drive a fixed body (see [`Simulation::add_fix_joint`]) to centre of mass `position_m` and
    /// orientation `orientation` (met at the end of the next step).
    pub fn set_fixed_transform(
        &mut self,
        h: &JointHandle,
        position_m: Vector3<f64>,
        orientation: UnitQuaternion<f64>,
    ) -> Result<()> {
        check_vec(&h.label, "position", &position_m)?;
        let els = self.joint_elements_mut(h)?;
        if els.len() != 3 || els.iter().any(|e| e.bodies[0].is_some()) {
            return Err(StarkError::InvalidInput(format!(
                "joint '{}' is not a fix joint",
                h.label
            )));
        }
        let axes = [Vector3::z(), Vector3::x()];
        let mut dir = 0;
        for e in els {
            match e.primitive {
                Primitive::Point => e.nodes[0] = Node::World(position_m.into()),
                Primitive::Direction => {
                    let d = orientation * axes[dir];
                    dir += 1;
                    e.nodes[0] = Node::World([0.0; 3]);
                    e.nodes[1] = Node::World(d.into());
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// [`Simulation::set_fixed_transform`] with a rotation of `angle_deg` about `axis`.
    pub fn set_fixed_transform_deg(
        &mut self,
        h: &JointHandle,
        position_m: Vector3<f64>,
        angle_deg: f64,
        axis: Vector3<f64>,
    ) -> Result<()> {
        check_axis(&h.label, &axis)?;
        let q = UnitQuaternion::from_axis_angle(&Unit::new_normalize(axis), angle_deg.to_radians());
        self.set_fixed_transform(h, position_m, q)
    }

    /// Readouts of each primitive of a joint at the last accepted step.
    pub fn joint_primitive_readouts(&self, h: &JointHandle) -> Vec<(Primitive, JointReadout)> {
        h.elements
            .iter()
            .filter_map(|&e| self.rigid_bodies.joints.potential.elements.get(e as usize))
            .map(|e| (e.primitive.clone(), e.readout))
            .collect()
    }

    /// The joint's state at the last accepted step: violations, its total force and torque on
    /// body b, its driver's effort, and its coordinate (angle or position) and rate now.
    pub fn joint_state(&self, h: &JointHandle) -> JointState {
        let mut s = JointState::default();
        let els = &self.rigid_bodies.joints.potential.elements;
        for &e in &h.elements {
            let Some(el) = els.get(e as usize) else { continue };
            let r = &el.readout;
            if el.primitive.is_hard() {
                if el.primitive.is_angular() {
                    s.violation_rad = s.violation_rad.max(r.violation);
                } else {
                    s.violation_m = s.violation_m.max(r.violation);
                }
            }
            for k in 0..3 {
                s.force_on_b_n[k] += r.force_b_n[k];
                s.torque_on_b_n_m[k] += r.torque_b_n_m[k];
            }
        }
        if let Some(d) = h.driver.and_then(|d| els.get(d as usize)) {
            let r = &d.readout;
            s.driver_effort = match d.primitive {
                Primitive::AngularVelocity { .. } => {
                    let axis =
                        (d.nodes[3].start_position_world(self) - d.nodes[2].start_position_world(self)).normalize();
                    Vector3::from(r.torque_b_n_m).dot(&axis)
                }
                Primitive::LinearVelocity { .. } => {
                    let axis =
                        (d.nodes[1].start_position_world(self) - d.nodes[0].start_position_world(self)).normalize();
                    Vector3::from(r.force_b_n).dot(&axis)
                }
                Primitive::Spring { .. } => {
                    // Tension: the force on b along the line from b's point to a's.
                    let line = d.nodes[0].start_position_world(self) - d.nodes[1].start_position_world(self);
                    let f = Vector3::from(r.force_b_n);
                    if line.norm() > 0.0 {
                        f.dot(&line.normalize())
                    } else {
                        f.norm()
                    }
                }
                _ => Vector3::from(r.force_b_n).norm(),
            };
        }
        if let Some(m) = h.measure {
            let poses = Poses {
                t: &|b| self.bodies.position[b],
                q: &|b| self.bodies.orientation[b],
            };
            s.coordinate = Some(m.value(&poses));
            s.coordinate_rate = Some(match m {
                Measure::Angle { a, b, axis_a, .. } => {
                    let w =
                        |body: Option<u32>| body.map_or(Vector3::zeros(), |b| self.bodies.angular_velocity[b as usize]);
                    let qa = a.map_or(UnitQuaternion::identity(), |b| self.bodies.orientation[b as usize]);
                    (w(b) - w(a)).dot(&(qa * axis_a))
                }
                Measure::Position {
                    a,
                    b,
                    anchor_a,
                    anchor_b,
                    axis_a,
                } => {
                    let vel = |body: Option<u32>, local: &Vector3<f64>| {
                        body.map_or(Vector3::zeros(), |b| {
                            let b = b as usize;
                            self.bodies.velocity[b]
                                + self.bodies.angular_velocity[b].cross(&(self.bodies.orientation[b] * local))
                        })
                    };
                    let qa = a.map_or(UnitQuaternion::identity(), |b| self.bodies.orientation[b as usize]);
                    (vel(b, &anchor_b) - vel(a, &anchor_a)).dot(&(qa * axis_a))
                }
            });
        }
        s
    }
}

impl Node {
    /// Current (committed) world position of a body-fixed or world node in `sim`.
    fn start_position_world(&self, sim: &Simulation) -> Vector3<f64> {
        match *self {
            Node::Rigid { body, local } => {
                sim.body_point_to_world(RigidBodyHandle { index: body }, &Vector3::from(local))
            }
            Node::World(p) => Vector3::from(p),
            Node::Point(i) => sim.nodes.x[i as usize],
            Node::AngularVelocity(b) => sim.bodies.angular_velocity[b as usize],
        }
    }
}
