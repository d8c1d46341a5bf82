//! Time stepping and output: `step`, `run` (its callback and progress bar), checkpoints, spawns
//! and time events (and the garbage-collector hooks of the callables they keep), frames.

use super::{report_out, Simulation};
use crate::convert::stark_err;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::{PyTraverseError, PyVisit};

#[pymethods]
impl Simulation {
    /// Advance by one accepted time step; returns the step report as a dict (dt, Newton
    /// iterations, residual, criterion, contact statistics ...).
    fn step<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let report = Self::drive(slf, |sim| sim.step())?;
        report_out(slf.py(), &report)
    }

    /// The same as `step()` (the original's name).
    fn run_one_step<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        Self::step(slf)
    }

    /// Simulate `duration` more seconds, calling `callback(sim)` before every step if given.
    /// The GIL is released while solving; Ctrl-C stops the run between steps. With
    /// `progress=True`, a progress bar (simulated time, steps, wall time) is drawn on
    /// `sys.stderr`. The last step is shortened to land on the end time. Returns the run
    /// summary as a dict.
    #[pyo3(signature = (duration, callback=None, progress=false))]
    fn run<'py>(
        slf: &Bound<'py, Self>,
        duration: f64,
        callback: Option<Py<PyAny>>,
        progress: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        if !(duration.is_finite() && duration >= 0.0) {
            return Err(stark_err(format!(
                "duration must be finite and non-negative, got {duration}"
            )));
        }
        if let Some(cb) = &callback {
            if !cb.bind(slf.py()).is_callable() {
                return Err(PyTypeError::new_err("callback must be callable"));
            }
        }
        let summary = Self::drive(slf, move |sim| {
            let mut bar = ProgressLine::new(sim.time(), duration);
            let result = sim.run_with(duration, |s| {
                let (t, steps) = (s.time(), s.summary().steps);
                Self::serve(s, |py, obj| {
                    py.check_signals()?;
                    if progress {
                        bar.draw(py, t, steps, false)?;
                    }
                    if let Some(cb) = &callback {
                        cb.call1(py, (obj,))?;
                    }
                    Ok(())
                })
            });
            if progress {
                let (t, steps) = (sim.time(), sim.summary().steps);
                // The final line is drawn whatever happened; a failure to draw is not the run's.
                let _ = Python::attach(|py| bar.draw(py, t, steps, true));
            }
            result
        })?;
        report_out(slf.py(), &summary)
    }

    /// Write a checkpoint of the whole state the next step depends on to `path`; a simulation
    /// rebuilt the same way (with its time events added again) continues from it bit for bit
    /// after `restore_checkpoint(path)`.
    fn save_checkpoint(&self, path: std::path::PathBuf) -> PyResult<()> {
        self.with(|s| s.save_checkpoint(&path))
    }

    /// Restore a checkpoint into this simulation, freshly built from the same scene (scene
    /// files rebuild their time events; closures added with `add_time_event` must be added
    /// again first) and not stepped yet. Another scene, a truncated file or another format
    /// version raise `StarkError` saying which.
    fn restore_checkpoint(slf: &Bound<'_, Self>, path: std::path::PathBuf) -> PyResult<()> {
        // Served like a step: the restore fires the spawns due by the checkpoint's time.
        Self::drive(slf, |s| s.restore_checkpoint(&path))
    }

    /// Add objects during the run: `action(sim)` runs once, when the simulated time first
    /// reaches `time_s` (before the first step when `time_s <= 0`, else right after the step that
    /// reaches it). It adds rigid bodies or deformables, their friction and initial state, as
    /// when building. What it adds must not intersect anything (the step raises `StarkError`
    /// naming the spawn). `restore_checkpoint` fires the spawns due by the checkpoint's time
    /// before restoring, so a resumed run must add the same spawns first, and the action must add
    /// the same objects whatever the state.
    fn add_spawn(&self, time_s: f64, label: &str, action: Py<PyAny>) -> PyResult<()> {
        Python::attach(|py| {
            if !action.bind(py).is_callable() {
                return Err(PyTypeError::new_err("the spawn action must be callable"));
            }
            Ok(())
        })?;
        let index = {
            let mut events = self.events.lock().unwrap_or_else(|e| e.into_inner());
            events.push(Some(action));
            events.len() - 1
        };
        self.with(|s| {
            s.add_spawn(time_s, label, move |sim| {
                Self::serve(sim, |py, obj| {
                    let action = obj.get().events.lock().unwrap_or_else(|e| e.into_inner())[index]
                        .as_ref()
                        .map(|a| a.clone_ref(py));
                    match action {
                        Some(a) => a.call1(py, (obj,)).map(|_| ()),
                        None => Err(stark_err("the spawn's action was cleared")),
                    }
                })
            })
        })
    }

    /// Spawns added with `add_spawn`, as `(time_s, label, fired)`.
    fn spawns(&self) -> PyResult<Vec<(f64, String, bool)>> {
        self.with(|s| Ok(s.spawns().into_iter().map(|(t, l, f)| (t, l.to_string(), f)).collect()))
    }

    /// Run `action(sim, t)` before every step whose end time `t` lies in `[t0, t1)`: move
    /// prescribed targets, change parameters or gravity. An exception stops the run.
    fn add_time_event(&self, t0: f64, t1: f64, action: Py<PyAny>) -> PyResult<()> {
        Python::attach(|py| {
            if !action.bind(py).is_callable() {
                return Err(PyTypeError::new_err("the time event action must be callable"));
            }
            Ok(())
        })?;
        if t0.is_nan() || t1.is_nan() {
            return Err(stark_err("time event bounds must not be NaN"));
        }
        let index = {
            let mut events = self.events.lock().unwrap_or_else(|e| e.into_inner());
            events.push(Some(action));
            events.len() - 1
        };
        self.get(|s| {
            s.add_time_event(t0, t1, move |sim, t| {
                Self::serve(sim, |py, obj| {
                    let action = obj.get().events.lock().unwrap_or_else(|e| e.into_inner())[index]
                        .as_ref()
                        .map(|a| a.clone_ref(py));
                    match action {
                        Some(a) => a.call1(py, (obj, t)).map(|_| ()),
                        None => Err(stark_err("the time event's action was cleared")),
                    }
                })
            })
        })
    }

    fn __traverse__(&self, visit: PyVisit<'_>) -> Result<(), PyTraverseError> {
        if let Ok(events) = self.events.try_lock() {
            for e in events.iter().flatten() {
                visit.call(e)?;
            }
        }
        Ok(())
    }

    fn __clear__(&self) {
        if let Ok(mut events) = self.events.try_lock() {
            for e in events.iter_mut() {
                *e = None;
            }
        }
    }

    /// Write one frame of every output mesh now (VTU, or legacy VTK if
    /// `settings.output.frame_format` says so); returns the file paths.
    fn write_frame(&self) -> PyResult<Vec<String>> {
        let files = self.with(|s| s.write_frame())?;
        Ok(files.iter().map(|p| p.display().to_string()).collect())
    }
}

