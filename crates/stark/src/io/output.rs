//! Simulation output: frames at a fixed rate and per-step logs as JSON lines.
//!
//! Frames are `<directory>/<name>_<label>_<frame>.vtu` (VTK XML, binary), one file per
//! registered mesh (deformable objects, obstacles and rigid-body meshes, which are written at the
//! body's pose), listed with their simulated times in `<directory>/<name>.pvd` (open that in
//! ParaView for a time axis in seconds; meshio reads both). Point data: `velocity` (m/s),
//! `contact_force_n` (the barrier force on the node, N), `prescribed` and `attached` (0/1). Cell
//! data of tets and triangles: `green_strain` (3×3, row-major), `cauchy_stress_pa` (3×3),
//! `von_mises_pa`, `principal_stress_pa` (largest first) and `strain_limit_active` (0/1).
//! With `settings.output.frame_format = "legacy_vtk"` the frames are legacy VTK
//! (`.vtk`, binary) with the velocity only. The step log
//! `<directory>/<name>.steps.jsonl` has one JSON object per accepted step.
//!
//! With rigid bodies, `<name>.bodies.jsonl` has one line per accepted step with every body's
//! pose and velocity, keyed by label:
//!
//! ```text
//! {"step":0,"time_s":0.01,"bodies":{"link0":{"position_m":[..],"orientation_wxyz":[..],"velocity_m_s":[..],"angular_velocity_rad_s":[..]}}}
//! ```
//!
//! and with joints `<name>.joints.jsonl` one line per step with every joint's
//! [`JointState`] keyed by label (a repeated label gets `#2`, `#3`, ...):
//!
//! ```text
//! {"step":0,"time_s":0.01,"joints":{"hinge0":{"violation_m":..,"violation_rad":..,"force_on_b_n":[..],"torque_on_b_n_m":[..],"driver_effort":..,"coordinate":..,"coordinate_rate":..}}}
//! ```
//!
//! Both are switched by `settings.output.bodies_log` and `joints_log` (on by default; off
//! when `step_log` is off).

use super::fields::{CellFields, NodeFields};
use super::vtk::{VtkCells, VtkWriter};
use super::vtu::{write_pvd, VtuCells, VtuWriter};
use crate::deformables::NodeSetHandle;
use crate::error::{Result, StarkError};
use crate::rigidbodies::joints::JointState;
use crate::simulation::Simulation;
use crate::state::NodeArrays;
use nalgebra::Vector3;
use serde::ser::SerializeMap;
use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};

// Defined in state: the models register their output meshes and sit below io.
pub use crate::state::OutputCells;

/// A mesh written in every frame.
#[derive(Clone, Debug)]
pub struct OutputMesh {
    /// Label in the file name.
    pub label: String,
    /// Its nodes.
    pub set: NodeSetHandle,
    /// Its cells.
    pub cells: OutputCells,
    /// Simulated time from which it exists (−∞, or the time of the spawn that added it), s:
    /// the `.pvd` lists it in the frames from then on.
    pub first_time_s: f64,
}

/// Writes frames and the step log.
#[derive(Default)]
pub struct Output {
    /// Registered meshes.
    pub meshes: Vec<OutputMesh>,
    /// Frames written so far.
    pub frames_written: usize,
    /// Time of the next frame, s.
    pub next_frame_time: f64,
    /// Simulated time of each frame written, s.
    pub frame_times: Vec<f64>,
    log: Option<std::io::BufWriter<std::fs::File>>,
    bodies_log: Option<std::io::BufWriter<std::fs::File>>,
    joints_log: Option<std::io::BufWriter<std::fs::File>>,
    /// Probe logs: name, what to record, and the file once opened.
    pub(crate) probes: Vec<Probe>,
    scratch_x: Vec<Vector3<f64>>,
    scratch_v: Vec<Vector3<f64>>,
}

fn io_err(path: &Path, source: std::io::Error) -> StarkError {
    StarkError::Output {
        path: path.display().to_string(),
        source,
    }
}

/// A mesh label as part of a file name: robot links are labelled `<robot>/<link>`, and a
/// directory separator in a frame's name would point into a directory that does not exist.
fn file_label(label: &str) -> String {
    label.replace(['/', '\\'], "-")
}

