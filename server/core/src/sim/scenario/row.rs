//! The post-processing row of a scenario run (Lim §4.2: "dynamics data of both arms … are
//! saved to files for post processing"): plain numbers and two identifiers, with its column
//! names next to it. Writing it (CSV, number format) is the server's job.

use nalgebra::{DMatrix, Isometry3};

use crate::grasp::GraspState;
use crate::hydraulics::N_ACT;
use crate::manipulability::{dual_measures, measures};
use crate::sim::{Arm, Simulation};

/// One value of a [`Row`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Cell {
    /// A number (SI units, as the column name says).
    Num(f64),
    /// A fixed identifier (stage letter, grasp-state name).
    Name(&'static str),
}

/// One post-processing row (Lim §4.2): everything the thesis plotted.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// Time (s).
    pub t_s: f64,
    /// Stage label.
    pub stage: &'static str,
    /// Joint angles per arm (rad).
    pub q: [[f64; N_ACT]; 2],
    /// Joint velocities per arm (rad/s).
    pub qd: [[f64; N_ACT]; 2],
    /// Applied valve commands per arm.
    pub u: [[f64; N_ACT]; 2],
    /// Jaw opening per arm (m).
    pub jaw_m: [f64; 2],
    /// P_I per actuator (Pa).
    pub p_in: [[f64; N_ACT]; 2],
    /// P_O per actuator (Pa).
    pub p_out: [[f64; N_ACT]; 2],
    /// Contact force/torque of each arm on the object (N, N·m).
    pub contact: [[f64; 6]; 2],
    /// Internal force/torque F_int (eq. 3.41).
    pub internal: [f64; 6],
    /// Object position (m).
    pub object_xyz: [f64; 3],
    /// Object orientation, roll pitch yaw (rad).
    pub object_rpy: [f64; 3],
    /// Grasp state.
    pub grasp: GraspState,
    /// Translational Yoshikawa measure per arm (Lim §3.5.1).
    pub yoshikawa: [f64; 2],
    /// Translational isotropy per arm.
    pub isotropy: [f64; 2],
    /// Dual-arm translational Yoshikawa measure (Lim eq. 3.68).
    pub dual_yoshikawa: f64,
    /// Dual-arm translational isotropy.
    pub dual_isotropy: f64,
    /// Each jaw's load fraction λ against its static friction limits (0 when not holding).
    pub grip_load: [f64; 2],
    /// Each jaw slipping (1) or not (0).
    pub slipping: [f64; 2],
}

impl Row {
    /// Column names, in the order [`Row::cells`] visits the values.
    pub fn header() -> Vec<String> {
        let mut h = vec!["t_s".to_string(), "stage".to_string()];
        for arm in ["left", "right"] {
            for k in 1..=N_ACT {
                h.push(format!("{arm}_q{k}_rad"));
            }
            for k in 1..=N_ACT {
                h.push(format!("{arm}_qd{k}_rad_s"));
            }
            for k in 1..=N_ACT {
                h.push(format!("{arm}_u{k}"));
            }
            h.push(format!("{arm}_jaw_m"));
            for k in 1..=N_ACT {
                h.push(format!("{arm}_p_in{k}_pa"));
                h.push(format!("{arm}_p_out{k}_pa"));
            }
            for c in ["fx_n", "fy_n", "fz_n", "tx_nm", "ty_nm", "tz_nm"] {
                h.push(format!("{arm}_contact_{c}"));
            }
        }
        for c in ["fx_n", "fy_n", "fz_n", "tx_nm", "ty_nm", "tz_nm"] {
            h.push(format!("internal_{c}"));
        }
        for c in ["x_m", "y_m", "z_m", "roll_rad", "pitch_rad", "yaw_rad"] {
            h.push(format!("object_{c}"));
        }
        h.push("grasp_state".into());
        for c in [
            "left_yoshikawa",
            "left_isotropy",
            "right_yoshikawa",
            "right_isotropy",
            "dual_yoshikawa",
            "dual_isotropy",
            "left_grip_load",
            "right_grip_load",
            "left_slipping",
            "right_slipping",
        ] {
            h.push(c.into());
        }
        h
    }