/// The progress bar of `run(..., progress=True)`, written to `sys.stderr` (so notebooks and
/// pytest's capture see it), redrawn at most five times a second.
struct ProgressLine {
    start_s: f64,
    duration_s: f64,
    wall: std::time::Instant,
    last_draw: Option<std::time::Instant>,
}

impl ProgressLine {
    fn new(start_s: f64, duration_s: f64) -> Self {
        ProgressLine {
            start_s,
            duration_s,
            wall: std::time::Instant::now(),
            last_draw: None,
        }
    }

    fn draw(&mut self, py: Python<'_>, time_s: f64, steps: u64, last: bool) -> PyResult<()> {
        if !last && self.last_draw.is_some_and(|d| d.elapsed().as_secs_f64() < 0.2) {
            return Ok(());
        }
        self.last_draw = Some(std::time::Instant::now());
        const WIDTH: usize = 30;
        let done = if self.duration_s > 0.0 {
            ((time_s - self.start_s) / self.duration_s).clamp(0.0, 1.0)
        } else {
            1.0
        };
        let filled = (done * WIDTH as f64).round() as usize;
        let line = format!(
            "\r[{}{}] {:3.0}%  {:.3}/{:.3} s simulated  step {}  {:.1} s{}",
            "#".repeat(filled),
            "-".repeat(WIDTH - filled),
            100.0 * done,
            time_s - self.start_s,
            self.duration_s,
            steps,
            self.wall.elapsed().as_secs_f64(),
            if last { "\n" } else { "" }
        );
        let stderr = py.import("sys")?.getattr("stderr")?;
        stderr.call_method1("write", (line,))?;
        stderr.call_method0("flush")?;
        Ok(())
    }
}
