//! The outcome of a robot–towel run, classified as in the paper's Table I: the robot pushes the
//! towel (P), drives over it (O), or gets stuck (S).
//!
//! The classifier reads only trajectories (sampled every step or every frame), in the robot's
//! driving direction `y`:
//!
//! 1. **O (over)** — the robot's rear passes the towel's far edge at some sample; or, at the end,
//!    a drive wheel is on the towel and in the final window the robot advances at least
//!    [`Rules::min_over_speed_fraction`] of its nominal speed while the towel's centroid follows
//!    it by less than [`Rules::push_follow_fraction`] (it rides on a towel that stays).
//! 2. **P (push)** — in the final window the robot advances at least [`Rules::min_advance_m`],
//!    the towel's centroid advances at least [`Rules::push_follow_fraction`] of that, and no
//!    drive wheel is on the towel during the window (the body shoves the towel along the floor).
//! 3. **S (stuck)** — anything else: the robot advances less than `min_advance_m` in the final
//!    window, or advances without carrying the towel and without climbing it. The mean motor
//!    torque (a fraction of the cap) in the window is reported with it: at the cap the wheels
//!    slip or stall against the towel.
//!
//! The final window is the last [`Rules::window_s`] seconds of the run.

use serde::{Deserialize, Serialize};

/// One sample of a robot–towel run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Sample {
    /// Time, s.
    pub time_s: f64,
    /// Robot body centre along the driving direction, m.
    pub robot_y_m: f64,
    /// Rearmost point of the robot along the driving direction, m.
    pub robot_rear_y_m: f64,
    /// Towel centroid (mean node position) along the driving direction, m.
    pub towel_centroid_y_m: f64,
    /// Farthest towel node along the driving direction, m.
    pub towel_far_edge_y_m: f64,
    /// A drive wheel touches the towel.
    pub drive_wheel_on_towel: bool,
    /// Mean motor torque as a fraction of the cap (1 = at the stall torque).
    pub motor_torque_fraction: f64,
}

/// Outcome of a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Outcome {
    /// The robot pushes the towel.
    #[serde(rename = "P")]
    Push,
    /// The robot drives over the towel.
    #[serde(rename = "O")]
    Over,
    /// The robot gets stuck.
    #[serde(rename = "S")]
    Stuck,
}

impl Outcome {
    /// The paper's letter.
    pub fn letter(self) -> char {
        match self {
            Outcome::Push => 'P',
            Outcome::Over => 'O',
            Outcome::Stuck => 'S',
        }
    }
}

/// Thresholds of the classifier.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Rules {
    /// Length of the final window, s.
    pub window_s: f64,
    /// Nominal forward speed of the robot, m/s.
    pub nominal_speed_m_s: f64,
    /// Least advance of the robot in the final window for P, m.
    pub min_advance_m: f64,
    /// The towel's centroid advances at least this fraction of the robot's advance: P.
    pub push_follow_fraction: f64,
    /// Least mean speed (fraction of nominal) in the final window to count as driving over.
    pub min_over_speed_fraction: f64,
}

impl Default for Rules {
    fn default() -> Self {
        Rules {
            window_s: 1.0,
            nominal_speed_m_s: 0.26,
            // A fifth of the nominal speed over the window.
            min_advance_m: 0.05,
            push_follow_fraction: 0.5,
            min_over_speed_fraction: 0.25,
        }
    }
}

/// A classified run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Classification {
    /// The outcome.
    pub outcome: Outcome,
    /// Which rule decided, in words.
    pub reason: String,
    /// Robot advance in the final window, m.
    pub robot_advance_m: f64,
    /// Towel centroid advance in the final window, m.
    pub towel_advance_m: f64,
    /// Mean motor torque fraction in the final window.
    pub mean_torque_fraction: f64,
}