impl Output {
    /// Register a mesh for the frames.
    pub fn add_mesh(&mut self, label: &str, set: NodeSetHandle, cells: OutputCells) {
        self.meshes.push(OutputMesh {
            label: label.to_string(),
            set,
            cells,
            first_time_s: f64::NEG_INFINITY,
        });
    }

    /// Write one frame of every mesh; returns the files written.
    pub fn write_frame(&mut self, directory: &Path, name: &str, nodes: &NodeArrays) -> Result<Vec<PathBuf>> {
        std::fs::create_dir_all(directory).map_err(|e| io_err(directory, e))?;
        let mut files = Vec::new();
        for mesh in &self.meshes {
            let r = mesh.set.range();
            self.scratch_x.clear();
            self.scratch_x.extend_from_slice(&nodes.x[r.clone()]);
            self.scratch_v.clear();
            self.scratch_v.extend_from_slice(&nodes.v[r]);
            let cells = match &mesh.cells {
                OutputCells::Points => VtkCells::Points,
                OutputCells::Segments(s) => VtkCells::Segments(s),
                OutputCells::Triangles(t) => VtkCells::Triangles(t),
                OutputCells::Tets(t) => VtkCells::Tets(t),
            };
            let path = directory.join(format!(
                "{name}_{}_{:05}.vtk",
                file_label(&mesh.label),
                self.frames_written
            ));
            VtkWriter::new(&self.scratch_x, cells)
                .title(&format!("{name} {} frame {}", mesh.label, self.frames_written))
                .point_vectors("velocity", &self.scratch_v)
                .write(&path)
                .map_err(|e| StarkError::Output {
                    path: path.display().to_string(),
                    source: std::io::Error::other(e.to_string()),
                })?;
            files.push(path);
        }
        self.frames_written += 1;
        Ok(files)
    }

    /// Write one VTU frame of every mesh at `time_s`, with the node fields (over all nodes)
    /// and each mesh's cell fields (where given and matching its cells), and rewrite the run's
    /// `<name>.pvd` collection. Returns the files written.
    pub fn write_frame_vtu(
        &mut self,
        directory: &Path,
        name: &str,
        nodes: &NodeArrays,
        time_s: f64,
        node_fields: &NodeFields,
        cell_fields: &[Option<Vec<CellFields>>],
    ) -> Result<Vec<PathBuf>> {
        std::fs::create_dir_all(directory).map_err(|e| io_err(directory, e))?;
        let mut files = Vec::new();
        for (k, mesh) in self.meshes.iter().enumerate() {
            let r = mesh.set.range();
            let (cells, n_cells) = match &mesh.cells {
                OutputCells::Points => (VtuCells::Points, mesh.set.len as usize),
                OutputCells::Segments(s) => (VtuCells::Segments(s), s.len()),
                OutputCells::Triangles(t) => (VtuCells::Triangles(t), t.len()),
                OutputCells::Tets(t) => (VtuCells::Tets(t), t.len()),
            };
            let file = format!("{name}_{}_{:05}.vtu", file_label(&mesh.label), self.frames_written);
            let path = directory.join(&file);
            let mut w = VtuWriter::new(&nodes.x[r.clone()], cells)
                .time(time_s)
                .point_vectors("velocity", &nodes.v[r.clone()])
                .point_vectors("contact_force_n", &node_fields.contact_force_n[r.clone()])
                .point_flags("prescribed", &node_fields.prescribed[r.clone()])
                .point_flags("attached", &node_fields.attached[r]);
            if let Some(Some(f)) = cell_fields.get(k) {
                if f.len() == n_cells {
                    w = w.cell_fields(f);
                }
            }
            w.write(&path).map_err(|e| io_err(&path, e))?;
            files.push(path);
        }
        self.frames_written += 1;
        self.frame_times.push(time_s);
        let entries: Vec<(f64, usize, String)> = self
            .frame_times
            .iter()
            .enumerate()
            .flat_map(|(f, &t)| {
                self.meshes
                    .iter()
                    .enumerate()
                    .filter(move |(_, m)| t >= m.first_time_s)
                    .map(move |(k, m)| (t, k, format!("{name}_{}_{f:05}.vtu", file_label(&m.label))))
            })
            .collect();
        let pvd = directory.join(format!("{name}.pvd"));
        write_pvd(&pvd, &entries).map_err(|e| io_err(&pvd, e))?;
        Ok(files)
    }

