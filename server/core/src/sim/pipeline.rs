//! The 1 ms step as a pipeline of named stages (the scheme is in the [`super`] module docs).
//! [`Simulation::step_inner`] is the list, after stage 0, the operator
//! ([`super::Operator::input`]: sticks and settings to the [`Input`], run by the caller):
//!
//! 0. the water's motion ramps towards the set current ([`Simulation::advance_flow`]);
//! 1. jaws and grasp transitions, per arm ([`arm::update_jaw`]), then the panel items'
//!    grasp and release ([`Simulation::panel_jaw`]; only with a panel);
//! 2. spool commands: cooperative control, or each arm's open loop or joint servo, then
//!    stuck valves ([`Simulation::spool_commands`]);
//! 3. panel loads: the held valve's or stab's wrench on each jaw with its stiffness,
//!    damping and lumped mass ([`Simulation::panel_loads`]; only with a panel);
//! 4. arm terms, per arm: H, C q̇ + G, J̇q̇, linkage levers and the factor of H̃, with the
//!    panel load linearly implicit ([`arm::arm_terms`]);
//! 5. object terms: inertia, weight, implicit seabed damping ([`ObjectTerms::new`]); then
//!    the contacts of links and jaws with everything ([`Simulation::contact_terms`], from
//!    the arms' and the object's mobilities), as implicit terms into each arm's H̃
//!    ([`arm::add_contacts`]) and rows for the box;
//! 6. the grasp constraint system ([`Constraint::new`]) with each holding jaw's grip limits
//!    ([`JawGrip::new`]);
//! 7. the sub-steps ([`Simulation::substep`]): chamber pressures, free accelerations,
//!    the box's contact forces ([`contact::box_acceleration`]), the grasp's contact wrenches
//!    (a slipping jaw's capped at its kinetic friction limits), integration;
//! 8. outputs: the contact report and strikes ([`Simulation::contact_report`]), relief
//!    openings, contact and internal wrenches, time, kinematics, end stops, then the slip
//!    stage: a slipping jaw's grasp frame follows the bar, and the grasp is lost when the bar
//!    has slid out ([`Simulation::finish_step`], [`constraint::slip_stage`]);
//! 9. panel items: the valve's 1-DOF step, the stab's pose, phase, depth and side load
//!    ([`Simulation::panel_update`]; only with a panel).
//!
//! Stages 3–6 fill a [`StepScratch`] that the sub-steps read. Stage 8 pushes the step's
//! events ([`super::Event`]: relief, end stop, slip, slid out); [`Simulation::step`] adds the
//! grasp change after the seabed debounce.

use nalgebra::{Point3, Vector3, Vector6};

use super::arm::{self, ArmTerms, Reach};
use super::constraint::{self, Constraint, GripOut, JawGrip};
use super::contact::{self, ContactTerms, ContactWork};
use super::object::{self, ObjectTerms};
use super::{Arm, ControlMethod, Event, Input, Simulation};
use crate::control::{self, ControlParams, CoopInputs};
use crate::finite_or;
use crate::hydraulics::N_ACT;
use crate::kinematics;
use crate::panel::ToolLoad;

/// Everything computed once per step and held over its sub-steps (configuration-dependent
/// terms change by < 0.3 % in 1 ms at the arms' speeds). Fixed-size, on the stack.
#[derive(Debug, Clone, Copy)]
pub(super) struct StepScratch {
    /// Sub-step length h (s).
    h: f64,
    /// Per arm: stage 4.
    arms: [ArmTerms; 2],
    /// Stage 5.
    object: ObjectTerms,
    /// Stage 6.
    constraint: Constraint,
}

/// What the last sub-step leaves for the outputs.
#[derive(Debug, Clone, Copy, Default)]
struct SubstepOutput {
    /// Relief valve open, per arm and actuator.
    relief: [[bool; N_ACT]; 2],
    /// Contact wrench of each arm on the object (zero when not holding).
    contact: [Vector6<f64>; 2],
    /// Each jaw's grip.
    grip: [GripOut; 2],
}

