//! The builder of a composite joint: the bodies (or the world) it connects and the primitive
//! elements it pushes onto the joint term, its driver and its coordinate.

use super::{JointElement, JointHandle, JointParams, JointReadout, Measure, Primitive};
use crate::energy::Node;
use crate::error::{Result, StarkError};
use crate::rigidbodies::RigidBodyHandle;
use crate::simulation::Simulation;
use nalgebra::{UnitQuaternion, Vector3};

/// Everything a joint is attached to, resolved from handles and world coordinates.
#[derive(Clone, Copy)]
pub(super) struct Side {
    pub(super) body: Option<u32>,
    pub(super) t: Vector3<f64>,
    pub(super) q: UnitQuaternion<f64>,
}

impl Side {
    pub(super) fn point(&self, world: &Vector3<f64>) -> Node {
        match self.body {
            None => Node::World((*world).into()),
            Some(b) => Node::rigid(b as usize, &(self.q.inverse() * (world - self.t))),
        }
    }
    pub(super) fn local_dir(&self, world: &Vector3<f64>) -> Vector3<f64> {
        self.q.inverse() * world
    }
    /// A unit direction as two points one unit apart, starting at the centre of mass.
    pub(super) fn direction(&self, world_dir: &Vector3<f64>) -> [Node; 2] {
        let d = world_dir.normalize();
        [self.point(&self.t), self.point(&(self.t + d))]
    }
    pub(super) fn omega(&self) -> Node {
        match self.body {
            None => Node::World([0.0; 3]),
            Some(b) => Node::AngularVelocity(b),
        }
    }
}

/// A unit vector perpendicular to `axis`.
pub(super) fn perpendicular(axis: &Vector3<f64>) -> Vector3<f64> {
    let a = axis.normalize();
    let trial = if a.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
    (trial - a * a.dot(&trial)).normalize()
}

/// Builds one composite joint.
pub(super) struct Builder<'s> {
    pub(super) sim: &'s mut Simulation,
    pub(super) label: String,
    pub(super) params: JointParams,
    pub(super) a: Side,
    pub(super) b: Side,
    pub(super) elements: Vec<u32>,
    pub(super) driver: Option<u32>,
    pub(super) measure: Option<Measure>,
}

impl<'s> Builder<'s> {
    pub(super) fn new(
        sim: &'s mut Simulation,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: Option<RigidBodyHandle>,
        params: JointParams,
    ) -> Result<Self> {
        params.validate(label)?;
        let side = |sim: &Simulation, h: Option<RigidBodyHandle>| -> Result<Side> {
            Ok(match h {
                None => Side {
                    body: None,
                    t: Vector3::zeros(),
                    q: UnitQuaternion::identity(),
                },
                Some(h) => {
                    let i = sim.check_body(h)?;
                    Side {
                        body: Some(i as u32),
                        t: sim.bodies.position[i],
                        q: sim.bodies.orientation[i],
                    }
                }
            })
        };
        let (sa, sb) = (side(sim, a)?, side(sim, b)?);
        if sa.body.is_none() && sb.body.is_none() {
            return Err(StarkError::InvalidInput(format!(
                "joint '{label}' connects the world to itself"
            )));
        }
        if let (Some(ia), Some(ib)) = (sa.body, sb.body) {
            if ia == ib {
                let name = &sim.rigid_bodies.labels[ia as usize];
                return Err(StarkError::InvalidInput(format!(
                    "joint '{label}' connects '{name}' to itself: `b` must be another body than `a`"
                )));
            }
        }
        Ok(Builder {
            sim,
            label: label.to_string(),
            params,
            a: sa,
            b: sb,
            elements: Vec::new(),
            driver: None,
            measure: None,
        })
    }

