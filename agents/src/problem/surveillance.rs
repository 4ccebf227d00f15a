//! The persistent-surveillance case study of the paper (Section 4.4): robots keep
//! surveillance stations covered while taking turns at charging stations so that no battery
//! runs out; one assignment per episode.
//!
//! # Model
//! The world is a plane with `S` surveillance stations and `C` charging stations. Robot `i`
//! has a position `p_i` and a battery level `b_i ∈ [0, 1]`. The tasks of an episode are the
//! `S + C` stations, in that order, in **Case 2**: every station gets at least one robot,
//! every robot exactly one station. During an episode a robot travels to its station
//! (straight line, draining `travel_drain` per unit of distance) and then either watches
//! (draining `surveil_drain`) or charges (gaining `charge_rate`, capped at 1). A robot that
//! stays at a surveillance station travels 0; a robot can only leave one if another robot
//! takes its place — the coverage constraint says exactly that.
//!
//! # Cost (the paper names the ingredients — battery levels and travel distances — not a
//! formula; this is ours)
//! Each robot computes its own row from its own state:
//!
//! ```text
//! surveillance station s:  w_d · |p_i − s| + w_b · (1 − b_i)            (+ P if unsafe)
//! charging station c:      w_d · |p_i − c| + w_c · b_i                  (+ P if unreachable)
//! ```
//!
//! * travel costs distance (`w_d`): robots stay where they are unless swapping pays;
//! * watching with a low battery costs (`w_b`) and charging a full one costs (`w_c`): the
//!   fullest robots watch, the emptiest charge;
//! * **safety**: watching is *unsafe* when the battery left after the episode,
//!   `b_i − travel_drain·|p_i − s| − surveil_drain`, would fall below `reserve`; it then
//!   costs the penalty `P`, larger than any other assignment's total, so an optimal
//!   assignment never chooses it while a safe one exists. A charging station the robot
//!   cannot reach with its battery costs `P` too.
//! * ties: robots in the same state at the same place (two full batteries on one charger)
//!   would be interchangeable, giving several optima that consensus ADMM resolves slowly;
//!   each robot adds `ε · ((7i + 13j) mod 17) / 17` (default `ε = 1e-3`, a thousandth of the
//!   weights), a fixed preference that makes the optimum unique.
//!
//! A **battery violation** is a battery below 0 after an episode (the robot ran out).
//!
//! ```
//! use admm_ta_agents::problem::surveillance::SurveillanceMission;
//! let mission = SurveillanceMission::default();
//! let state = mission.initial_state(0);
//! let row = mission.cost_row(0, &state);
//! assert_eq!(row.len(), mission.tasks());
//! ```

use nalgebra::{Point2, distance};
use serde::{Deserialize, Serialize};

/// A mission (the TOML file's contents; every field has the documented default).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SurveillanceMission {
    pub robots: usize,
    /// Positions `[x, y]` of the surveillance stations.
    pub surveillance_stations: Vec<[f64; 2]>,
    /// Positions `[x, y]` of the charging stations.
    pub charging_stations: Vec<[f64; 2]>,
    /// Initial positions (default: spread on a circle of radius 4 around (5, 5)).
    pub initial_positions: Option<Vec<[f64; 2]>>,
    /// Initial battery levels (default: evenly from 1.0 down to 0.55).
    pub initial_batteries: Option<Vec<f64>>,
    /// Battery used by one episode of watching.
    pub surveil_drain: f64,
    /// Battery used per unit of distance travelled.
    pub travel_drain: f64,
    /// Battery gained by one episode of charging.
    pub charge_rate: f64,
    /// Battery a robot must still have after an episode of watching.
    pub reserve: f64,
    /// `w_d`: cost per unit of distance.
    pub distance_weight: f64,
    /// `w_b`: cost of watching per unit of missing battery.
    pub battery_weight: f64,
    /// `w_c`: cost of charging per unit of battery already there.
    pub charge_weight: f64,
    /// `P`: cost of an unsafe or unreachable station.
    pub penalty: f64,
    /// `ε`: step of the fixed robot–station preference that breaks ties.
    pub tie_break: f64,
    /// Communication graph of the robots.
    pub topology: String,
}