impl Simulation {
    /// One step: the stages in order (see the module docs). Kinematics are current for the
    /// state's q on entry and on exit.
    pub(super) fn step_inner(&mut self, input: &Input) {
        self.advance_flow();
        let speed = finite_or(input.speed_scale, 0.0).clamp(0.0, 1.0);
        for i in 0..2 {
            let reach = self.reach(i).filter(|_| !self.panel_holds(i));
            let cmd = finite_or(input.arms[i].jaw, 0.0).clamp(-1.0, 1.0) * speed;
            let before = self.state.arms[i].jaw_opening_m;
            arm::update_jaw(
                &mut self.state.arms[i],
                &self.params.arms[i].hydraulics.jaw,
                &self.params.object,
                reach,
                cmd,
                &self.work[i].tool,
                &self.state.object.pose,
                self.params.step.dt_s,
            );
            self.panel_jaw(i, cmd, before);
        }
        let r = self.grasp_radii();
        self.spool_commands(input, speed, &r);
        let loads = self.panel_loads();
        // The contact workspace, out of `self` while the step borrows it (a pointer moves).
        let mut cw = self
            .contact_work
            .take()
            .unwrap_or_else(|| Box::new(ContactWork::new()));
        let scratch = self.step_scratch(&r, &loads, &mut cw);
        let mut out = SubstepOutput::default();
        for k in 0..self.params.step.substeps {
            out = self.substep(&scratch, &cw.terms, k == 0);
        }
        self.finish_step(&scratch, &cw.terms, &out);
        self.contact_work = Some(cw);
        self.panel_update();
    }

    /// Stage 2: the valve spool of every actuator. Cooperative control while the method is
    /// closed loop and both jaws hold (its object pose reference starts at the object's pose);
    /// otherwise each arm's operator input. A stuck valve overrides its command.
    fn spool_commands(&mut self, input: &Input, speed: f64, r: &[Vector3<f64>; 2]) {
        let holding_both = self.state.arms.iter().all(|a| a.holding);
        let coop = input.method == ControlMethod::Closed && holding_both;
        if coop && !self.state.coop_active {
            self.state.coop_ref = self.state.object.pose;
        }
        self.state.coop_active = coop;
        let nominal: [[f64; N_ACT]; 2] = core::array::from_fn(|i| {
            core::array::from_fn(|j| {
                self.params.arms[i].hydraulics.actuators[j].nominal_speed_rad_s
            })
        });
        let (dt, cp) = (self.params.step.dt_s, &self.params.control);
        let spools = if coop {
            let contact = self.state.arms.map(|a| Vector6::from(a.contact_wrench));
            let ci = CoopInputs {
                object: &self.state.object.pose,
                r,
                jacobians: [&self.work[0].jw, &self.work[1].jw],
                contact: &contact,
                twist: &object_twist_command(&input.object_velocity, speed, cp),
                nominal_speed: &nominal,
            };
            let u = control::cooperative(&ci, &mut self.state.coop_ref, dt, cp);
            for a in self.state.arms.iter_mut() {
                a.servo_active = false;
            }
            u
        } else {
            // In the closed chain each jaw is taken to carry half the object's weight in the
            // medium (the equal share, eq. 3.46) for the arms' rate control.
            let share = -0.5
                * object::wet_mass_kg(&self.params.object, &self.params.step.environment)
                * self.params.step.gravity.z;
            let arms = &mut self.state.arms;
            let work = &mut self.work;
            core::array::from_fn(|i| {
                arm::operator_spools(
                    &mut arms[i],
                    &input.arms[i],
                    &self.models[i],
                    &self.params.arms[i],
                    &self.params.step,
                    &mut work[i],
                    speed,
                    cp,
                    holding_both,
                    share,
                )
            })
        };
        for (i, a) in self.state.arms.iter_mut().enumerate() {
            let faults = &self.params.arms[i].faults;
            // The spool follows its command (or a stuck valve's position) with the valve's
            // first-order lag (hydraulics::SPOOL_TIME_CONSTANT_S).
            a.spool = core::array::from_fn(|j| {
                crate::hydraulics::spool_response(a.spool[j], faults.spool(j, spools[i][j]), dt)
            });
        }
    }

