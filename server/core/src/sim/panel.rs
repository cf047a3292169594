//! The intervention panel's stages of the step (physics in [`crate::panel`]): the jaws taking
//! and releasing its items (stage 1), the held items' loads on the jaws (stage 3) and the
//! items' own update after the arms moved (stage 9); and the read accessors. Every stage
//! returns at once without a panel, so a simulation without one is unchanged.

use nalgebra::{Isometry3, Translation3, Vector3, Vector6};

use super::arm::{self, RELEASE_GAP_M};
use super::{Arm, Simulation};
use crate::panel::{
    Graspable, PanelParams, PanelState, StabPhase, ToolLoad, item_torque_about, tool_load,
    valve_step,
};

/// A side-load fault is counted on a rising edge above the limit and re-armed only once the
/// load falls below this fraction of it (0.9), so a load hovering at the limit counts once.
const SIDE_LOAD_REARM: f64 = 0.9;

impl Simulation {
    /// The panel's state, `None` without a panel.
    pub fn panel(&self) -> Option<&PanelState> {
        self.state.panel.as_ref()
    }

    /// What arm `arm`'s jaw could take now: a box handle it is within reach of and aligned
    /// with (the jaw stage's own capture test), else the valve's T-bar or the stab's handle
    /// when the tool point is within the panel's capture radius of it and the other arm does
    /// not hold it.
    pub fn in_capture_range(&self, arm: Arm) -> Option<Graspable> {
        if let Some(r) = self.reach(arm.index()).filter(|r| r.aligned) {
            return Some(Graspable::BoxHandle(r.handle));
        }
        self.panel_capture(arm)
    }

    /// The valve's T-bar grip point (world, m) — it lies on the stem axis, so it does not
    /// move as the valve turns.
    pub fn valve_grip_m(&self) -> Option<Vector3<f64>> {
        self.params.panel.as_ref().map(PanelParams::valve_grip_m)
    }

    /// The stab's handle grip point (world, m).
    pub fn stab_handle_m(&self) -> Option<Vector3<f64>> {
        self.state.panel.as_ref().map(PanelState::stab_handle_m)
    }

    /// The holster mouth (world, m) and axis (into the panel).
    pub fn holster_m(&self) -> Option<(Vector3<f64>, Vector3<f64>)> {
        let p = self.params.panel.as_ref()?;
        Some((p.holster_mouth_m(), p.normal()))
    }

    /// The receptacle mouth (world, m) and axis (into the panel).
    pub fn receptacle_m(&self) -> Option<(Vector3<f64>, Vector3<f64>)> {
        let p = self.params.panel.as_ref()?;
        Some((p.receptacle_mouth_m(), p.normal()))
    }

    /// Arm `i` holds a panel item.
    pub(super) fn panel_holds(&self, i: usize) -> bool {
        self.state
            .panel
            .as_ref()
            .is_some_and(|s| s.held_by(Arm::BOTH[i]).is_some())
    }

    /// The panel item within capture range of `arm`'s tool point and not held by the other arm.
    fn panel_capture(&self, arm: Arm) -> Option<Graspable> {
        let (p, s) = (self.params.panel.as_ref()?, self.state.panel.as_ref()?);
        let tool = self.work[arm.index()].tool.translation.vector;
        let free = |item| s.holder(item).is_none_or(|a| a == arm);
        let near = |x: Vector3<f64>| (tool - x).norm() <= p.capture_radius_m;
        if near(p.valve_grip_m()) && free(Graspable::Valve) {
            Some(Graspable::Valve)
        } else if near(s.stab_handle_m()) && free(Graspable::Stab) {
            Some(Graspable::Stab)
        } else {
            None
        }
    }

