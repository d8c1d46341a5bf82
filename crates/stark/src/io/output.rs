//! Simulation output: VTK frames at a fixed rate and a per-step log as JSON lines.
//!
//! Frames are `<directory>/<name>_<label>_<frame>.vtk` (legacy VTK, binary; ParaView opens the
//! numbered series as one animation, meshio and Blender import them), one file per registered
//! mesh, with the node velocity (m/s) as point data. The step log `<directory>/<name>.steps.jsonl`
//! has one JSON object per accepted step.

use super::vtk::{VtkCells, VtkWriter};
use crate::deformables::NodeSetHandle;
use crate::error::{Result, StarkError};
use crate::state::NodeArrays;
use nalgebra::Vector3;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Cells of an output mesh, in indices local to its node set.
#[derive(Clone, Debug)]
pub enum OutputCells {
    /// Just the nodes.
    Points,
    /// Segments.
    Segments(Vec<[usize; 2]>),
    /// Triangles.
    Triangles(Vec<[usize; 3]>),
    /// Tetrahedra.
    Tets(Vec<[usize; 4]>),
}

/// A mesh written in every frame.
#[derive(Clone, Debug)]
pub struct OutputMesh {
    /// Label in the file name.
    pub label: String,
    /// Its nodes.
    pub set: NodeSetHandle,
    /// Its cells.
    pub cells: OutputCells,
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
    log: Option<std::io::BufWriter<std::fs::File>>,
    rigid_log: Option<std::io::BufWriter<std::fs::File>>,
    scratch_x: Vec<Vector3<f64>>,
    scratch_v: Vec<Vector3<f64>>,
}

fn io_err(path: &Path, source: std::io::Error) -> StarkError {
    StarkError::Output {
        path: path.display().to_string(),
        source,
    }
}

impl Output {
    /// Register a mesh for the frames.
    pub fn add_mesh(&mut self, label: &str, set: NodeSetHandle, cells: OutputCells) {
        self.meshes.push(OutputMesh {
            label: label.to_string(),
            set,
            cells,
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
            let path = directory.join(format!("{name}_{}_{:05}.vtk", mesh.label, self.frames_written));
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

    /// Start the step log (truncates an existing one).
    pub fn open_log(&mut self, directory: &Path, name: &str) -> Result<PathBuf> {
        std::fs::create_dir_all(directory).map_err(|e| io_err(directory, e))?;
        let path = directory.join(format!("{name}.steps.jsonl"));
        let file = std::fs::File::create(&path).map_err(|e| io_err(&path, e))?;
        self.log = Some(std::io::BufWriter::new(file));
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

    /// Start the rigid-body log `<name>.rigid.jsonl` (truncates an existing one).
    pub fn open_rigid_log(&mut self, directory: &Path, name: &str) -> Result<PathBuf> {
        std::fs::create_dir_all(directory).map_err(|e| io_err(directory, e))?;
        let path = directory.join(format!("{name}.rigid.jsonl"));
        let file = std::fs::File::create(&path).map_err(|e| io_err(&path, e))?;
        self.rigid_log = Some(std::io::BufWriter::new(file));
        Ok(path)
    }

    /// Append one record to the rigid-body log (if open).
    pub fn log_rigid<T: serde::Serialize>(&mut self, record: &T) -> Result<()> {
        if let Some(log) = &mut self.rigid_log {
            let line = serde_json::to_string(record).expect("serialisable record");
            writeln!(log, "{line}").map_err(|e| io_err(Path::new("rigid log"), e))?;
        }
        Ok(())
    }

    /// Flush the logs.
    pub fn flush(&mut self) -> Result<()> {
        if let Some(log) = &mut self.log {
            log.flush().map_err(|e| io_err(Path::new("step log"), e))?;
        }
        if let Some(log) = &mut self.rigid_log {
            log.flush().map_err(|e| io_err(Path::new("rigid log"), e))?;
        }
        Ok(())
    }
}