    pub(super) fn push(&mut self, primitive: Primitive, nodes: &[Node]) -> u32 {
        let mut all = [Node::World([0.0; 3]); 4];
        all[..nodes.len()].copy_from_slice(nodes);
        let tolerance = if !primitive.is_hard() {
            f64::INFINITY
        } else if primitive.is_angular() {
            self.params.tolerance_deg.to_radians()
        } else {
            self.params.tolerance_m
        };
        let set = &mut self.sim.rigid_bodies.joints.potential;
        set.elements.push(JointElement {
            label: self.label.clone(),
            primitive,
            nodes: all,
            bodies: [self.a.body, self.b.body],
            stiffness: self.params.stiffness,
            tolerance,
            enabled: true,
            servo: None,
            readout: JointReadout::default(),
        });
        set.version += 1;
        let e = (set.elements.len() - 1) as u32;
        self.elements.push(e);
        e
    }

    pub(super) fn point(&mut self, p: &Vector3<f64>) {
        let nodes = [self.a.point(p), self.b.point(p)];
        self.push(Primitive::Point, &nodes);
    }

    pub(super) fn direction(&mut self, d: &Vector3<f64>) {
        let [a0, a1] = self.a.direction(d);
        let [b0, b1] = self.b.direction(d);
        self.push(Primitive::Direction, &[a0, a1, b0, b1]);
    }

    pub(super) fn point_on_axis(&mut self, p: &Vector3<f64>, axis: &Vector3<f64>) {
        let nodes = [self.a.point(p), self.a.point(&(p + axis.normalize())), self.b.point(p)];
        self.push(Primitive::PointOnAxis, &nodes);
    }

    pub(super) fn angle_limit(&mut self, d: &Vector3<f64>, limit_rad: f64) {
        let [a0, a1] = self.a.direction(d);
        let [b0, b1] = self.b.direction(d);
        self.push(Primitive::AngleLimit { limit_rad }, &[a0, a1, b0, b1]);
    }

    pub(super) fn angular_velocity(
        &mut self,
        axis: &Vector3<f64>,
        target_rad_s: f64,
        max_torque_n_m: f64,
        delay_rad_s: f64,
    ) {
        let [a0, a1] = self.a.direction(axis);
        let e = self.push(
            Primitive::AngularVelocity {
                target_rad_s,
                max_torque_n_m,
                delay_rad_s,
                drive_only: false,
            },
            &[self.a.omega(), self.b.omega(), a0, a1],
        );
        self.driver = Some(e);
    }

    pub(super) fn linear_velocity(
        &mut self,
        p: &Vector3<f64>,
        axis: &Vector3<f64>,
        target_m_s: f64,
        max_force_n: f64,
        delay_m_s: f64,
    ) {
        let nodes = [self.a.point(p), self.a.point(&(p + axis.normalize())), self.b.point(p)];
        let e = self.push(
            Primitive::LinearVelocity {
                target_m_s,
                max_force_n,
                delay_m_s,
            },
            &nodes,
        );
        self.driver = Some(e);
    }

    pub(super) fn angle_measure(&mut self, axis: &Vector3<f64>) {
        let u = perpendicular(axis);
        self.measure = Some(Measure::Angle {
            a: self.a.body,
            b: self.b.body,
            axis_a: self.a.local_dir(&axis.normalize()),
            ref_a: self.a.local_dir(&u),
            ref_b: self.b.local_dir(&u),
        });
    }

    pub(super) fn position_measure(&mut self, p: &Vector3<f64>, axis: &Vector3<f64>) {
        let local = |s: &Side| s.q.inverse() * (p - s.t);
        self.measure = Some(Measure::Position {
            a: self.a.body,
            b: self.b.body,
            anchor_a: local(&self.a),
            anchor_b: local(&self.b),
            axis_a: self.a.local_dir(&axis.normalize()),
        });
    }

    pub(super) fn finish(self) -> JointHandle {
        self.sim.register_joint(JointHandle {
            label: self.label,
            elements: self.elements,
            driver: self.driver,
            measure: self.measure,
        })
    }
}
