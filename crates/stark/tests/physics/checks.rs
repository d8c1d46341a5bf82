//! Shared per-step checks of the contact tests: every accepted state is free of edge–triangle
//! intersections (the exact test, independent of the barrier and CCD) and of inverted tets.

use stark::{Simulation, StepReport};

/// Totals of the line-search validity test of rigid contact over the checked steps.
#[derive(Clone, Copy, Debug, Default)]
pub struct ValidityTotals {
    /// Trial states tested.
    pub checks: usize,
    /// Trial states rejected (an edge crossed a triangle).
    pub rejected: usize,
    /// Wall time of the tests, s.
    pub time_s: f64,
    /// Wall time of the steps, s.
    pub step_time_s: f64,
    /// Steps.
    pub steps: usize,
}

impl ValidityTotals {
    /// One line for the test output.
    pub fn summary(&self) -> String {
        format!(
            "{} steps, validity test on {} trial states ({} rejected), {:.1} ms of {:.1} ms ({:.1}%)",
            self.steps,
            self.checks,
            self.rejected,
            1e3 * self.time_s,
            1e3 * self.step_time_s,
            100.0 * self.time_s / self.step_time_s.max(1e-300)
        )
    }
}

/// Advance one step and check the accepted state; `what` names the scene in messages.
pub fn step_checked(sim: &mut Simulation, what: &str, totals: &mut ValidityTotals) -> StepReport {
    let t = sim.time();
    let report = sim
        .step()
        .unwrap_or_else(|e| panic!("{what}: step failed at t = {t}: {e}"));
    let check = sim.state_check();
    let crossings = &check.intersections;
    assert!(
        crossings.is_empty(),
        "{what}: intersection at t = {:.4} s: {:?}",
        sim.time(),
        &crossings[..crossings.len().min(5)]
    );
    let inverted = check.inverted_tets;
    assert_eq!(
        inverted,
        0,
        "{what}: {inverted} inverted tets at t = {:.4} s",
        sim.time()
    );
    if let Some(c) = report.contact {
        totals.checks += c.validity_checks;
        totals.rejected += c.invalid_trials;
        totals.time_s += c.validity_time_s;
    }
    totals.step_time_s += report.wall_time_s;
    totals.steps += 1;
    report
}
