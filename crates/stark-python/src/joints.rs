//! Joints, motors and servos between rigid bodies (or a body and the world): `Simulation`
//! methods mirroring the library's `rigidbodies::joints` (rigid-body presets and attachments are
//! in `rigid_objects`).
//!
//! Argument names are the library's (units in the names). Body `a` may be `None`: the world.

use crate::convert::{to_python, Rot, V3};
use crate::handles::*;
use crate::params::{self, Mirror};
use crate::simulation::Simulation;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use stark::rigidbodies::joints::{JointHandle, JointKind, JointReadout, Primitive, DEFAULT_CONTROLLER_DELAY};
use stark::rigidbodies::RigidBodyHandle;

/// A joint: returned by the `Simulation.add_*` joint methods and taken by the joint setters
/// and `joint_state`.
#[pyclass(module = "starkrs", frozen, from_py_object)]
#[derive(Clone, Debug)]
pub struct Joint {
    /// Its label.
    #[pyo3(get)]
    pub label: String,
    /// The library handle.
    pub handle: JointHandle,
    /// The issuing simulation.
    pub sim: u64,
}

#[pymethods]
impl Joint {
    fn __repr__(&self) -> String {
        format!("Joint('{}')", self.label)
    }
    /// Whether it has a driver (motor, press, velocity controller, servo or spring).
    #[getter]
    fn has_driver(&self) -> bool {
        self.handle.driver.is_some()
    }
    /// Whether it has a coordinate (a hinge angle or a slider position).
    #[getter]
    fn has_coordinate(&self) -> bool {
        self.handle.measure.is_some()
    }
}

impl Joint {
    /// Wrap a library handle issued by simulation `sim`.
    pub fn new(sim: u64, handle: JointHandle) -> Self {
        Joint {
            label: handle.label.clone(),
            handle,
            sim,
        }
    }
}

impl Issued for Joint {
    fn simulation_id(&self) -> u64 {
        self.sim
    }
}

/// A joint's state at the last accepted step (`Simulation.joint_state`).
#[pyclass(module = "starkrs", frozen, get_all)]
#[derive(Clone, Debug)]
pub struct JointState {
    /// Largest violation of its length constraints, m.
    pub violation_m: f64,
    /// Largest violation of its angle constraints, rad.
    pub violation_rad: f64,
    /// Total force of the joint on body b (world frame), N.
    pub force_on_b_n: [f64; 3],
    /// Total torque of the joint on body b about its centre of mass, N·m.
    pub torque_on_b_n_m: [f64; 3],
    /// Its driver's effort: torque (N·m) or force (N) along the driver's axis for motors, presses,
    /// velocity controllers and servos (positive when driving b along +axis); a spring's tension (N).
    pub driver_effort: f64,
    /// Its coordinate: hinge angle (rad) or slider position (m), or None.
    pub coordinate: Option<f64>,
    /// Rate of its coordinate, rad/s or m/s, or None.
    pub coordinate_rate: Option<f64>,
}

#[pymethods]
impl JointState {
    fn __repr__(&self) -> String {
        format!(
            "JointState(coordinate={}, coordinate_rate={}, driver_effort={}, violation_m={:.3e}, violation_rad={:.3e})",
            py_optional(self.coordinate),
            py_optional(self.coordinate_rate),
            self.driver_effort,
            self.violation_m,
            self.violation_rad
        )
    }
}

/// An optional number as Python writes it (`None` or the number).
fn py_optional(x: Option<f64>) -> String {
    x.map_or_else(|| "None".to_string(), |x| x.to_string())
}

impl From<stark::rigidbodies::joints::JointState> for JointState {
    fn from(s: stark::rigidbodies::joints::JointState) -> Self {
        JointState {
            violation_m: s.violation_m,
            violation_rad: s.violation_rad,
            force_on_b_n: s.force_on_b_n,
            torque_on_b_n_m: s.torque_on_b_n_m,
            driver_effort: s.driver_effort,
            coordinate: s.coordinate,
            coordinate_rate: s.coordinate_rate,
        }
    }
}

fn joint_params_arg(
    py: Python<'_>,
    p: Option<&Bound<'_, params::JointParams>>,
) -> PyResult<stark::rigidbodies::joints::JointParams> {
    match p {
        Some(p) => p.borrow().to_rust(py),
        None => Ok(Default::default()),
    }
}

