//! Running, frames and fields, the scene's origin and hash, checkpoints.

use super::*;

impl Simulation {
    pub(super) fn write_frame_now(&mut self) -> Result<()> {
        self.write_frame().map(|_| ())
    }

    /// Write one frame of the current state now, in the settings' format (with VTU, the
    /// `.pvd` lists it at the current time); returns the files written.
    pub fn write_frame(&mut self) -> Result<Vec<std::path::PathBuf>> {
        let dir = self.settings.output.directory.clone();
        let name = self.settings.name.clone();
        match self.settings.output.frame_format {
            crate::solver::FrameFormat::LegacyVtk => {
                let files = self.output.write_frame(&dir, &name, &self.nodes)?;
                self.output.frame_times.push(self.time);
                Ok(files)
            }
            crate::solver::FrameFormat::Vtu => {
                let fields = self.node_fields();
                let x = &self.nodes.x;
                let cells: Vec<_> = self
                    .output
                    .meshes
                    .iter()
                    .map(|m| match &m.cells {
                        crate::io::output::OutputCells::Tets(_) => {
                            self.deformables.tets.potential.cell_fields(&m.label, x)
                        }
                        crate::io::output::OutputCells::Triangles(_) => {
                            self.deformables.triangles.potential.cell_fields(&m.label, x)
                        }
                        _ => None,
                    })
                    .collect();
                self.output
                    .write_frame_vtu(&dir, &name, &self.nodes, self.time, &fields, &cells)
            }
        }
    }

    /// The per-node output fields of the current state: contact force, prescribed, attached.
    pub fn node_fields(&mut self) -> crate::io::fields::NodeFields {
        let n = self.nodes.len();
        let contact_force_n = if self.contact.objects().is_empty() {
            vec![Vector3::zeros(); n]
        } else {
            self.contact.barrier_forces(&self.nodes.x)
        };
        let mut prescribed = vec![false; n];
        for &i in self.deformables.prescribed.potential.prescribed_nodes() {
            prescribed[i as usize] = true;
        }
        let mut attached = vec![false; n];
        let a = &self.deformables.attachments;
        a.point_point
            .potential
            .attached_nodes()
            .chain(a.point_edge.potential.attached_nodes())
            .chain(a.point_triangle.potential.attached_nodes())
            .chain(self.rigid_bodies.attachments.potential.attached_nodes())
            .for_each(|i| attached[i as usize] = true);
        crate::io::fields::NodeFields {
            contact_force_n,
            prescribed,
            attached,
        }
    }

    /// Simulate `duration_s` more seconds.
    pub fn run(&mut self, duration_s: f64) -> Result<RunSummary> {
        self.run_with(duration_s, |_| Ok(()))
    }

    /// Simulate `duration_s` more seconds, calling `callback` before every step.
    pub fn run_with(
        &mut self,
        duration_s: f64,
        mut callback: impl FnMut(&mut Simulation) -> Result<()>,
    ) -> Result<RunSummary> {
        let end = self.time + duration_s;
        self.step_end_limit = Some(end);
        let mut result = Ok(());
        // Stop when less than a thousandth of a step remains (rounding of repeated additions).
        while self.time < end - 1e-3 * self.dt.min(self.settings.time_step_s) {
            result = callback(self).and_then(|()| self.step().map(|_| ()));
            if result.is_err() {
                break;
            }
        }
        self.step_end_limit = None;
        // The logs are flushed also when a step or the callback failed (or was interrupted),
        // so that they hold every accepted step.
        let flushed = self.output.flush();
        result?;
        flushed?;
        Ok(self.summary.clone())
    }

    /// Where the scene came from (set by the scene loaders; [`SceneOrigin::Program`](crate::io::SceneOrigin::Program)
    /// for simulations built in code), recorded in checkpoints.
    pub fn scene_origin(&self) -> &crate::io::SceneOrigin {
        &self.origin
    }

    /// Record where the scene came from (the CLI does, for `stark resume`).
    pub fn set_scene_origin(&mut self, origin: crate::io::SceneOrigin) {
        self.origin = origin;
    }