    /// Stage 1, after the jaw moved (`cmd`: the speed-scaled jaw command; `before`: the
    /// opening before it moved): a jaw holding a panel item stops on its grip and lets go
    /// when opened [`RELEASE_GAP_M`] past it; a jaw that is not holding anything closes on a
    /// grip in capture range (it was open at least the grip width and is now closed to it)
    /// and takes the item, as the box handles are taken ([`arm::update_jaw`]).
    pub(super) fn panel_jaw(&mut self, i: usize, cmd: f64, before: f64) {
        let Some(p) = self.params.panel else {
            return;
        };
        let arm = Arm::BOTH[i];
        let width = |item| match item {
            Graspable::Stab => p.stab.handle_width_m,
            _ => p.valve.grip_width_m,
        };
        let held = self.state.panel.as_ref().and_then(|s| s.held_by(arm));
        let capture = match held {
            None if !self.state.arms[i].holding && cmd < 0.0 => self.panel_capture(arm),
            _ => None,
        };
        let tool = self.work[i].tool;
        let jaw = &self.params.arms[i].hydraulics.jaw;
        let a = &mut self.state.arms[i];
        let Some(s) = self.state.panel.as_mut() else {
            return;
        };
        if let Some(item) = held {
            let w = width(item);
            if a.jaw_opening_m > w + RELEASE_GAP_M {
                a.clamp_force_n = 0.0;
                release(&p, s, item);
            } else {
                a.jaw_opening_m = a.jaw_opening_m.max(w);
                a.clamp_force_n = arm::clamp_force(a.clamp_force_n, jaw, true, cmd);
            }
        } else if let Some(item) = capture {
            let w = width(item);
            if before >= w - 1e-9 && a.jaw_opening_m <= w + 1e-9 {
                a.jaw_opening_m = w;
                a.clamp_force_n = arm::clamp_force(a.clamp_force_n, jaw, true, cmd);
                take(&p, s, item, arm, &tool);
            }
        }
    }

    /// Stage 3: each arm's load from the panel item it holds (`None` without one).
    pub(super) fn panel_loads(&self) -> [Option<ToolLoad>; 2] {
        let (Some(p), Some(s)) = (self.params.panel.as_ref(), self.state.panel.as_ref()) else {
            return [None, None];
        };
        Arm::BOTH.map(|arm| self.load_on(p, s, arm))
    }

    /// The load on `arm`'s jaw at the current state.
    fn load_on(&self, p: &PanelParams, s: &PanelState, arm: Arm) -> Option<ToolLoad> {
        let i = arm.index();
        let w = &self.work[i];
        let twist = w.jw * Vector6::from(self.state.arms[i].qd);
        let sp = &self.params.step;
        let rho = sp.environment.density_kgm3();
        tool_load(p, s, arm, &w.tool, &twist, &sp.gravity, rho)
    }

    /// Stage 9, with the arms at their new state: the valve's 1-DOF step under the holding
    /// jaw's torque about its axis (backward Euler in the coupling's stiffness and damping
    /// about that axis, [`valve_step`]); the stab's pose, phase, depth and side load, and the
    /// side-load fault count (rising edges above the limit, re-armed below
    /// [`SIDE_LOAD_REARM`] of it).
    pub(super) fn panel_update(&mut self) {
        let (Some(p), Some(mut s)) = (self.params.panel, self.state.panel) else {
            return;
        };
        let h = self.params.step.dt_s;
        let (mut angle, mut rate) = (s.valve_angle_rad, s.valve_rate_rad_s);
        s.valve_torque_nm = 0.0;
        let (k, c) = match s.valve_holder {
            Some(arm) => {
                if let Some(load) = self.load_on(&p, &s, arm) {
                    let tool = self.work[arm.index()].tool.translation.vector;
                    s.valve_torque_nm =
                        item_torque_about(&load, &tool, &p.valve_grip_m(), &p.valve_axis());
                }
                (p.coupling.stiffness_nm_rad, p.coupling.damping_nm_s_rad)
            }
            None => (0.0, 0.0),
        };
        valve_step(&p.valve, &mut angle, &mut rate, s.valve_torque_nm, k, c, h);
        (s.valve_angle_rad, s.valve_rate_rad_s) = (angle, rate);
        self.update_stab(&p, &mut s);
        let limit = p.stab.side_load_limit_n;
        if s.side_load_n > limit && !s.side_over {
            s.side_load_faults += 1;
            s.side_over = true;
        } else if s.side_load_n < SIDE_LOAD_REARM * limit {
            s.side_over = false;
        }
        s.peak_side_load_n = s.peak_side_load_n.max(s.side_load_n);
        self.state.panel = Some(s);
    }