/// Classify a run from its samples (in time order; at least two).
pub fn classify(samples: &[Sample], rules: &Rules) -> Result<Classification, String> {
    let (Some(first), Some(last)) = (samples.first(), samples.last()) else {
        return Err("no samples".into());
    };
    if samples.len() < 2 || !(last.time_s > first.time_s) {
        return Err("the run needs at least two samples in time order".into());
    }
    let start = (last.time_s - rules.window_s).max(first.time_s);
    let window: Vec<&Sample> = samples.iter().filter(|s| s.time_s >= start).collect();
    let w0 = window[0];
    let duration_s = (last.time_s - w0.time_s).max(f64::MIN_POSITIVE);
    let robot_advance_m = last.robot_y_m - w0.robot_y_m;
    let towel_advance_m = last.towel_centroid_y_m - w0.towel_centroid_y_m;
    let mean_torque_fraction = window.iter().map(|s| s.motor_torque_fraction).sum::<f64>() / window.len() as f64;
    let result = |outcome, reason: String| Classification {
        outcome,
        reason,
        robot_advance_m,
        towel_advance_m,
        mean_torque_fraction,
    };
    if let Some(s) = samples.iter().find(|s| s.robot_rear_y_m > s.towel_far_edge_y_m) {
        return Ok(result(
            Outcome::Over,
            format!(
                "the robot's rear ({:.3} m) passed the towel's far edge ({:.3} m) at t = {:.2} s",
                s.robot_rear_y_m, s.towel_far_edge_y_m, s.time_s
            ),
        ));
    }
    let speed = robot_advance_m / duration_s;
    let follows = robot_advance_m > 0.0 && towel_advance_m >= rules.push_follow_fraction * robot_advance_m;
    if last.drive_wheel_on_towel && speed >= rules.min_over_speed_fraction * rules.nominal_speed_m_s && !follows {
        return Ok(result(
            Outcome::Over,
            format!(
                "a drive wheel is on the towel and the robot advances at {speed:.3} m/s in the last {:.1} s \
                 while the towel's centroid moves {towel_advance_m:.3} m",
                duration_s
            ),
        ));
    }
    let climbing = window.iter().any(|s| s.drive_wheel_on_towel);
    if robot_advance_m >= rules.min_advance_m && follows && !climbing {
        return Ok(result(
            Outcome::Push,
            format!(
                "the towel's centroid advances {towel_advance_m:.3} m with the robot's {robot_advance_m:.3} m \
                 in the last {duration_s:.1} s, no drive wheel on the towel"
            ),
        ));
    }
    let why = if robot_advance_m < rules.min_advance_m {
        format!("the robot advances only {robot_advance_m:.3} m in the last {duration_s:.1} s")
    } else if climbing && follows {
        format!("the robot advances {robot_advance_m:.3} m but drags the towel with a wheel on it")
    } else {
        format!(
            "the robot advances {robot_advance_m:.3} m without carrying the towel ({towel_advance_m:.3} m) \
             or passing it"
        )
    };
    Ok(result(
        Outcome::Stuck,
        format!(
            "{why}; mean motor torque {:.0}% of the cap",
            100.0 * mean_torque_fraction
        ),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run of `duration` s sampled at 10 ms: the robot (radius 0.18 m) at `robot(t)`, the
    /// towel's centroid at `towel(t)` with its far edge 0.35 m beyond, wheels on the towel per
    /// `on(t)`, torque fraction `torque(t)`.
    fn run(
        duration: f64,
        robot: impl Fn(f64) -> f64,
        towel: impl Fn(f64) -> f64,
        on: impl Fn(f64) -> bool,
        torque: impl Fn(f64) -> f64,
    ) -> Vec<Sample> {
        (0..=(duration * 100.0).round() as usize)
            .map(|i| {
                let t = i as f64 * 0.01;
                Sample {
                    time_s: t,
                    robot_y_m: robot(t),
                    robot_rear_y_m: robot(t) - 0.18,
                    towel_centroid_y_m: towel(t),
                    towel_far_edge_y_m: towel(t) + 0.35,
                    drive_wheel_on_towel: on(t),
                    motor_torque_fraction: torque(t),
                }
            })
            .collect()
    }

    #[test]
    fn rear_past_the_far_edge_is_over() {
        // Drives at 0.26 m/s from 0 over a towel centred at 0.7 (far edge 1.05 m): the rear
        // passes it at t = (1.05 + 0.18)/0.26 = 4.73 s.
        let s = run(6.0, |t| 0.26 * t, |_| 0.7, |t| (2.0..4.5).contains(&t), |_| 0.3);
        let c = classify(&s, &Rules::default()).unwrap();
        assert_eq!(c.outcome, Outcome::Over, "{}", c.reason);
        assert!(c.reason.contains("t = 4.7"), "{}", c.reason);
    }

    #[test]
    fn riding_on_a_towel_that_stays_is_over() {
        // Still on the towel at the end (a long towel), climbing at 0.2 m/s.
        let s = run(6.0, |t| 0.2 * t, |_| 1.5, |t| t > 2.0, |_| 0.5);
        let c = classify(&s, &Rules::default()).unwrap();
        assert_eq!(c.outcome, Outcome::Over, "{}", c.reason);
    }

    #[test]
    fn towel_moving_with_the_robot_is_push() {
        // From t = 2 s the towel moves with the robot at 0.2 m/s; no wheel on it.
        let robot = |t: f64| 0.26 * t.min(2.0) + 0.2 * (t - 2.0).max(0.0);
        let towel = |t: f64| 0.8 + 0.2 * (t - 2.0).max(0.0);
        let s = run(6.0, robot, towel, |_| false, |_| 0.9);
        let c = classify(&s, &Rules::default()).unwrap();
        assert_eq!(c.outcome, Outcome::Push, "{}", c.reason);
        assert!((c.robot_advance_m - 0.2).abs() < 1e-9 && (c.towel_advance_m - 0.2).abs() < 1e-9);
    }

    #[test]
    fn stalled_against_the_towel_is_stuck_at_the_cap() {
        // Stops at the towel at t = 2 s with the motors at their cap.
        let s = run(
            6.0,
            |t| 0.26 * t.min(2.0),
            |_| 0.8,
            |t| t > 1.8,
            |t| if t > 2.0 { 1.0 } else { 0.3 },
        );
        let c = classify(&s, &Rules::default()).unwrap();
        assert_eq!(c.outcome, Outcome::Stuck, "{}", c.reason);
        assert!(c.reason.contains("100% of the cap"), "{}", c.reason);
    }

    #[test]
    fn dragging_the_towel_with_a_wheel_on_it_is_stuck() {
        // The robot crawls while a wheel is on the towel and the towel comes along: neither a
        // clean push (a wheel climbs) nor driving over (the towel follows).
        let s = run(6.0, |t| 0.05 * t, |t| 0.8 + 0.05 * t, |_| true, |_| 1.0);
        let c = classify(&s, &Rules::default()).unwrap();
        assert_eq!(c.outcome, Outcome::Stuck, "{}", c.reason);
    }

    #[test]
    fn slow_creep_below_the_threshold_is_stuck() {
        // 4 cm in the last second (below 5 cm), towel following: not a push.
        let s = run(6.0, |t| 0.04 * t, |t| 0.8 + 0.04 * t, |_| false, |_| 1.0);
        let c = classify(&s, &Rules::default()).unwrap();
        assert_eq!(c.outcome, Outcome::Stuck, "{}", c.reason);
    }

    #[test]
    fn too_few_samples_is_an_error() {
        assert!(classify(&[], &Rules::default()).is_err());
        assert!(classify(&[Sample::default()], &Rules::default()).is_err());
    }

    #[test]
    fn outcome_letters_serialise_as_in_the_paper() {
        assert_eq!(serde_json::to_string(&Outcome::Push).unwrap(), "\"P\"");
        assert_eq!(Outcome::Over.letter(), 'O');
    }
}