impl Default for SurveillanceMission {
    fn default() -> Self {
        Self {
            robots: 10,
            surveillance_stations: vec![[2.0, 8.0], [8.0, 8.0]],
            charging_stations: vec![[3.0, 2.0], [7.0, 2.0]],
            initial_positions: None,
            initial_batteries: None,
            surveil_drain: 0.12,
            travel_drain: 0.01,
            charge_rate: 0.06,
            reserve: 0.05,
            distance_weight: 0.1,
            battery_weight: 1.0,
            charge_weight: 0.5,
            penalty: 100.0,
            tie_break: 1e-3,
            topology: "complete".into(),
        }
    }
}

/// One robot's state between episodes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RobotState {
    pub position: [f64; 2],
    pub battery: f64,
}

/// A mission that cannot run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MissionError {
    #[error("mission file: {0}")]
    Parse(String),
    #[error("mission: {0}")]
    Invalid(String),
}

impl SurveillanceMission {
    /// Parses and validates a TOML mission.
    pub fn from_toml(text: &str) -> Result<Self, MissionError> {
        let mission: Self =
            toml::from_str(text).map_err(|e| MissionError::Parse(e.message().to_string()))?;
        mission.validate()?;
        Ok(mission)
    }

    /// Stations: surveillance first, then charging.
    pub fn tasks(&self) -> usize {
        self.surveillance_stations.len() + self.charging_stations.len()
    }

    /// Whether task `j` is a surveillance station.
    pub fn is_surveillance(&self, task: usize) -> bool {
        task < self.surveillance_stations.len()
    }

    fn station(&self, task: usize) -> Point2<f64> {
        let s = self.surveillance_stations.len();
        let [x, y] = if task < s {
            self.surveillance_stations[task]
        } else {
            self.charging_stations[task - s]
        };
        Point2::new(x, y)
    }