    /// Start the step log (truncates an existing one).
    pub fn open_log(&mut self, directory: &Path, name: &str) -> Result<PathBuf> {
        self.open_log_keeping(directory, name, None)
    }

    /// Start the step log; with `keep_lines`, an existing log keeps its first lines (a run
    /// resumed from a checkpoint continues it) and the rest is dropped.
    pub fn open_log_keeping(&mut self, directory: &Path, name: &str, keep_lines: Option<u64>) -> Result<PathBuf> {
        let (log, path) = create_log(directory, format!("{name}.steps.jsonl"), keep_lines)?;
        self.log = Some(log);
        Ok(path)
    }

    /// Append one record to the step log (if open).
    pub fn log<T: serde::Serialize>(&mut self, record: &T) -> Result<()> {
        if let Some(log) = &mut self.log {
            let line = serde_json::to_string(record).expect("serialisable record");
            writeln!(log, "{line}").map_err(|e| io_err(Path::new("step log"), e))?;
        }
        Ok(())
    }

    /// Flush the logs.
    pub fn flush(&mut self) -> Result<()> {
        for (log, what) in [
            (&mut self.log, "step log"),
            (&mut self.bodies_log, "body log"),
            (&mut self.joints_log, "joint log"),
        ] {
            if let Some(log) = log {
                log.flush().map_err(|e| io_err(Path::new(what), e))?;
            }
        }
        Ok(())
    }
}

/// Create a log file; with `keep_lines`, keep that many lines of an existing one (one line per
/// step in every log) and append after them.
fn create_log(
    directory: &Path,
    file: String,
    keep_lines: Option<u64>,
) -> Result<(std::io::BufWriter<std::fs::File>, PathBuf)> {
    std::fs::create_dir_all(directory).map_err(|e| io_err(directory, e))?;
    let path = directory.join(file);
    let kept = match keep_lines {
        Some(n) => match std::fs::read_to_string(&path) {
            Ok(text) => text.lines().take(n as usize).fold(String::new(), |mut acc, l| {
                acc.push_str(l);
                acc.push('\n');
                acc
            }),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
            Err(e) => return Err(io_err(&path, e)),
        },
        None => String::new(),
    };
    let f = std::fs::File::create(&path).map_err(|e| io_err(&path, e))?;
    let mut w = std::io::BufWriter::new(f);
    w.write_all(kept.as_bytes()).map_err(|e| io_err(&path, e))?;
    Ok((w, path))
}

fn write_line<T: Serialize>(log: &mut Option<std::io::BufWriter<std::fs::File>>, what: &str, record: &T) -> Result<()> {
    if let Some(log) = log {
        let line = serde_json::to_string(record).expect("serialisable record");
        writeln!(log, "{line}").map_err(|e| io_err(Path::new(what), e))?;
    }
    Ok(())
}

/// Pose and velocity of a rigid body (one entry of a line of the body log).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct BodyState {
    /// Centre of mass, m.
    pub position_m: [f64; 3],
    /// Orientation (body → world) as a unit quaternion `[w, x, y, z]`.
    pub orientation_wxyz: [f64; 4],
    /// Velocity of the centre of mass, m/s.
    pub velocity_m_s: [f64; 3],
    /// Angular velocity (world frame), rad/s.
    pub angular_velocity_rad_s: [f64; 3],
}

/// Labelled records written as a JSON object in their order.
struct Named<'a, T>(&'a [(String, T)]);

impl<T: Serialize> Serialize for Named<'_, T> {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> std::result::Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (k, v) in self.0 {
            map.serialize_entry(k, v)?;
        }
        map.end()
    }
}

#[derive(Serialize)]
struct BodiesLine<'a> {
    step: u64,
    time_s: f64,
    bodies: Named<'a, BodyState>,
}

#[derive(Serialize)]
struct JointsLine<'a> {
    step: u64,
    time_s: f64,
    joints: Named<'a, JointState>,
}