    /// A hash of the scene's structure: nodes and their rest positions, bodies and their mass
    /// properties, every term's name and element count (contact's active pairs excluded), the
    /// contact objects and the number of time events. A checkpoint restores only into a
    /// simulation of the same hash.
    pub fn scene_hash(&mut self) -> u64 {
        let mut h = crate::io::checkpoint::Fnv::default();
        h.str("stark scene");
        h.u64(self.nodes.len() as u64);
        for (r, b) in self.nodes.rest.iter().zip(&self.nodes.body) {
            r.iter().for_each(|&c| h.f64(c));
            h.u64(u64::from(*b));
        }
        for (label, set) in &self.deformables.sets {
            h.str(label);
            h.u64(u64::from(set.len));
        }
        h.u64(self.bodies.len() as u64);
        for b in 0..self.bodies.len() {
            h.f64(self.bodies.mass[b]);
            self.bodies.inertia_local[b].iter().for_each(|&c| h.f64(c));
        }
        for label in &self.rigid_bodies.labels {
            h.str(label);
        }
        for o in self.contact.objects() {
            h.str(&o.label);
        }
        h.u64(self.events.len() as u64);
        if !self.spawns.is_empty() {
            h.str("spawns");
            for s in &self.spawns {
                h.f64(s.time_s);
                h.str(&s.label);
            }
        }
        for t in self.terms_mut() {
            h.str(t.name());
            // Contact's elements are its active pairs, which change from step to step; the rigid
            // inertia's are the bodies (hashed above; left out so that older checkpoints, whose
            // rigid inertia also held rigid nodes, still match).
            if t.name() != "contact" && t.name() != "rigid body inertia" {
                h.u64(t.num_elements() as u64);
            }
        }
        h.finish()
    }

    /// Write a checkpoint of the current state to `path` (see [`crate::io::checkpoint`]); a run
    /// continued from it with [`Simulation::restore_checkpoint`] repeats this one bit for bit.
    pub fn save_checkpoint(&mut self, path: impl AsRef<std::path::Path>) -> Result<()> {
        let path = path.as_ref();
        // The logs then hold every step the checkpoint counts, whatever happens to the process.
        self.output.flush()?;
        let terms = self
            .terms_mut()
            .into_iter()
            .map(|t| (t.name().to_string(), t.save_state()))
            .collect();
        let state = crate::io::checkpoint::SimulationState {
            nodes: self.nodes.clone(),
            bodies: self.bodies.clone(),
            settings: self.settings.clone(),
            time_s: self.time,
            dt_s: self.dt,
            guess_scale: self.guess_scale,
            summary: self.summary.clone(),
            frames_written: self.output.frames_written,
            next_frame_time_s: self.output.next_frame_time,
            frame_times_s: self.output.frame_times.clone(),
            terms,
            kept_preconditioner: self.newton.save_kept_preconditioner(),
        };
        let header = crate::io::checkpoint::header(
            self.scene_hash(),
            &self.settings.name,
            self.origin.clone(),
            &self.settings.output.directory,
            self.time,
            self.summary.steps,
        );
        crate::io::checkpoint::write(path, header, &state)
    }

    /// Restore a checkpoint written by [`Simulation::save_checkpoint`] into this simulation,
    /// which must be freshly built from the same scene (with its time events registered again)
    /// and not yet stepped. The settings come back as saved except `threads` and `output`, which
    /// stay this simulation's (so the caller chooses where the continued run writes); the logs
    /// there are cut back to the checkpoint's step and continued, and frames continue numbering.
    pub fn restore_checkpoint(&mut self, path: impl AsRef<std::path::Path>) -> Result<()> {
        let path = path.as_ref();
        let fail = |message: String| StarkError::Checkpoint {
            path: path.display().to_string(),
            message,
        };
        if self.started {
            return Err(fail(
                "a checkpoint restores only into a freshly built simulation that has not stepped yet".into(),
            ));
        }
        // The objects spawned by the checkpoint's time exist before its state is restored.
        if !self.spawns.is_empty() {
            let header = crate::io::checkpoint::read_header(path)?;
            self.fire_spawns(header.time_s, false)?;
        }
        let hash = self.scene_hash();
        let (_, state) = crate::io::checkpoint::read(path, hash, &self.settings.name)?;
        let mut terms = self.terms_mut();
        if terms.len() != state.terms.len() {
            return Err(fail(format!(
                "{} energy terms saved, {} in this simulation",
                state.terms.len(),
                terms.len()
            )));
        }
        for (t, (name, bytes)) in terms.iter_mut().zip(&state.terms) {
            if t.name() != name {
                return Err(fail(format!(
                    "term '{name}' saved where this simulation has '{}'",
                    t.name()
                )));
            }
            t.restore_state(bytes)
                .map_err(|e| fail(format!("term '{name}': {e}")))?;
        }
        drop(terms);
        self.newton
            .restore_kept_preconditioner(&state.kept_preconditioner)
            .map_err(fail)?;
        let keep_threads = self.settings.threads;
        let keep_output = self.settings.output.clone();
        self.settings = state.settings;
        self.settings.threads = keep_threads;
        self.settings.output = keep_output;
        self.nodes = state.nodes;
        self.bodies = state.bodies;
        self.time = state.time_s;
        self.dt = state.dt_s;
        self.guess_scale = state.guess_scale;
        self.summary = state.summary;
        self.output.frames_written = state.frames_written;
        self.output.next_frame_time = state.next_frame_time_s;
        self.output.frame_times = state.frame_times_s;
        self.resumed_at_step = Some(self.summary.steps);
        Ok(())
    }
}