impl Simulation {
    fn a_body(&self, a: &Option<BodyArg>) -> PyResult<Option<RigidBodyHandle>> {
        a.as_ref().map(|a| self.body(a)).transpose()
    }

    fn joint_out(&self, h: JointHandle) -> Joint {
        Joint::new(self.id(), h)
    }

    /// A joint from `a` (or the world) and `b` made by `f`.
    fn make_joint(
        &self,
        a: &Option<BodyArg>,
        b: &BodyArg,
        f: impl FnOnce(&mut stark::Simulation, Option<RigidBodyHandle>, RigidBodyHandle) -> stark::Result<JointHandle>,
    ) -> PyResult<Joint> {
        let (a, b) = (self.a_body(a)?, self.body(b)?);
        let h = self.with(|s| f(s, a, b))?;
        Ok(self.joint_out(h))
    }

    fn joint_arg(&self, joint: &Joint) -> PyResult<JointHandle> {
        self.own(joint)?;
        Ok(joint.handle.clone())
    }
}

#[pymethods]
impl Simulation {
    // ---- Joints ----

    /// Ball joint: body b's point at `point_m` (world, now) stays on a's (or the world's).
    #[pyo3(signature = (label, a, b, point_m, params=None))]
    fn add_ball_joint(
        &self,
        py: Python<'_>,
        label: &str,
        a: Option<BodyArg>,
        b: BodyArg,
        point_m: V3,
        params: Option<&Bound<'_, params::JointParams>>,
    ) -> PyResult<Joint> {
        let p = joint_params_arg(py, params)?;
        self.make_joint(&a, &b, |s, a, b| s.add_ball_joint(label, a, b, point_m.0, p))
    }