    /// Refuses missions that cannot run (Case 2 needs at least as many robots as stations).
    pub fn validate(&self) -> Result<(), MissionError> {
        let bad = |what: String| Err(MissionError::Invalid(what));
        if self.surveillance_stations.is_empty() || self.charging_stations.is_empty() {
            return bad("needs at least one surveillance and one charging station".into());
        }
        if self.robots < self.tasks() {
            return bad(format!(
                "{} robots cannot cover {} stations (every station needs a robot)",
                self.robots,
                self.tasks()
            ));
        }
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        let points = self
            .surveillance_stations
            .iter()
            .chain(&self.charging_stations)
            .chain(self.initial_positions.iter().flatten());
        if !points.clone().all(|p| finite(p)) {
            return bad("station and robot positions must be finite".into());
        }
        if let Some(p) = &self.initial_positions
            && p.len() != self.robots
        {
            return bad(format!(
                "{} initial positions for {} robots",
                p.len(),
                self.robots
            ));
        }
        if let Some(b) = &self.initial_batteries {
            if b.len() != self.robots {
                return bad(format!(
                    "{} initial batteries for {} robots",
                    b.len(),
                    self.robots
                ));
            }
            if !b.iter().all(|v| (0.0..=1.0).contains(v)) {
                return bad("initial batteries must lie in [0, 1]".into());
            }
        }
        for (name, v) in [
            ("surveil_drain", self.surveil_drain),
            ("travel_drain", self.travel_drain),
            ("charge_rate", self.charge_rate),
            ("reserve", self.reserve),
            ("distance_weight", self.distance_weight),
            ("battery_weight", self.battery_weight),
            ("charge_weight", self.charge_weight),
            ("tie_break", self.tie_break),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(format!("{name} must be a finite number ≥ 0, got {v}"));
            }
        }
        if !(self.penalty.is_finite() && self.penalty > 0.0) {
            return bad(format!("penalty must be positive, got {}", self.penalty));
        }
        if self.charge_rate <= 0.0 {
            return bad("charge_rate must be positive, or no robot can ever recharge".into());
        }
        Ok(())
    }

    /// Robot `i`'s state before the first episode.
    pub fn initial_state(&self, i: usize) -> RobotState {
        let n = self.robots.max(1);
        let position = match &self.initial_positions {
            Some(p) => p[i],
            None => {
                let angle = std::f64::consts::TAU * i as f64 / n as f64;
                [5.0 + 4.0 * angle.cos(), 5.0 + 4.0 * angle.sin()]
            }
        };
        let battery = match &self.initial_batteries {
            Some(b) => b[i],
            None => 1.0 - 0.45 * i as f64 / (n - 1).max(1) as f64,
        };
        RobotState { position, battery }
    }

    fn travel(&self, state: &RobotState, task: usize) -> f64 {
        distance(&Point2::from(state.position), &self.station(task))
    }

    /// Robot `i`'s cost of every station, from its own state only.
    pub fn cost_row(&self, i: usize, state: &RobotState) -> Vec<f64> {
        (0..self.tasks())
            .map(|j| {
                let d = self.travel(state, j);
                let b = state.battery;
                let left = b - self.travel_drain * d;
                let base = if self.is_surveillance(j) {
                    let unsafe_watch = left - self.surveil_drain < self.reserve;
                    self.distance_weight * d
                        + self.battery_weight * (1.0 - b)
                        + if unsafe_watch { self.penalty } else { 0.0 }
                } else {
                    self.distance_weight * d
                        + self.charge_weight * b
                        + if left < 0.0 { self.penalty } else { 0.0 }
                };
                base + self.tie_break * ((7 * i + 13 * j) % 17) as f64 / 17.0
            })
            .collect()
    }

    /// Every robot's first-episode cost row, concatenated (row-major `robots × tasks`).
    pub fn initial_costs(&self) -> Vec<f64> {
        (0..self.robots)
            .flat_map(|i| self.cost_row(i, &self.initial_state(i)))
            .collect()
    }

    /// The state after an episode at station `task`.
    pub fn advance(&self, state: &RobotState, task: usize) -> RobotState {
        let d = self.travel(state, task);
        let after_travel = state.battery - self.travel_drain * d;
        let battery = if self.is_surveillance(task) {
            after_travel - self.surveil_drain
        } else {
            (after_travel + self.charge_rate).min(1.0)
        };
        let p = self.station(task);
        RobotState {
            position: [p.x, p.y],
            battery,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::{AssignmentCase, CostMatrix};

    #[test]
    fn the_default_mission_keeps_every_battery_alive_under_the_optimal_assignment() {
        let s = SurveillanceMission::default();
        s.validate().unwrap();
        let mut states: Vec<RobotState> = (0..s.robots).map(|i| s.initial_state(i)).collect();
        for _ in 0..300 {
            let values = (0..s.robots)
                .flat_map(|i| s.cost_row(i, &states[i]))
                .collect();
            let costs = CostMatrix::new(s.robots, s.tasks(), values).unwrap();
            let best = crate::certify::oracle::solve_costs(&costs, AssignmentCase::Two).unwrap();
            for (state, &task) in states.iter_mut().zip(&best) {
                *state = s.advance(state, task);
                assert!(state.battery >= 0.0, "{state:?}");
            }
            for j in 0..s.tasks() {
                assert!(best.contains(&j), "station {j} uncovered");
            }
        }
    }

    #[test]
    fn bad_missions_are_refused_with_a_reason() {
        for (text, needle) in [
            ("robots = 3", "cannot cover"),
            ("charge_rate = 0.0", "recharge"),
            ("initial_batteries = [1.5]", "initial batteries"),
            ("colour = 3", "unknown field"),
            ("surveil_drain = -1.0", "surveil_drain"),
            ("charging_stations = []", "at least one"),
        ] {
            let e = SurveillanceMission::from_toml(text)
                .unwrap_err()
                .to_string();
            assert!(e.contains(needle), "{text}: {e}");
        }
        let ok = SurveillanceMission::from_toml("robots = 6\nreserve = 0.1").unwrap();
        assert_eq!(ok.robots, 6);
        assert_eq!(ok.tasks(), 4);
    }
}
