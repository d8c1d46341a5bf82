//! Solver and simulation settings: plain data with documented defaults.
//!
//! A floor of its own between the models and the solver: `Settings` aggregates the model
//! settings (contact) and the solver settings, and the solver and simulation read them.

use crate::contact::ContactSettings;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// How the Newton system is solved.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, strum::VariantNames)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
pub enum LinearSolver {
    /// Block-Jacobi preconditioned conjugate gradients (cheapest per iteration; the iteration
    /// count grows with the mesh's resolution).
    Pcg,
    /// Conjugate gradients preconditioned by smoothed-aggregation algebraic multigrid (one
    /// V-cycle; the near-null space the rigid motions of the unknowns; a hierarchy's
    /// interpolation serves four steps, its levels recomputed for each step's Hessian):
    /// iteration counts nearly independent of resolution, for large meshes (a 256² cloth, 200k
    /// unknowns: 15 CG iterations per Newton iteration instead of 466, 2.6× faster; a 128² one,
    /// 50k unknowns: 1.2–2.3×; below ~50k unknowns block-Jacobi CG is faster).
    Amg,
    /// Sparse Cholesky (pays below about 25k DOFs, and in contact-dense scenes): a factorisation
    /// per Newton iteration (the symbolic analysis reused while the pattern is unchanged); once
    /// the residual fell a hundredfold in a step, CG preconditioned with the step's last factor,
    /// refactorising when CG needs more than 8 iterations.
    Cholesky,
}

/// When element Hessians are projected to positive semi-definite.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, strum::VariantNames)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
pub enum Projection {
    /// Every element, every iteration (robust, costs an eigen-decomposition per indefinite
    /// element).
    Always,
    /// Exact Hessians until CG meets negative curvature or the direction is not a descent
    /// direction; then projected ones for the rest of the step (like the original's progressive
    /// projection, which projects only where needed).
    OnDemand,
}

crate::params::documented_struct! {
    /// Newton solver settings.
    #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct NewtonSettings {
        /// A step converges when the force residual `‖∇ᵥE‖∞ / dt` falls below this, N (or N·m for
        /// rotational DOFs) (default: 1e-6, the paper's tolerance).
        pub residual_tolerance_n: f64,
        /// A step also converges when the Newton step `‖Δv‖∞` falls below this, m/s; 0 disables it
        /// (default: 0). The original Stark uses 1e-3 and its scenes rely on it.
        pub step_tolerance_m_s: f64,
        /// Newton iterations before the step counts as failed and dt is halved (default: 100).
        pub max_iterations: usize,
        /// Linear solver: `pcg` (block-Jacobi preconditioned CG), `amg` (CG preconditioned by
        /// algebraic multigrid) or `cholesky` (default: `pcg`).
        pub linear_solver: LinearSolver,
        /// Largest number of CG iterations per solve (default: 10000).
        pub cg_max_iterations: usize,
        /// Relative CG tolerance at the first Newton iteration; it tightens as the residual falls
        /// (forcing sequence `min(this, √(r/r₀))`) (default: 1e-2).
        pub cg_relative_tolerance: f64,
        /// Armijo sufficient-decrease constant (default: 1e-4).
        pub armijo: f64,
        /// Largest number of step halvings in the line search (default: 30).
        pub max_line_search_iterations: usize,
        /// When element Hessians are projected: `always` or `on_demand` (default: `on_demand`:
        /// after a linear solve found the exact Hessian indefinite, for the rest of the step or
        /// until the next switch to exact Hessians, see below).
        pub projection: Projection,
        /// Far from the solution, the contact barriers' positive semi-definite Hessian form
        /// (`contact.hessian`), and their exact Hessians once a step was taken in full
        /// (projection on demand starts over); back to the definite form after an exact step had
        /// to be cut below a quarter. Where the exact barrier Hessians make the total
        /// indefinite, their definite form until the residual fell tenfold (default: true). Off:
        /// exact Hessians throughout, the barriers' definite form and then projection on demand.
        /// (Named `majorizer_far_from_solution` before friction's Hessian became primal–dual;
        /// the old name is still read.)
        #[serde(alias = "majorizer_far_from_solution")]
        pub definite_far_from_solution: bool,
    }
}