    /// Ball joint whose `direction` (world, now; fixed in both bodies) may tilt by at most
    /// `limit_deg`.
    #[pyo3(signature = (label, a, b, point_m, direction, limit_deg, params=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_ball_joint_with_cone_limit(
        &self,
        py: Python<'_>,
        label: &str,
        a: Option<BodyArg>,
        b: BodyArg,
        point_m: V3,
        direction: V3,
        limit_deg: f64,
        params: Option<&Bound<'_, params::JointParams>>,
    ) -> PyResult<Joint> {
        let p = joint_params_arg(py, params)?;
        self.make_joint(&a, &b, |s, a, b| {
            s.add_ball_joint_with_cone_limit(label, a, b, point_m.0, direction.0, limit_deg, p)
        })
    }

    /// Body b's point at `point_m` stays on the line through it along `axis` fixed in a.
    #[pyo3(signature = (label, a, b, point_m, axis, params=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_point_on_axis_joint(
        &self,
        py: Python<'_>,
        label: &str,
        a: Option<BodyArg>,
        b: BodyArg,
        point_m: V3,
        axis: V3,
        params: Option<&Bound<'_, params::JointParams>>,
    ) -> PyResult<Joint> {
        let p = joint_params_arg(py, params)?;
        self.make_joint(&a, &b, |s, a, b| {
            s.add_point_on_axis_joint(label, a, b, point_m.0, axis.0, p)
        })
    }

    /// The distance between a's point `point_a_m` and b's point `point_b_m` (world, now) stays
    /// what it is now.
    #[pyo3(signature = (label, a, b, point_a_m, point_b_m, params=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_distance_joint(
        &self,
        py: Python<'_>,
        label: &str,
        a: Option<BodyArg>,
        b: BodyArg,
        point_a_m: V3,
        point_b_m: V3,
        params: Option<&Bound<'_, params::JointParams>>,
    ) -> PyResult<Joint> {
        let p = joint_params_arg(py, params)?;
        self.make_joint(&a, &b, |s, a, b| {
            s.add_distance_joint(label, a, b, point_a_m.0, point_b_m.0, p)
        })
    }

    /// The distance between the two points stays within `[min_m, max_m]`.
    #[pyo3(signature = (label, a, b, point_a_m, point_b_m, min_m, max_m, params=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_distance_limits(
        &self,
        py: Python<'_>,
        label: &str,
        a: Option<BodyArg>,
        b: BodyArg,
        point_a_m: V3,
        point_b_m: V3,
        min_m: f64,
        max_m: f64,
        params: Option<&Bound<'_, params::JointParams>>,
    ) -> PyResult<Joint> {
        let p = joint_params_arg(py, params)?;
        self.make_joint(&a, &b, |s, a, b| {
            s.add_distance_limits(label, a, b, point_a_m.0, point_b_m.0, min_m, max_m, p)
        })
    }

    /// Damped spring between the two points, rest length = their distance now; `limits_m`
    /// (min, max) adds hard distance limits.
    #[pyo3(signature = (label, a, b, point_a_m, point_b_m, stiffness_n_m, damping_n_s_m=0.0, limits_m=None, params=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_spring(
        &self,
        py: Python<'_>,
        label: &str,
        a: Option<BodyArg>,
        b: BodyArg,
        point_a_m: V3,
        point_b_m: V3,
        stiffness_n_m: f64,
        damping_n_s_m: f64,
        limits_m: Option<(f64, f64)>,
        params: Option<&Bound<'_, params::JointParams>>,
    ) -> PyResult<Joint> {
        let p = joint_params_arg(py, params)?;
        self.make_joint(&a, &b, |s, a, b| {
            s.add_spring(
                label,
                a,
                b,
                point_a_m.0,
                point_b_m.0,
                stiffness_n_m,
                damping_n_s_m,
                limits_m,
                p,
            )
        })
    }

    /// `direction` (world, now) stays the same in both bodies.
    #[pyo3(signature = (label, a, b, direction, params=None))]
    fn add_direction_joint(
        &self,
        py: Python<'_>,
        label: &str,
        a: Option<BodyArg>,
        b: BodyArg,
        direction: V3,
        params: Option<&Bound<'_, params::JointParams>>,
    ) -> PyResult<Joint> {
        let p = joint_params_arg(py, params)?;
        self.make_joint(&a, &b, |s, a, b| s.add_direction_joint(label, a, b, direction.0, p))
    }

    /// The angle between `direction` in a and in b stays below `limit_deg`.
    #[pyo3(signature = (label, a, b, direction, limit_deg, params=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_angle_limit(
        &self,
        py: Python<'_>,
        label: &str,
        a: Option<BodyArg>,
        b: BodyArg,
        direction: V3,
        limit_deg: f64,
        params: Option<&Bound<'_, params::JointParams>>,
    ) -> PyResult<Joint> {
        let p = joint_params_arg(py, params)?;
        self.make_joint(&a, &b, |s, a, b| {
            s.add_angle_limit(label, a, b, direction.0, limit_deg, p)
        })
    }

    /// Fix a body to the world where it is; `set_fixed_transform` then drives it kinematically.
    #[pyo3(signature = (label, body, params=None))]
    fn add_fix_joint(
        &self,
        py: Python<'_>,
        label: &str,
        body: BodyArg,
        params: Option<&Bound<'_, params::JointParams>>,
    ) -> PyResult<Joint> {
        let p = joint_params_arg(py, params)?;
        let b = self.body(&body)?;
        let h = self.with(|s| s.add_fix_joint(label, b, p))?;
        Ok(self.joint_out(h))
    }

    /// Glue body b to body a in their current relative pose.
    #[pyo3(signature = (label, a, b, params=None))]
    fn add_attachment_joint(
        &self,
        py: Python<'_>,
        label: &str,
        a: BodyArg,
        b: BodyArg,
        params: Option<&Bound<'_, params::JointParams>>,
    ) -> PyResult<Joint> {
        let p = joint_params_arg(py, params)?;
        let (a, b) = (self.body(&a)?, self.body(&b)?);
        let h = self.with(|s| s.add_attachment_joint(label, a, b, p))?;
        Ok(self.joint_out(h))
    }

    /// Hinge about `axis` through `point_m` (world, now).
    #[pyo3(signature = (label, a, b, point_m, axis, params=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_hinge_joint(
        &self,
        py: Python<'_>,
        label: &str,
        a: Option<BodyArg>,
        b: BodyArg,
        point_m: V3,
        axis: V3,
        params: Option<&Bound<'_, params::JointParams>>,
    ) -> PyResult<Joint> {
        let p = joint_params_arg(py, params)?;
        self.make_joint(&a, &b, |s, a, b| s.add_hinge_joint(label, a, b, point_m.0, axis.0, p))
    }

    /// Hinge that turns at most `limit_deg` either way from its current angle.
    #[pyo3(signature = (label, a, b, point_m, axis, limit_deg, params=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_hinge_joint_with_limit(
        &self,
        py: Python<'_>,
        label: &str,
        a: Option<BodyArg>,
        b: BodyArg,
        point_m: V3,
        axis: V3,
        limit_deg: f64,
        params: Option<&Bound<'_, params::JointParams>>,
    ) -> PyResult<Joint> {
        let p = joint_params_arg(py, params)?;
        self.make_joint(&a, &b, |s, a, b| {
            s.add_hinge_joint_with_limit(label, a, b, point_m.0, axis.0, limit_deg, p)
        })
    }

    /// Universal (Cardan) joint at `point_m`: `axis_a` (in a) stays perpendicular to `axis_b`
    /// (in b); they must be perpendicular now.
    #[pyo3(signature = (label, a, b, point_m, axis_a, axis_b, params=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_universal_joint(
        &self,
        py: Python<'_>,
        label: &str,
        a: Option<BodyArg>,
        b: BodyArg,
        point_m: V3,
        axis_a: V3,
        axis_b: V3,
        params: Option<&Bound<'_, params::JointParams>>,
    ) -> PyResult<Joint> {
        let p = joint_params_arg(py, params)?;
        self.make_joint(&a, &b, |s, a, b| {
            s.add_universal_joint(label, a, b, point_m.0, axis_a.0, axis_b.0, p)
        })
    }

    /// Slider: b moves along `axis` through `point_m` and may turn about it.
    #[pyo3(signature = (label, a, b, point_m, axis, params=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_slider_joint(
        &self,
        py: Python<'_>,
        label: &str,
        a: Option<BodyArg>,
        b: BodyArg,
        point_m: V3,
        axis: V3,
        params: Option<&Bound<'_, params::JointParams>>,
    ) -> PyResult<Joint> {
        let p = joint_params_arg(py, params)?;
        self.make_joint(&a, &b, |s, a, b| s.add_slider_joint(label, a, b, point_m.0, axis.0, p))
    }

    /// Prismatic joint: b only translates along `axis`.
    #[pyo3(signature = (label, a, b, point_m, axis, params=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_prismatic_joint(
        &self,
        py: Python<'_>,
        label: &str,
        a: Option<BodyArg>,
        b: BodyArg,
        point_m: V3,
        axis: V3,
        params: Option<&Bound<'_, params::JointParams>>,
    ) -> PyResult<Joint> {
        let p = joint_params_arg(py, params)?;
        self.make_joint(&a, &b, |s, a, b| {
            s.add_prismatic_joint(label, a, b, point_m.0, axis.0, p)
        })
    }

    /// Prismatic press: a prismatic joint driven at `target_m_s` along `axis` with at most
    /// `max_force_n`; `delay_m_s` is the speed error over which the force ramps up.
    #[pyo3(signature = (label, a, b, point_m, axis, target_m_s, max_force_n, delay_m_s=DEFAULT_CONTROLLER_DELAY, params=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_prismatic_press(
        &self,
        py: Python<'_>,
        label: &str,
        a: Option<BodyArg>,
        b: BodyArg,
        point_m: V3,
        axis: V3,
        target_m_s: f64,
        max_force_n: f64,
        delay_m_s: f64,
        params: Option<&Bound<'_, params::JointParams>>,
    ) -> PyResult<Joint> {
        let p = joint_params_arg(py, params)?;
        self.make_joint(&a, &b, |s, a, b| {
            s.add_prismatic_press(label, a, b, point_m.0, axis.0, target_m_s, max_force_n, delay_m_s, p)
        })
    }

    /// Motor: a hinge driven at `target_rad_s` about `axis` with at most `max_torque_n_m`.
    #[pyo3(signature = (label, a, b, point_m, axis, target_rad_s, max_torque_n_m, delay_rad_s=DEFAULT_CONTROLLER_DELAY, params=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_motor(
        &self,
        py: Python<'_>,
        label: &str,
        a: Option<BodyArg>,
        b: BodyArg,
        point_m: V3,
        axis: V3,
        target_rad_s: f64,
        max_torque_n_m: f64,
        delay_rad_s: f64,
        params: Option<&Bound<'_, params::JointParams>>,
    ) -> PyResult<Joint> {
        let p = joint_params_arg(py, params)?;
        self.make_joint(&a, &b, |s, a, b| {
            s.add_motor(
                label,
                a,
                b,
                point_m.0,
                axis.0,
                target_rad_s,
                max_torque_n_m,
                delay_rad_s,
                p,
            )
        })
    }

    /// Angular velocity controller alone: drives `(ω_b − ω_a)·axis` to `target_rad_s` with at
    /// most `max_torque_n_m`.
    #[pyo3(signature = (label, a, b, axis, target_rad_s, max_torque_n_m, delay_rad_s=DEFAULT_CONTROLLER_DELAY))]
    #[allow(clippy::too_many_arguments)]
    fn add_angular_velocity_controller(
        &self,
        label: &str,
        a: Option<BodyArg>,
        b: BodyArg,
        axis: V3,
        target_rad_s: f64,
        max_torque_n_m: f64,
        delay_rad_s: f64,
    ) -> PyResult<Joint> {
        self.make_joint(&a, &b, |s, a, b| {
            s.add_angular_velocity_controller(label, a, b, axis.0, target_rad_s, max_torque_n_m, delay_rad_s)
        })
    }

    /// Linear velocity controller alone: drives the relative velocity of the points at
    /// `point_m` along `axis` to `target_m_s` with at most `max_force_n`.
    #[pyo3(signature = (label, a, b, point_m, axis, target_m_s, max_force_n, delay_m_s=DEFAULT_CONTROLLER_DELAY))]
    #[allow(clippy::too_many_arguments)]
    fn add_linear_velocity_controller(
        &self,
        label: &str,
        a: Option<BodyArg>,
        b: BodyArg,
        point_m: V3,
        axis: V3,
        target_m_s: f64,
        max_force_n: f64,
        delay_m_s: f64,
    ) -> PyResult<Joint> {
        self.make_joint(&a, &b, |s, a, b| {
            s.add_linear_velocity_controller(label, a, b, point_m.0, axis.0, target_m_s, max_force_n, delay_m_s)
        })
    }

    /// Hinge servo: a motor that turns to `target_deg` (relative to now) with at most
    /// `max_torque_n_m`, closing the error within about `response_time_s`.
    #[pyo3(signature = (label, a, b, point_m, axis, target_deg, max_torque_n_m, response_time_s, params=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_hinge_servo(
        &self,
        py: Python<'_>,
        label: &str,
        a: Option<BodyArg>,
        b: BodyArg,
        point_m: V3,
        axis: V3,
        target_deg: f64,
        max_torque_n_m: f64,
        response_time_s: f64,
        params: Option<&Bound<'_, params::JointParams>>,
    ) -> PyResult<Joint> {
        let p = joint_params_arg(py, params)?;
        self.make_joint(&a, &b, |s, a, b| {
            s.add_hinge_servo(
                label,
                a,
                b,
                point_m.0,
                axis.0,
                target_deg,
                max_torque_n_m,
                response_time_s,
                p,
            )
        })
    }

    /// Prismatic servo: a press that moves to `target_m` (relative to now) along `axis` with at
    /// most `max_force_n`, closing the error within about `response_time_s`.
    #[pyo3(signature = (label, a, b, point_m, axis, target_m, max_force_n, response_time_s, params=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_prismatic_servo(
        &self,
        py: Python<'_>,
        label: &str,
        a: Option<BodyArg>,
        b: BodyArg,
        point_m: V3,
        axis: V3,
        target_m: f64,
        max_force_n: f64,
        response_time_s: f64,
        params: Option<&Bound<'_, params::JointParams>>,
    ) -> PyResult<Joint> {
        let p = joint_params_arg(py, params)?;
        self.make_joint(&a, &b, |s, a, b| {
            s.add_prismatic_servo(
                label,
                a,
                b,
                point_m.0,
                axis.0,
                target_m,
                max_force_n,
                response_time_s,
                p,
            )
        })
    }

    /// Every joint made so far, in creation order.
    fn joints(&self) -> PyResult<Vec<Joint>> {
        let hs = self.get(|s| s.rigid_bodies.named_joints.clone())?;
        Ok(hs.into_iter().map(|h| self.joint_out(h)).collect())
    }

    /// The joint labelled `label`, or None.
    fn joint(&self, label: &str) -> PyResult<Option<Joint>> {
        let h = self.get(|s| s.rigid_bodies.named_joints.iter().find(|j| j.label == label).cloned())?;
        Ok(h.map(|h| self.joint_out(h)))
    }

    /// The joint's state at the last accepted step.
    fn joint_state(&self, joint: Joint) -> PyResult<JointState> {
        let h = self.joint_arg(&joint)?;
        Ok(self.get(|s| s.joint_state(&h))?.into())
    }

    /// The state of every joint at the last accepted step, by label (a repeated label gets `#2`,
    /// `#3`, ... as in the joint log).
    fn joint_states<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let states = self.get(|s| s.joint_states())?;
        let d = PyDict::new(py);
        for (label, state) in states {
            d.set_item(label, JointState::from(state))?;
        }
        Ok(d)
    }

    /// Largest violation of any enabled hard joint constraint at the last accepted step:
    /// (m, rad).
    fn max_joint_violations(&self) -> PyResult<(f64, f64)> {
        self.get(|s| s.max_joint_violations())
    }

    /// Each primitive of a joint at the last accepted step, in the order the joint is built of
    /// them: dicts with `primitive` (its `kind` and parameters, e.g. `{"kind": "distance",
    /// "target_m": 0.2}`), `violation` (m, or rad for angular primitives), and the forces (N,
    /// world frame) and torques (N·m, about each body's centre of mass) on the two bodies:
    /// `force_a_n`, `torque_a_n_m`, `force_b_n`, `torque_b_n_m`.
    fn joint_primitive_readouts<'py>(&self, py: Python<'py>, joint: Joint) -> PyResult<Bound<'py, PyAny>> {
        #[derive(serde::Serialize)]
        struct Row {
            primitive: Primitive,
            #[serde(flatten)]
            readout: JointReadout,
        }
        let h = self.joint_arg(&joint)?;
        let rows: Vec<Row> = self
            .get(|s| s.joint_primitive_readouts(&h))?
            .into_iter()
            .map(|(primitive, readout)| Row { primitive, readout })
            .collect();
        to_python(py, &rows)
    }

    /// Largest stiffness of the joint's hard constraints (after hardening), N/m.
    fn joint_stiffness(&self, joint: Joint) -> PyResult<f64> {
        let h = self.joint_arg(&joint)?;
        self.get(|s| s.joint_stiffness(&h))
    }

    /// Switch a joint on or off (off: it exerts nothing).
    fn set_joint_enabled(&self, joint: Joint, enabled: bool) -> PyResult<()> {
        let h = self.joint_arg(&joint)?;
        self.with(|s| s.set_joint_enabled(&h, enabled))
    }

    /// Stiffness of the joint's hard constraints, N/m.
    fn set_joint_stiffness(&self, joint: Joint, stiffness: f64) -> PyResult<()> {
        let h = self.joint_arg(&joint)?;
        self.with(|s| s.set_joint_stiffness(&h, stiffness))
    }

    /// Tolerances the joint is hardened to: m and degrees.
    fn set_joint_tolerance(&self, joint: Joint, tolerance_m: f64, tolerance_deg: f64) -> PyResult<()> {
        let h = self.joint_arg(&joint)?;
        self.with(|s| s.set_joint_tolerance(&h, tolerance_m, tolerance_deg))
    }

    /// Target velocity of a motor, press or velocity controller: rad/s or m/s.
    fn set_joint_target_velocity(&self, joint: Joint, target: f64) -> PyResult<()> {
        let h = self.joint_arg(&joint)?;
        self.with(|s| s.set_joint_target_velocity(&h, target))
    }

    /// Largest torque (N·m) or force (N) of a motor, press, controller or servo.
    fn set_joint_max_effort(&self, joint: Joint, max: f64) -> PyResult<()> {
        let h = self.joint_arg(&joint)?;
        self.with(|s| s.set_joint_max_effort(&h, max))
    }

    /// Target of a servo: degrees for a hinge servo, metres for a prismatic one.
    fn set_servo_target(&self, joint: Joint, target: f64) -> PyResult<()> {
        let h = self.joint_arg(&joint)?;
        self.with(|s| s.set_servo_target(&h, target))
    }

    /// Rest length (m) and damping (N·s/m) of a spring.
    fn set_spring(&self, joint: Joint, rest_length_m: f64, damping_n_s_m: f64) -> PyResult<()> {
        let h = self.joint_arg(&joint)?;
        self.with(|s| s.set_spring(&h, rest_length_m, damping_n_s_m))
    }

    /// Target pose of a fix joint's body: position (m) of its centre of mass and orientation
    /// (quaternion (w, x, y, z) or (3, 3) matrix), met at the end of the next step.
    fn set_fixed_transform(&self, joint: Joint, position_m: V3, orientation: Rot) -> PyResult<()> {
        let h = self.joint_arg(&joint)?;
        self.with(|s| s.set_fixed_transform(&h, position_m.0, orientation.0))
    }

    /// Target pose of a fix joint's body: centre of mass at `position_m` (m), orientation a
    /// rotation of `angle_deg` about `axis` (met at the end of the next step).
    fn set_fixed_transform_deg(&self, joint: Joint, position_m: V3, angle_deg: f64, axis: V3) -> PyResult<()> {
        let h = self.joint_arg(&joint)?;
        self.with(|s| s.set_fixed_transform_deg(&h, position_m.0, angle_deg, axis.0))
    }
}