    /// Stage 9's stab part (see [`crate::panel`]'s module docs for the rules).
    fn update_stab(&self, p: &PanelParams, s: &mut PanelState) {
        s.side_load_n = 0.0;
        s.stop_force_n = 0.0;
        let Some(arm) = s.stab_holder else {
            return;
        };
        let tool = self.work[arm.index()].tool;
        if s.stab_phase == StabPhase::Seated {
            if let Some(load) = self.load_on(p, s, arm) {
                s.side_load_n = load.side_load_n;
                s.stop_force_n = (-load.pull_n).max(0.0);
                if load.pull_n > p.stab.seating_force_n {
                    s.stab_phase = StabPhase::Inserting;
                }
            }
            return;
        }
        s.stab_pose = tool * s.stab_grasp;
        let n = p.normal();
        let tip = s.stab_tip_m(p);
        let axis = s.stab_pose.rotation * Vector3::x();
        let aligned = |mouth: &Vector3<f64>| {
            let d = tip - mouth;
            (d - n * d.dot(&n)).norm() <= p.stab.position_tolerance_m
                && axis.dot(&n).clamp(-1.0, 1.0).acos() <= p.stab.angle_tolerance_rad
        };
        let holster = p.holster_mouth_m();
        let dh = tip - holster;
        // In the holster sleeve: past its mouth and within a body radius of its axis.
        let in_holster =
            dh.dot(&n) > 0.0 && (dh - n * dh.dot(&n)).norm() <= 0.5 * p.stab.diameter_m;
        if s.in_holster_bore && !in_holster {
            s.in_holster_bore = false;
        } else if !s.in_holster_bore && in_holster && aligned(&holster) {
            s.in_holster_bore = true;
        }
        let mouth = p.receptacle_mouth_m();
        let depth = (tip - mouth).dot(&n);
        match s.stab_phase {
            StabPhase::Inserting if depth < 0.0 => s.stab_phase = StabPhase::Held(arm),
            StabPhase::Held(_) if depth > 0.0 && !s.in_holster_bore && aligned(&mouth) => {
                s.stab_phase = StabPhase::Inserting;
            }
            _ => {}
        }
        s.stab_depth_m = 0.0;
        s.face_force_n = 0.0;
        if let StabPhase::Held(_) = s.stab_phase {
            s.face_force_n = self.load_on(p, s, arm).map_or(0.0, |l| l.face_n);
        }
        if s.stab_phase == StabPhase::Inserting {
            s.stab_depth_m = depth.max(0.0);
            if let Some(load) = self.load_on(p, s, arm) {
                s.side_load_n = load.side_load_n;
                s.stop_force_n = load.stop_push_n;
                if load.stop_push_n >= p.stab.seating_force_n {
                    // Latched where it is, its tip moved back to full depth: no jump in the
                    // lateral or angular coupling, and the axial push carries on into the
                    // coupling (the latch force it had).
                    s.stab_phase = StabPhase::Seated;
                    s.seatings += 1;
                    s.stab_pose.translation.vector -= n * (depth - p.stab.insertion_depth_m);
                    s.stab_depth_m = p.stab.insertion_depth_m;
                }
            }
        }
    }
}

/// `arm`'s jaw (tool pose `tool`) takes `item`.
fn take(p: &PanelParams, s: &mut PanelState, item: Graspable, arm: Arm, tool: &Isometry3<f64>) {
    match item {
        Graspable::Valve => {
            s.valve_holder = Some(arm);
            s.valve_grasp = p.valve_frame(s.valve_angle_rad).inverse() * tool;
        }
        Graspable::Stab => {
            s.stab_holder = Some(arm);
            s.stab_grasp = tool.inverse() * s.stab_pose;
            match s.stab_phase {
                StabPhase::Holstered => {
                    s.in_holster_bore = true;
                    s.stab_phase = StabPhase::Held(arm);
                }
                StabPhase::Dropped | StabPhase::Held(_) => s.stab_phase = StabPhase::Held(arm),
                StabPhase::Inserting | StabPhase::Seated => {}
            }
        }
        Graspable::BoxHandle(_) => {}
    }
}

/// The holding jaw lets go of `item`: the valve stays where it is; the stab stays in the
/// receptacle (inserting or seated), goes back into the holster if its tip is in the holster
/// bore, or else drops to the seabed below where it was let go.
fn release(p: &PanelParams, s: &mut PanelState, item: Graspable) {
    match item {
        Graspable::Valve => s.valve_holder = None,
        Graspable::Stab => {
            s.stab_holder = None;
            if let StabPhase::Held(_) = s.stab_phase {
                if s.in_holster_bore {
                    s.stab_phase = StabPhase::Holstered;
                    s.stab_pose = p.holstered_stab();
                } else {
                    s.stab_phase = StabPhase::Dropped;
                    let mut t = s.stab_pose.translation.vector;
                    t.z = p.seabed_z_m() + 0.5 * p.stab.diameter_m;
                    s.stab_pose = Isometry3::from_parts(Translation3::from(t), p.pose.rotation);
                }
            }
        }
        Graspable::BoxHandle(_) => {}
    }
}