impl Default for NewtonSettings {
    fn default() -> Self {
        NewtonSettings {
            residual_tolerance_n: 1e-6,
            step_tolerance_m_s: 0.0,
            max_iterations: 100,
            linear_solver: LinearSolver::Pcg,
            cg_max_iterations: 10_000,
            cg_relative_tolerance: 1e-2,
            armijo: 1e-4,
            max_line_search_iterations: 30,
            projection: Projection::OnDemand,
            definite_far_from_solution: true,
        }
    }
}

crate::params::documented_struct! {
    /// Frame and log output.
    #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct OutputSettings {
        /// Directory for frames and logs (default: "output").
        pub directory: PathBuf,
        /// Frames per simulated second; 0 disables frames (default: 30).
        pub fps: f64,
        /// Write frames (default: true).
        pub frames: bool,
        /// File format of the frames: `vtu` or `legacy_vtk` (default: `vtu`, with a `.pvd` series
        /// carrying the times).
        pub frame_format: FrameFormat,
        /// Write the per-step log `<name>.steps.jsonl` (default: true). Off, it also turns off the
        /// body and joint logs.
        pub step_log: bool,
        /// Write `<name>.bodies.jsonl`, every rigid body's pose and velocity after each step, when
        /// the simulation has rigid bodies (default: true).
        pub bodies_log: bool,
        /// Write `<name>.joints.jsonl`, every joint's state after each step, when the simulation has
        /// joints (default: true).
        pub joints_log: bool,
    }
}

/// File format of the output frames.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, strum::VariantNames)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
pub enum FrameFormat {
    /// VTK XML unstructured grids (`.vtu`, binary data) with point and cell fields, and a
    /// `<name>.pvd` collection per run that gives ParaView each frame's simulated time.
    #[default]
    Vtu,
    /// Legacy VTK (`.vtk`, binary) with the node velocity only.
    LegacyVtk,
}

impl Default for OutputSettings {
    fn default() -> Self {
        OutputSettings {
            directory: PathBuf::from("output"),
            fps: 30.0,
            frames: true,
            frame_format: FrameFormat::Vtu,
            step_log: true,
            bodies_log: true,
            joints_log: true,
        }
    }
}

crate::params::documented_struct! {
    /// Everything that configures a simulation run.
    #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct Settings {
        /// Name, used for output files (default: "simulation").
        pub name: String,
        /// Largest (and initial) time step, s (default: 1/30).
        pub time_step_s: f64,
        /// Halve dt on a failed step and grow it back after successes (default: true).
        pub adaptive_time_step: bool,
        /// Smallest dt before the simulation gives up, s (default: 1e-6).
        pub min_time_step_s: f64,
        /// Factor dt grows by after each successful step, up to `time_step_s` (default: 1.5).
        pub time_step_growth: f64,
        /// Gravity, m/s² (default: (0, 0, −9.81)).
        pub gravity_m_s2: [f64; 3],
        /// Worker threads; 0 uses all cores (default: 0).
        pub threads: usize,
        /// Newton solver.
        pub newton: NewtonSettings,
        /// Output.
        pub output: OutputSettings,
        /// Contact.
        pub contact: ContactSettings,
        /// Largest number of times one step is repeated after a model hardened a stiffness
        /// (default: 40).
        pub max_hardening_retries: usize,
    }
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            name: "simulation".into(),
            time_step_s: 1.0 / 30.0,
            adaptive_time_step: true,
            min_time_step_s: 1e-6,
            time_step_growth: 1.5,
            gravity_m_s2: [0.0, 0.0, -9.81],
            threads: 0,
            newton: NewtonSettings::default(),
            output: OutputSettings::default(),
            contact: ContactSettings::default(),
            max_hardening_retries: 40,
        }
    }
}