    /// Stages 4–6: the terms held over the step's sub-steps (`loads`: stage 3's).
    fn step_scratch(
        &self,
        r: &[Vector3<f64>; 2],
        loads: &[Option<ToolLoad>; 2],
        contacts: &mut ContactWork,
    ) -> StepScratch {
        let sp = &self.params.step;
        let h = sp.dt_s / sp.substeps as f64;
        let st = &self.state;
        let held = st.arms.iter().any(|a| a.holding);
        let object = ObjectTerms::new(&self.params.object, sp, &st.object, &st.flow, held, h);
        let mut arms: [ArmTerms; 2] = core::array::from_fn(|i| {
            arm::arm_terms(
                &self.models[i],
                &self.params.arms[i],
                sp,
                &self.work[i],
                &st.arms[i],
                &st.flow,
                h,
                loads[i].as_ref(),
            )
        });
        let contact_loads = self.contact_terms(h, &object, &arms, contacts);
        for (i, t) in arms.iter_mut().enumerate() {
            if let Some(l) = &contact_loads[i] {
                arm::add_contacts(t, l, &self.work[i].jw, st.arms[i].holding);
            }
        }
        let grip = core::array::from_fn(|i| {
            st.arms[i].holding.then(|| {
                JawGrip::new(
                    &self.params,
                    &st.arms[i],
                    &self.work[i].tool,
                    &st.object.pose,
                )
            })
        });
        let constraint = Constraint::new(
            [(&st.arms[0], &arms[0]), (&st.arms[1], &arms[1])],
            (&st.object, &object),
            [&self.work[0].tool, &self.work[1].tool],
            r,
            sp,
            grip,
        );
        StepScratch {
            h,
            arms,
            object,
            constraint,
        }
    }

    /// Stage 7, one sub-step of length h: chamber pressures (backward Euler), the arms' and
    /// the object's free accelerations, the contact wrenches of the closed chain, then
    /// semi-implicit Euler for arms and object. `first`: the step's first sub-step.
    fn substep(&mut self, s: &StepScratch, contacts: &ContactTerms, first: bool) -> SubstepOutput {
        let h = s.h;
        let mut out = SubstepOutput::default();
        let mut qdd = [Vector6::zeros(); 2];
        for (i, a) in self.state.arms.iter_mut().enumerate() {
            let hp = &self.params.arms[i].hydraulics;
            out.relief[i] = arm::update_pressures(a, hp, &s.arms[i], h);
            qdd[i] = arm::free_acceleration(a, &self.models[i], hp, &s.arms[i], &self.params.step);
        }
        let o = &self.state.object;
        let (mut acc_o, seabed) = s.object.free_acceleration(&self.params.object, o, first);
        contact::box_acceleration(contacts, &object::twist(o), &mut acc_o, h);
        let arms = &self.state.arms;
        (out.contact, out.grip) = s.constraint.apply(
            [&s.arms[0], &s.arms[1]],
            &s.object,
            [&self.work[0].jw, &self.work[1].jw],
            [&arms[0].qd, &arms[1].qd],
            &object::twist(o),
            &mut qdd,
            &mut acc_o,
        );
        for ((a, model), qdd) in self.state.arms.iter_mut().zip(&self.models).zip(&qdd) {
            arm::integrate(a, model, qdd, h);
        }
        object::integrate(&mut self.state.object, &acc_o, &seabed, h);
        out
    }

