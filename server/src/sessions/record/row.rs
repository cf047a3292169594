//! The session record's CSV row (100 Hz): its values and its column names, together.

use std::io::{self, Write};

use seaarms_core::hydraulics::N_ACT;
use seaarms_core::sim::{Arm, Simulation};

use crate::csv_out::{CsvOut, Field};

/// One arm's part of a [`SessionRow`].
#[derive(Debug, Clone, PartialEq)]
pub struct ArmRow {
    /// Joint angles (rad).
    pub q: [f64; N_ACT],
    /// Joint velocities (rad/s).
    pub qd: [f64; N_ACT],
    /// Line pressures P_I (Pa).
    pub p_in: [f64; N_ACT],
    /// Line pressures P_O (Pa).
    pub p_out: [f64; N_ACT],
    /// Jaw opening (m).
    pub jaw_m: f64,
    /// Holding the object.
    pub holding: bool,
    /// Contact force/torque on the object (N, N·m).
    pub contact: [f64; 6],
}

/// One row of a session's time series.
#[derive(Debug, Clone, PartialEq)]
pub struct SessionRow {
    /// Simulated time (s).
    pub t_s: f64,
    /// Left, right.
    pub arms: [ArmRow; 2],
    /// Object position (m).
    pub object_xyz: [f64; 3],
    /// Internal force/torque (N, N·m) (Lim eq. 3.41).
    pub internal: [f64; 6],
    /// Grasp state name.
    pub grasp: &'static str,
    /// Relief-valve openings of the simulation (since its last reset).
    pub relief_events: u64,
    /// The attempt the row belongs to (`t` restarts at each attempt's start).
    pub attempt: String,
}

const WRENCH: [&str; 6] = ["fx", "fy", "fz", "tx", "ty", "tz"];

impl SessionRow {
    /// The row of the simulation's current state in attempt `attempt`.
    pub fn from_sim(sim: &Simulation, attempt: &str) -> SessionRow {
        let arm = |arm: Arm| {
            let a = sim.arm(arm);
            ArmRow {
                q: a.q,
                qd: a.qd,
                p_in: a.p_in,
                p_out: a.p_out,
                jaw_m: a.jaw_opening_m,
                holding: a.holding,
                contact: a.contact_wrench,
            }
        };
        let o = sim.object().pose.translation.vector;
        SessionRow {
            t_s: sim.time_s(),
            arms: Arm::BOTH.map(arm),
            object_xyz: [o.x, o.y, o.z],
            internal: sim.internal_wrench(),
            grasp: sim.grasp_state().as_str(),
            relief_events: sim.relief_events(),
            attempt: attempt.to_string(),
        }
    }

    /// Column names, in [`SessionRow::write`] order.
    pub fn header() -> Vec<String> {
        let mut h = vec!["t".to_string()];
        for arm in ["left", "right"] {
            for name in ["q", "qd", "p_in", "p_out"] {
                h.extend((1..=N_ACT).map(|j| format!("{arm}_{name}{j}")));
            }
            h.push(format!("{arm}_jaw_m"));
            h.push(format!("{arm}_holding"));
            h.extend(WRENCH.iter().map(|c| format!("{arm}_contact_{c}")));
        }
        h.extend(["object_x", "object_y", "object_z"].map(String::from));
        h.extend(WRENCH.iter().map(|c| format!("internal_{c}")));
        h.extend(["grasp", "relief_events", "attempt"].map(String::from));
        h
    }

    /// Writes the row (one CSV line) through the one CSV writer.
    pub fn write<W: Write>(&self, out: &mut CsvOut<W>) -> io::Result<()> {
        out.field(Field::Num(self.t_s))?;
        for a in &self.arms {
            for &x in a.q.iter().chain(&a.qd).chain(&a.p_in).chain(&a.p_out) {
                out.field(Field::Num(x))?;
            }
            out.field(Field::Num(a.jaw_m))?;
            out.field(Field::Int(u64::from(a.holding)))?;
            for &x in &a.contact {
                out.field(Field::Num(x))?;
            }
        }
        for &x in self.object_xyz.iter().chain(&self.internal) {
            out.field(Field::Num(x))?;
        }
        out.field(Field::Text(self.grasp))?;
        out.field(Field::Int(self.relief_events))?;
        out.field(Field::Text(&self.attempt))?;
        out.end_row()
    }
}