    /// Visits this row's values in [`Row::header`] order: numbers, and the stage letter and
    /// grasp-state name as identifiers. Formatting (CSV, number format) is the caller's.
    pub fn cells(&self, mut f: impl FnMut(Cell)) {
        f(Cell::Num(self.t_s));
        f(Cell::Name(self.stage));
        for i in 0..2 {
            for &x in self.q[i].iter().chain(&self.qd[i]).chain(&self.u[i]) {
                f(Cell::Num(x));
            }
            f(Cell::Num(self.jaw_m[i]));
            for k in 0..N_ACT {
                f(Cell::Num(self.p_in[i][k]));
                f(Cell::Num(self.p_out[i][k]));
            }
            for &x in &self.contact[i] {
                f(Cell::Num(x));
            }
        }
        for &x in self
            .internal
            .iter()
            .chain(&self.object_xyz)
            .chain(&self.object_rpy)
        {
            f(Cell::Num(x));
        }
        f(Cell::Name(self.grasp.as_str()));
        for x in [
            self.yoshikawa[0],
            self.isotropy[0],
            self.yoshikawa[1],
            self.isotropy[1],
            self.dual_yoshikawa,
            self.dual_isotropy,
            self.grip_load[0],
            self.grip_load[1],
            self.slipping[0],
            self.slipping[1],
        ] {
            f(Cell::Num(x));
        }
    }
}

fn rpy(iso: &Isometry3<f64>) -> [f64; 3] {
    let (r, p, y) = iso.rotation.euler_angles();
    [r, p, y]
}

/// Builds a row from the simulation state (allocates: manipulability SVDs).
pub fn row(sim: &Simulation, stage: &'static str) -> Row {
    let mut q = [[0.0; N_ACT]; 2];
    let mut qd = q;
    let mut u = q;
    let mut p_in = q;
    let mut p_out = q;
    let mut contact = [[0.0; 6]; 2];
    let mut jaw_m = [0.0; 2];
    let mut grip_load = [0.0; 2];
    let mut slipping = [0.0; 2];
    let mut yoshikawa = [0.0; 2];
    let mut isotropy = [0.0; 2];
    let mut jt: Vec<DMatrix<f64>> = Vec::with_capacity(2);
    for arm in Arm::BOTH {
        let i = arm.index();
        let a = sim.arm(arm);
        q[i] = a.q;
        qd[i] = a.qd;
        u[i] = a.spool;
        p_in[i] = a.p_in;
        p_out[i] = a.p_out;
        contact[i] = a.contact_wrench;
        jaw_m[i] = a.jaw_opening_m;
        grip_load[i] = a.grip.load_fraction;
        slipping[i] = if a.grip.slipping { 1.0 } else { 0.0 };
        let j = sim.jacobian_world(arm);
        let jtr = DMatrix::from_fn(3, N_ACT, |r, c| j[(r, c)]);
        if let Ok(m) = measures(&jtr) {
            yoshikawa[i] = m.yoshikawa;
            isotropy[i] = m.isotropy;
        }
        jt.push(jtr);
    }
    let (dual_yoshikawa, dual_isotropy) = match dual_measures(&jt[0], &jt[1]) {
        Ok(m) => (m.yoshikawa, m.isotropy),
        Err(_) => (0.0, 0.0),
    };
    let o = sim.object();
    let t = o.pose.translation.vector;
    Row {
        t_s: sim.time_s(),
        stage,
        q,
        qd,
        u,
        jaw_m,
        p_in,
        p_out,
        contact,
        internal: sim.internal_wrench(),
        object_xyz: [t.x, t.y, t.z],
        object_rpy: rpy(&o.pose),
        grasp: sim.grasp_state(),
        yoshikawa,
        isotropy,
        dual_yoshikawa,
        dual_isotropy,
        grip_load,
        slipping,
    }
}