    /// Stage 8: the contact report and strikes, relief openings (rising edges), contact and
    /// internal wrenches, time, the kinematics, end stops (rising edges) and contact flags for
    /// the new q, and the slip stage; each detection is pushed to the step's events.
    fn finish_step(&mut self, s: &StepScratch, contacts: &ContactTerms, out: &SubstepOutput) {
        self.contact_report(contacts, s.h);
        for (i, a) in self.state.arms.iter_mut().enumerate() {
            for j in 0..N_ACT {
                if out.relief[i][j] && !a.relief_open[j] {
                    a.relief_events += 1;
                    self.events.push(Event::Relief {
                        arm: Arm::BOTH[i],
                        actuator: j,
                    });
                }
                a.relief_open[j] = out.relief[i][j];
            }
            a.contact_wrench = if s.constraint.active[i] {
                out.contact[i].into()
            } else {
                [0.0; 6]
            };
        }
        self.state.internal = s.constraint.internal_wrench(&out.contact).into();
        self.state.time_s += self.params.step.dt_s;
        self.state.steps += 1;
        self.update_kinematics();
        for i in 0..2 {
            let stops = arm::at_end_stops(&self.models[i], &self.state.arms[i].q);
            let a = &mut self.state.arms[i];
            for (joint, (&now, was)) in stops.iter().zip(&a.at_end_stop).enumerate() {
                if now && !was {
                    self.events.push(Event::EndStop {
                        arm: Arm::BOTH[i],
                        joint,
                    });
                }
            }
            a.at_end_stop = stops;
            constraint::slip_stage(
                Arm::BOTH[i],
                &mut self.state.arms[i],
                &out.grip[i],
                &self.params,
                &self.work[i].tool,
                &self.state.object.pose,
                &mut self.events,
            );
            let c = self.reach(i).is_some();
            self.state.arms[i].contact = c || self.state.arms[i].holding;
        }
    }

    /// Forward kinematics and world Jacobians of both arms for the state's q.
    pub(super) fn update_kinematics(&mut self) {
        for i in 0..2 {
            // The models carry their bases: these are world-frame results. The Jacobian goes
            // straight into `jw` (`kin.jacobian` is not kept: nothing here reads it).
            let w = &mut self.work[i];
            kinematics::jacobian6(
                &self.models[i],
                &mut w.kin,
                &self.state.arms[i].q,
                &mut w.jw,
            );
            w.tool = w.kin.end_effector();
        }
    }

    /// The handle whose bar arm `i`'s tool point is within the capture radius of (the
    /// nearest, if several), with whether the jaw is aligned with it.
    pub(super) fn reach(&self, i: usize) -> Option<Reach> {
        let op = &self.params.object;
        let o = &self.state.object.pose;
        let tool = &self.work[i].tool;
        let p = o.inverse_transform_point(&Point3::from(tool.translation.vector));
        let (handle, d) = op
            .handles
            .iter()
            .enumerate()
            .map(|(k, h)| (k, h.distance_m(&p.coords)))
            .fold((0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
        if d.is_nan() || d > op.capture_radius_m {
            return None;
        }
        let jaw = (o.rotation.inverse() * tool.rotation).to_rotation_matrix();
        let aligned = self
            .params
            .grip
            .accepts(&op.handles[handle].alignment(&jaw));
        Some(Reach { handle, aligned })
    }

    /// Grasp points relative to the object COM (world frame): the holding tool frames, or,
    /// when not holding, arm i's side handle i (Lim's grasp points).
    pub(super) fn grasp_radii(&self) -> [Vector3<f64>; 2] {
        let o = &self.state.object.pose;
        core::array::from_fn(|i| {
            let a = &self.state.arms[i];
            if a.holding {
                o.rotation * a.grasp_rel.translation.vector
            } else {
                o.rotation * self.params.object.handles[i].centre_m
            }
        })
    }
}

/// The operator's object twist for cooperative control (m/s, rad/s; world): non-finite
/// components as 0, scaled by `speed`, and the linear and angular parts each limited to the
/// controller's maximum speeds.
fn object_twist_command(v: &[f64; 6], speed: f64, cp: &ControlParams) -> Vector6<f64> {
    let part = |k: usize, max: f64| {
        let mut x = Vector3::new(
            finite_or(v[k], 0.0),
            finite_or(v[k + 1], 0.0),
            finite_or(v[k + 2], 0.0),
        ) * speed;
        if x.norm() > max {
            x *= max / x.norm();
        }
        x
    };
    let (lin, ang) = (
        part(0, cp.max_object_speed_m_s),
        part(3, cp.max_object_rate_rad_s),
    );
    Vector6::new(lin.x, lin.y, lin.z, ang.x, ang.y, ang.z)
}