/// `labels` made unique: the second and later copies of a label get `#2`, `#3`, ...
fn unique_labels<'a>(labels: impl Iterator<Item = &'a str>) -> Vec<String> {
    let mut seen: std::collections::HashMap<&str, usize> = std::collections::HashMap::new();
    labels
        .map(|l| {
            let n = seen.entry(l).or_insert(0);
            *n += 1;
            if *n == 1 {
                l.to_string()
            } else {
                format!("{l}#{n}")
            }
        })
        .collect()
}

impl Simulation {
    /// Every rigid body's label with its current pose and velocity.
    pub fn body_states(&self) -> Vec<(String, BodyState)> {
        let b = &self.bodies;
        self.rigid_bodies
            .labels
            .iter()
            .enumerate()
            .map(|(i, label)| {
                let q = b.orientation[i].quaternion();
                (
                    label.clone(),
                    BodyState {
                        position_m: b.position[i].into(),
                        orientation_wxyz: [q.w, q.i, q.j, q.k],
                        velocity_m_s: b.velocity[i].into(),
                        angular_velocity_rad_s: b.angular_velocity[i].into(),
                    },
                )
            })
            .collect()
    }

    /// Every joint of [`RigidBodies::named_joints`](crate::rigidbodies::RigidBodies::named_joints)
    /// with its state at the last accepted step (labels made unique as in the joint log).
    pub fn joint_states(&self) -> Vec<(String, JointState)> {
        let joints = &self.rigid_bodies.named_joints;
        unique_labels(joints.iter().map(|j| j.label.as_str()))
            .into_iter()
            .zip(joints)
            .map(|(label, j)| (label, self.joint_state(j)))
            .collect()
    }

    /// Largest violation of any enabled hard joint constraint at the last accepted step: (m, rad).
    pub fn max_joint_violations(&self) -> (f64, f64) {
        let mut worst = (0.0f64, 0.0f64);
        for el in &self.rigid_bodies.joints.potential.elements {
            if el.enabled && el.primitive.is_hard() {
                if el.primitive.is_angular() {
                    worst.1 = worst.1.max(el.readout.violation);
                } else {
                    worst.0 = worst.0.max(el.readout.violation);
                }
            }
        }
        worst
    }

    /// Open the body and joint logs the settings ask for (the simulation has bodies or joints).
    /// Returns the files opened.
    pub(crate) fn open_rigid_logs(&mut self, keep_lines: Option<u64>) -> Result<Vec<PathBuf>> {
        let o = &self.settings.output;
        let mut files = Vec::new();
        if o.step_log && o.bodies_log && !self.bodies.is_empty() {
            let (log, path) = create_log(&o.directory, format!("{}.bodies.jsonl", self.settings.name), keep_lines)?;
            self.output.bodies_log = Some(log);
            files.push(path);
        }
        if o.step_log && o.joints_log && !self.rigid_bodies.named_joints.is_empty() {
            let (log, path) = create_log(&o.directory, format!("{}.joints.jsonl", self.settings.name), keep_lines)?;
            self.output.joints_log = Some(log);
            files.push(path);
        }
        if o.step_log {
            for probe in &mut self.output.probes {
                let file = format!("{}.{}.jsonl", self.settings.name, probe.name);
                let (log, path) = create_log(&o.directory, file, keep_lines)?;
                probe.log = Some(log);
                files.push(path);
            }
        }
        Ok(files)
    }

    /// Record a quantity of the simulation every accepted step: `record(sim)` is written as one
    /// JSON line `{"step": …, "time_s": …, "<name>": record}` to `<scene>.<name>.jsonl` in the
    /// output directory (when step logs are on), continued like the body and joint logs when a
    /// run resumes from a checkpoint. Use it for what a scene measures (a robot's pose, a
    /// towel's centroid, a grasp's slip).
    pub fn add_probe<T: Serialize>(
        &mut self,
        name: &str,
        record: impl Fn(&Simulation) -> T + Send + 'static,
    ) -> Result<()> {
        if name.is_empty() || name.contains(['/', '\\']) || self.output.probes.iter().any(|p| p.name == name) {
            return Err(crate::error::StarkError::InvalidInput(format!(
                "probe name '{name}' must be non-empty, without path separators, and unique"
            )));
        }
        self.output.probes.push(Probe {
            name: name.to_string(),
            record: Box::new(move |sim| serde_json::to_value(record(sim)).expect("serialisable probe record")),
            log: None,
            last: None,
        });
        Ok(())
    }