impl Settings {
    /// Check the values; errors name the field.
    pub fn validate(&self) -> crate::Result<()> {
        use crate::error::check_param;
        let o = "settings";
        check_param(
            o,
            "time_step_s",
            self.time_step_s,
            self.time_step_s > 0.0 && self.time_step_s.is_finite(),
            "must be positive and finite (s)",
        )?;
        check_param(
            o,
            "min_time_step_s",
            self.min_time_step_s,
            self.min_time_step_s > 0.0 && self.min_time_step_s <= self.time_step_s,
            "must be positive and at most time_step_s",
        )?;
        check_param(
            o,
            "time_step_growth",
            self.time_step_growth,
            self.time_step_growth >= 1.0 && self.time_step_growth.is_finite(),
            "must be at least 1",
        )?;
        for g in self.gravity_m_s2 {
            check_param(o, "gravity_m_s2", g, g.is_finite(), "must be finite (m/s²)")?;
        }
        let n = &self.newton;
        check_param(
            o,
            "newton.residual_tolerance_n",
            n.residual_tolerance_n,
            n.residual_tolerance_n > 0.0,
            "must be positive (N)",
        )?;
        check_param(
            o,
            "newton.step_tolerance_m_s",
            n.step_tolerance_m_s,
            n.step_tolerance_m_s >= 0.0,
            "must be non-negative (m/s)",
        )?;
        check_param(
            o,
            "newton.max_iterations",
            n.max_iterations as f64,
            n.max_iterations > 0,
            "must be at least 1",
        )?;
        check_param(
            o,
            "newton.cg_relative_tolerance",
            n.cg_relative_tolerance,
            n.cg_relative_tolerance > 0.0 && n.cg_relative_tolerance < 1.0,
            "must lie in (0, 1)",
        )?;
        check_param(
            o,
            "newton.armijo",
            n.armijo,
            n.armijo >= 0.0 && n.armijo < 0.5,
            "must lie in [0, 0.5)",
        )?;
        check_param(
            o,
            "output.fps",
            self.output.fps,
            self.output.fps >= 0.0 && self.output.fps.is_finite(),
            "must be non-negative (0 disables frames)",
        )?;
        self.contact.validate()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::{BarrierKind, PairHessian};
    use crate::params::Documented;
    use serde::de::DeserializeOwned;
    use strum::VariantNames;

    /// Scene files written before the rename still set the barriers' switch.
    #[test]
    fn the_switchs_old_name_is_read() {
        let old: Settings = serde_json::from_str(r#"{"newton": {"majorizer_far_from_solution": false}}"#).unwrap();
        assert!(!old.newton.definite_far_from_solution);
        let new: Settings = serde_json::from_str(r#"{"newton": {"definite_far_from_solution": false}}"#).unwrap();
        assert!(!new.newton.definite_far_from_solution);
        assert!(Settings::default().newton.definite_far_from_solution);
    }

    /// The names the bindings list (`VARIANTS`) are the names scene files and serde use.
    fn names_round_trip<E: VariantNames + DeserializeOwned + Serialize>() {
        assert!(!E::VARIANTS.is_empty());
        for name in E::VARIANTS {
            let e: E = serde_json::from_value(serde_json::json!(name)).expect(name);
            assert_eq!(serde_json::to_value(&e).unwrap(), serde_json::json!(name));
        }
    }

    #[test]
    fn enum_names_are_the_serde_names() {
        names_round_trip::<LinearSolver>();
        names_round_trip::<Projection>();
        names_round_trip::<FrameFormat>();
        names_round_trip::<BarrierKind>();
        names_round_trip::<PairHessian>();
    }

    /// Every field of the documented structs has a doc, and the table names the serialized
    /// fields (the order is checked by the Python module when it registers the classes).
    fn table_matches<S: Documented + Default + Serialize>() {
        let json = serde_json::to_value(S::default()).unwrap();
        let keys: Vec<_> = json.as_object().unwrap().keys().cloned().collect();
        let mut names: Vec<_> = S::FIELDS.iter().map(|f| f.name.to_string()).collect();
        assert!(S::FIELDS.iter().all(|f| !f.doc_text().is_empty()));
        assert!(!S::DOC.is_empty());
        names.sort();
        let mut sorted = keys;
        sorted.sort();
        assert_eq!(names, sorted);
    }

    #[test]
    fn documented_tables_match_the_structs() {
        table_matches::<Settings>();
        table_matches::<NewtonSettings>();
        table_matches::<OutputSettings>();
        table_matches::<crate::contact::ContactSettings>();
        table_matches::<crate::presets::LineMaterial>();
        table_matches::<crate::presets::SurfaceMaterial>();
        table_matches::<crate::presets::VolumeMaterial>();
        let types: Vec<_> = Settings::FIELDS.iter().map(|f| f.rust_type()).collect();
        assert!(types.contains(&"[f64;3]".to_string()) && types.contains(&"NewtonSettings".to_string()));
    }
}