/// Register the classes.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Joint>()?;
    m.add_class::<JointState>()?;
    Ok(())
}

/// A `JointKind` from a dict with the fields of a scene file's `[[joint]]` type (through JSON, so
/// that serde names a misspelt field; NumPy arrays are read as lists).
fn joint_kind(py: Python<'_>, label: &str, kind: &Bound<'_, PyAny>) -> PyResult<JointKind> {
    let as_list = pyo3::types::PyCFunction::new_closure(
        py,
        None,
        None,
        |args: &Bound<'_, pyo3::types::PyTuple>, _: Option<&Bound<'_, PyDict>>| -> PyResult<Py<PyAny>> {
            Ok(args.get_item(0)?.call_method0("tolist")?.unbind())
        },
    )?;
    let kwargs = PyDict::new(py);
    kwargs.set_item("default", as_list)?;
    let json: String = py
        .import("json")?
        .getattr("dumps")?
        .call((kind,), Some(&kwargs))?
        .extract()?;
    serde_json::from_str(&json).map_err(|e| {
        let text = e.to_string();
        let message = text.rsplit_once(" at line ").map_or(text.as_str(), |(m, _)| m);
        pyo3::exceptions::PyValueError::new_err(format!("joint '{label}': kind: {message}"))
    })
}

#[pymethods]
impl Simulation {
    /// Add a joint of any kind (the library's `add_joint`): `kind` is a dict with `type` and the
    /// fields of that type as a scene file's `[[joint]]` spells them (docs/scene-format.md),
    /// e.g. `{"type": "hinge", "point_m": [0, 0, 0], "axis": [0, 1, 0]}` or
    /// `{"type": "motor", ..., "target_velocity_deg_s": 90, "max_torque_n_m": 1}`. `a` may be
    /// None (the world); `a` and `b` are None for the couplings (`joint_coupling`,
    /// `joint_spring`), which name their joints by label. A misspelt or missing field is a
    /// ValueError naming it.
    #[pyo3(signature = (label, a, b, kind, params=None))]
    fn add_joint(
        &self,
        py: Python<'_>,
        label: &str,
        a: Option<BodyArg>,
        b: Option<BodyArg>,
        kind: &Bound<'_, PyAny>,
        params: Option<&Bound<'_, params::JointParams>>,
    ) -> PyResult<Joint> {
        let kind = joint_kind(py, label, kind)?;
        let p = joint_params_arg(py, params)?;
        let (a, b) = (self.a_body(&a)?, self.a_body(&b)?);
        let h = self.with(|s| s.add_joint(label, a, b, kind, p))?;
        Ok(self.joint_out(h))
    }
}