    /// The record probe `name` wrote after the last step (None before the first step, when step
    /// logs are off, or if there is no such probe).
    pub fn last_probe_record(&self, name: &str) -> Option<&serde_json::Value> {
        self.output.probes.iter().find(|p| p.name == name)?.last.as_ref()
    }

    /// Append the current body and joint states to their logs (those that are open).
    pub(crate) fn write_rigid_logs(&mut self, step: u64) -> Result<()> {
        let time_s = self.time();
        if self.output.bodies_log.is_some() {
            let bodies = self.body_states();
            let line = BodiesLine {
                step,
                time_s,
                bodies: Named(&bodies),
            };
            write_line(&mut self.output.bodies_log, "body log", &line)?;
        }
        if self.output.joints_log.is_some() {
            let joints = self.joint_states();
            let line = JointsLine {
                step,
                time_s,
                joints: Named(&joints),
            };
            write_line(&mut self.output.joints_log, "joint log", &line)?;
        }
        let mut probes = std::mem::take(&mut self.output.probes);
        let mut result = Ok(());
        for p in probes.iter_mut().filter(|p| p.log.is_some()) {
            let mut line = serde_json::Map::new();
            line.insert("step".into(), step.into());
            line.insert("time_s".into(), time_s.into());
            line.insert(p.name.clone(), (p.record)(self));
            result = write_line(&mut p.log, "probe log", &line);
            p.last = line.remove(&p.name);
            // Flushed every step: scenes read their probes while running (outcomes, plots).
            if let (Ok(()), Some(log)) = (&result, &mut p.log) {
                result = log.flush().map_err(|e| io_err(Path::new("probe log"), e));
            }
            if result.is_err() {
                break;
            }
        }
        self.output.probes = probes;
        result
    }
}

/// A quantity recorded every step ([`Simulation::add_probe`]).
pub(crate) struct Probe {
    name: String,
    #[allow(clippy::type_complexity)]
    record: Box<dyn Fn(&Simulation) -> serde_json::Value + Send>,
    log: Option<std::io::BufWriter<std::fs::File>>,
    /// The record of the last step written.
    last: Option<serde_json::Value>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::vtk::read_vtk;
    use crate::presets::meshes;
    use crate::rigidbodies::joints::JointParams;
    use crate::rigidbodies::MassProperties;
    use crate::Settings;
    use nalgebra::UnitQuaternion;

