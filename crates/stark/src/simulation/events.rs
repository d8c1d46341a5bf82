//! Scripted time events and spawns: actions run before the steps they are due at.

use super::*;

/// A scripted action run before every step whose end time lies in `[start_s, end_s)`.
pub(super) type EventAction = Box<dyn FnMut(&mut Simulation, f64) -> Result<()> + Send>;

pub(super) struct TimeEvent {
    start_s: f64,
    end_s: f64,
    action: EventAction,
}

/// What a spawn does once: add objects (rigid bodies, deformables) and their interactions.
pub(super) type SpawnAction = Box<dyn FnOnce(&mut Simulation) -> Result<()> + Send>;

/// Objects added when the simulated time reaches `time_s` ([`Simulation::add_spawn`]).
pub(super) struct Spawn {
    pub(super) time_s: f64,
    pub(super) label: String,
    /// `None` once fired.
    action: Option<SpawnAction>,
}

/// A spawn is due when the simulated time is within this of its time (repeated additions of dt
/// round), s.
pub(super) const SPAWN_TIME_TOLERANCE_S: f64 = 1e-9;

impl Simulation {
    /// Run `action(sim, t)` before every step whose end time `t` lies in `[start_s, end_s)`.
    /// Use it to move prescribed targets, ramp parameters or change gravity; `t` is the time the
    /// step is solved for, so targets set for `t` are met at the end of that step.
    pub fn add_time_event(
        &mut self,
        start_s: f64,
        end_s: f64,
        action: impl FnMut(&mut Simulation, f64) -> Result<()> + Send + 'static,
    ) {
        self.events.push(TimeEvent {
            start_s,
            end_s,
            action: Box::new(action),
        });
    }

    /// Add objects during the run: `action(sim)` runs once, when the simulated time first
    /// reaches `time_s` (before the first step when `time_s <= 0`, else right after the step
    /// that reaches it, so they are in that step's frame and logs; spawns due together fire in
    /// the order of their times, then in the order added). Use it to pour balls into a
    /// cup or drop parts on a conveyor: the action adds rigid bodies, deformables, contact
    /// settings and friction as when building a scene, and sets their initial state.
    ///
    /// What it adds must not intersect anything (checked; the run stops with an error naming
    /// the spawn). Checkpoints taken after a spawn restore into a simulation built from the same
    /// scene with the same spawns added: [`Simulation::restore_checkpoint`] fires the spawns due
    /// by the checkpoint's time first, so the action must add the same objects whatever the
    /// state (their state is then restored).
    pub fn add_spawn(
        &mut self,
        time_s: f64,
        label: &str,
        action: impl FnOnce(&mut Simulation) -> Result<()> + Send + 'static,
    ) -> Result<()> {
        if !time_s.is_finite() {
            return Err(StarkError::InvalidInput(format!(
                "spawn '{label}': time_s = {time_s} must be finite"
            )));
        }
        if self.started && time_s < self.time - SPAWN_TIME_TOLERANCE_S {
            return Err(StarkError::InvalidInput(format!(
                "spawn '{label}' at t = {time_s} s is in the past (the simulation is at t = {} s)",
                self.time
            )));
        }
        self.spawns.push(Spawn {
            time_s,
            label: label.to_string(),
            action: Some(Box::new(action)),
        });
        Ok(())
    }

    /// Spawns added with [`Simulation::add_spawn`]: `(time_s, label, fired)`.
    pub fn spawns(&self) -> Vec<(f64, &str, bool)> {
        self.spawns
            .iter()
            .map(|s| (s.time_s, s.label.as_str(), s.action.is_none()))
            .collect()
    }

    /// Fire every spawn due by time `t`, earliest first. `check` tests the new objects for
    /// intersections (off when replaying spawns into a simulation about to be restored).
    pub(super) fn fire_spawns(&mut self, t: f64, check: bool) -> Result<()> {
        let due = |s: &Spawn| s.action.is_some() && t >= s.time_s - SPAWN_TIME_TOLERANCE_S;
        if !self.spawns.iter().any(due) {
            return Ok(());
        }
        // By time, then in the order added: a replay fires them as the run did.
        let mut order: Vec<usize> = (0..self.spawns.len()).collect();
        order.sort_by(|&a, &b| self.spawns[a].time_s.total_cmp(&self.spawns[b].time_s).then(a.cmp(&b)));
        for k in order {
            if !due(&self.spawns[k]) {
                continue;
            }
            let action = self.spawns[k].action.take().expect("due spawns have their action");
            let (time_s, label) = (self.spawns[k].time_s, self.spawns[k].label.clone());
            let meshes_before = self.output.meshes.len();
            action(self).map_err(|e| StarkError::InvalidInput(format!("spawn '{label}' at t = {time_s} s: {e}")))?;
            // The frames list its meshes from the spawn's time on.
            for m in &mut self.output.meshes[meshes_before..] {
                m.first_time_s = time_s;
            }
            if check {
                let crossings = self.contact.find_intersections(&self.nodes.x);
                if !crossings.is_empty() {
                    return Err(StarkError::InvalidInput(format!(
                        "spawn '{label}' at t = {time_s} s: the objects it added intersect others ({} edge–triangle \
                         pairs), e.g. {}",
                        crossings.len(),
                        crossings[0]
                    )));
                }
            }
        }
        Ok(())
    }

    pub(super) fn run_events(&mut self, t_end: f64) -> Result<()> {
        let mut events = std::mem::take(&mut self.events);
        let mut result = Ok(());
        for e in events.iter_mut() {
            if t_end >= e.start_s && t_end < e.end_s {
                result = (e.action)(self, t_end);
                if result.is_err() {
                    break;
                }
            }
        }
        // Events added by events are kept.
        events.append(&mut self.events);
        self.events = events;
        result
    }
}