    /// A box on a hinge to the world and a ball hanging from it on two ball joints with the same
    /// label, written to `dir`.
    fn pendulum(dir: &Path, configure: impl FnOnce(&mut Settings)) -> Simulation {
        let mut settings = Settings::default();
        settings.name = "pendulum".into();
        settings.output.directory = dir.to_path_buf();
        settings.threads = 1;
        configure(&mut settings);
        let mut sim = Simulation::new(settings).unwrap();
        let size = Vector3::new(0.4, 0.05, 0.05);
        let q = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), 0.3);
        let arm = sim
            .add_rigid_body_with(
                "arm",
                &MassProperties::cuboid(1.0, size),
                q * Vector3::new(0.2, 0.0, 0.0),
                q,
            )
            .unwrap();
        let m = meshes::box_mesh(size);
        sim.add_rigid_output_mesh(arm, &m.vertices, &m.elements).unwrap();
        let ball = sim
            .add_rigid_body_with(
                "ball",
                &MassProperties::sphere(0.5, 0.05),
                q * Vector3::new(0.4, 0.0, -0.1),
                UnitQuaternion::identity(),
            )
            .unwrap();
        let s = meshes::sphere_mesh(0.05, 1);
        sim.add_rigid_collision_mesh(ball, &s.vertices, &s.elements, Some(0.001))
            .unwrap();
        let p = JointParams::default();
        sim.add_hinge_joint("hinge", None, arm, Vector3::zeros(), Vector3::y(), p)
            .unwrap();
        let end = q * Vector3::new(0.4, 0.0, 0.0);
        sim.add_ball_joint("hook", Some(arm), ball, end, p).unwrap();
        sim.add_ball_joint("hook", Some(arm), ball, end, p).unwrap();
        sim
    }

    fn lines(path: &Path) -> Vec<serde_json::Value> {
        std::fs::read_to_string(path)
            .unwrap()
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect()
    }

    fn vec3(v: &serde_json::Value) -> Vector3<f64> {
        let a: Vec<f64> = v.as_array().unwrap().iter().map(|c| c.as_f64().unwrap()).collect();
        Vector3::new(a[0], a[1], a[2])
    }

    #[test]
    fn probes_are_logged_every_step_and_continue_on_resume() {
        let dir = tempfile::tempdir().unwrap();
        let ball_height = |sim: &Simulation| sim.body_states()[1].1.position_m[2];
        let mut sim = pendulum(dir.path(), |_| {});
        sim.add_probe("ball_z", move |sim| ball_height(sim)).unwrap();
        let bad = sim.add_probe("ball_z", |_| 0.0).unwrap_err().to_string();
        assert!(bad.contains("unique"), "{bad}");
        assert!(sim.add_probe("a/b", |_| 0.0).is_err());
        sim.run(2.0 / 30.0).unwrap();
        let ckpt = dir.path().join("p.ckpt");
        sim.save_checkpoint(&ckpt).unwrap();
        sim.run(2.0 / 30.0).unwrap();
        let log = dir.path().join("pendulum.ball_z.jsonl");
        let full = lines(&log);
        assert_eq!(full.len(), 4);
        assert_eq!(full[3]["step"], 3);
        assert_eq!(full[3]["ball_z"].as_f64().unwrap(), ball_height(&sim));

        // A resumed run cuts the log back to the checkpoint and continues it identically.
        let mut resumed = pendulum(dir.path(), |_| {});
        resumed.add_probe("ball_z", move |sim| ball_height(sim)).unwrap();
        resumed.restore_checkpoint(&ckpt).unwrap();
        resumed.run(2.0 / 30.0).unwrap();
        assert_eq!(lines(&log), full);
    }

    #[test]
    fn bodies_and_joints_are_logged_every_step() {
        let dir = tempfile::tempdir().unwrap();
        let mut sim = pendulum(dir.path(), |_| {});
        let summary = sim.run(3.0 / 30.0).unwrap();
        assert_eq!(summary.steps, 3);
        assert_eq!((summary.rigid_bodies, summary.joints), (2, 3));
        assert!(summary.max_joint_violation_m > 0.0 && summary.max_joint_violation_m < 1e-3);
        let bodies = lines(&dir.path().join("pendulum.bodies.jsonl"));
        let joints = lines(&dir.path().join("pendulum.joints.jsonl"));
        assert_eq!((bodies.len(), joints.len()), (3, 3));
        let last = &bodies[2];
        assert_eq!(last["step"], 2);
        assert_eq!(last["time_s"].as_f64().unwrap(), sim.time());
        let names: Vec<_> = last["bodies"].as_object().unwrap().keys().cloned().collect();
        assert_eq!(names, ["arm", "ball"]);
        for (name, state) in sim.body_states() {
            let logged = &last["bodies"][&name];
            let p = vec3(&logged["position_m"]);
            assert!((p - Vector3::from(state.position_m)).norm() < 1e-15, "{name}");
            let w = vec3(&logged["angular_velocity_rad_s"]);
            assert!(
                (w - Vector3::from(state.angular_velocity_rad_s)).norm() < 1e-12,
                "{name}"
            );
            assert_eq!(logged["orientation_wxyz"].as_array().unwrap().len(), 4);
        }
        assert!(
            vec3(&last["bodies"]["ball"]["velocity_m_s"]).norm() > 0.01,
            "nothing moved"
        );
        // Joints by label, a repeated label numbered; the hinge's angle and rate are logged.
        let last = &joints[2]["joints"];
        let names: Vec<_> = last.as_object().unwrap().keys().cloned().collect();
        assert_eq!(names, ["hinge", "hook", "hook#2"]);
        let states = sim.joint_states();
        let hinge = &states[0].1;
        assert_eq!(last["hinge"]["coordinate"].as_f64().unwrap(), hinge.coordinate.unwrap());
        assert!(hinge.coordinate.unwrap().abs() > 1e-4);
        assert!(last["hook"]["coordinate"].is_null());
        let f = vec3(&last["hook"]["force_on_b_n"]);
        assert!(f.norm() > 1e-3, "{f}");
        assert!(
            (f - Vector3::from(states[1].1.force_on_b_n)).norm() <= 1e-12 * f.norm(),
            "{f}"
        );
    }

    /// A step writes at most one frame: frame times it passed over (a step longer than the
    /// frame interval, or frames switched on after steps without, as when a run resumes with
    /// frames from a checkpoint written without) are skipped, not written as copies of its state.
    #[test]
    fn a_step_writes_at_most_one_frame() {
        let dir = tempfile::tempdir().unwrap();
        let mut sim = pendulum(dir.path(), |s| {
            s.output.fps = 60.0;
            s.output.frames = false;
        });
        for _ in 0..10 {
            sim.step().unwrap();
        }
        assert_eq!(sim.output.frames_written, 0);
        sim.settings.output.frames = true;
        sim.step().unwrap();
        assert_eq!(sim.output.frames_written, 1, "one frame, not one per missed frame time");
        // dt = 1/30 s at 60 frames per second: one frame per step, the next due after it.
        sim.step().unwrap();
        assert_eq!(sim.output.frames_written, 2);
        assert!(sim.output.next_frame_time > sim.time());
    }

    #[test]
    fn rigid_meshes_are_in_the_frames_at_the_body_pose() {
        let dir = tempfile::tempdir().unwrap();
        // The legacy VTK frames (read back with the crate's reader); VTU frames hold the same
        // points.
        let mut sim = pendulum(dir.path(), |s| {
            s.output.fps = 30.0;
            s.output.frame_format = crate::solver::FrameFormat::LegacyVtk;
        });
        for _ in 0..3 {
            sim.step().unwrap();
        }
        assert_eq!(sim.output.frames_written, 4);
        for (label, body) in [("arm", 0u32), ("ball", 1)] {
            let mesh = sim.output.meshes.iter().find(|m| m.label == label).unwrap();
            let frame = read_vtk(dir.path().join(format!("pendulum_{label}_00003.vtk"))).unwrap();
            let x = sim.positions(mesh.set);
            assert_eq!(frame.points.len(), x.len());
            let h = crate::rigidbodies::RigidBodyHandle { index: body };
            for (i, p) in frame.points.iter().enumerate() {
                assert_eq!(*p, x[i]);
                let on_body = sim.body_point_to_world(h, &sim.nodes.rest[mesh.set.global(i)]);
                assert!((p - on_body).norm() < 1e-12, "{label} vertex {i}: {p} vs {on_body}");
            }
            // The frame before moved with the body too.
            let before = read_vtk(dir.path().join(format!("pendulum_{label}_00000.vtk"))).unwrap();
            assert!(
                (before.points[0] - frame.points[0]).norm() > 1e-4,
                "{label} did not move"
            );
        }
    }

    #[test]
    fn rigid_logs_follow_the_settings() {
        let dir = tempfile::tempdir().unwrap();
        let mut sim = pendulum(dir.path(), |s| {
            s.output.joints_log = false;
            s.output.frames = false;
        });
        sim.step().unwrap();
        sim.output.flush().unwrap();
        assert!(dir.path().join("pendulum.bodies.jsonl").exists());
        assert!(!dir.path().join("pendulum.joints.jsonl").exists());
        let quiet = tempfile::tempdir().unwrap();
        let mut sim = pendulum(quiet.path(), |s| {
            s.output.step_log = false;
            s.output.frames = false;
        });
        sim.step().unwrap();
        assert_eq!(std::fs::read_dir(quiet.path()).unwrap().count(), 0);
        assert_eq!(
            unique_labels(["a", "b", "a", "a"].into_iter()),
            ["a", "b", "a#2", "a#3"]
        );
    }
}
