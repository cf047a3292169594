//! The per-arm stages of the step, each a function of one arm's parameters and state: the
//! jaw, the operator's valve commands, the rigid-body terms held over the step, and within a
//! sub-step the chamber pressures, the free joint acceleration and the integration.

use nalgebra::{Isometry3, Matrix6, Point3, Vector6};

use super::contact::ArmLoad;
use super::{ArmInput, ArmParams, ArmState, ArmWork, StepParams, water};
use crate::control::{self, ControlParams};
use crate::dynamics;
use crate::finite_or;
use crate::grasp::ObjectParams;
use crate::hydraulics::{self, HydraulicParams, JawParams, N_ACT};
use crate::linalg::Ldlt;
use crate::model::Model;
use crate::panel::ToolLoad;

/// Overtravel beyond a joint limit at which q is clamped (rad): 0.1.
const HARD_STOP_RAD: f64 = 0.1;
/// How far past the grip width a jaw opens before it lets go (m): 0.002.
pub(super) const RELEASE_GAP_M: f64 = 0.002;

/// One arm's terms computed once per step and held over its sub-steps.
#[derive(Debug, Clone, Copy)]
pub(super) struct ArmTerms {
    /// LDLᵀ factor of H̃ = H + h·D (+ h·d_stop + h²·k_stop on a joint past its limit), the
    /// mass matrix with the implicit damping and end stops; `None` if not positive definite
    /// (then the arm's joints do not accelerate).
    pub(super) factor: Option<Ldlt<N_ACT>>,
    /// C(q, q̇)q̇ + G(q) (buoyancy included) less the links' drag torques at the step's q̇.
    pub(super) bias: Vector6<f64>,
    /// Viscous actuator damping D (K_damp·Ĵ²), treated implicitly.
    pub(super) damp: [f64; N_ACT],
    /// Actuator coordinate x, lever Ĵ and joint angle q at the start of the step; within the
    /// step x = x₀ + Ĵ·(q − q₀) (the linkage curvature changes x by < 1 µm over 1 ms).
    pub(super) x0: [f64; N_ACT],
    /// Ĵ = dx/dq at the start of the step.
    pub(super) jhat: [f64; N_ACT],
    /// q at the start of the step.
    pub(super) q0: [f64; N_ACT],
    /// Z = L̃⁻¹Jᵀ with H̃ = L̃L̃ᵀ, for a holding arm (zero otherwise): J·H̃⁻¹·Jᵀ = ZᵀZ and
    /// H̃⁻¹Jᵀf = L̃⁻ᵀ(Zf).
    pub(super) z: Matrix6<f64>,
    /// Tool-point J̇q̇ (linear; angular), world frame.
    pub(super) jdqd: Vector6<f64>,
    /// Fault-adjusted supply pressure (Pa).
    pub(super) supply_pa: f64,
    /// Fault-adjusted bulk modulus (Pa).
    pub(super) bulk_modulus_pa: f64,
    /// Fault-adjusted cross-piston leakage per actuator (m³/s per Pa).
    pub(super) leak: [f64; N_ACT],
    /// Joint torques of a held panel item's load, Jᵀ·(F − h·K·J·q̇) (the linearly implicit
    /// form; its h·JᵀCJ + h²·JᵀKJ and lumped mass are in H̃), and of the contacts; `None`
    /// without either.
    pub(super) ext: Option<Vector6<f64>>,
    /// H̃ itself (what `factor` factors).
    pub(super) matrix: Matrix6<f64>,
}

/// A handle within reach of a jaw: its index and whether the jaw is aligned with it
/// ([`crate::grasp::Alignment`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Reach {
    /// Index into [`ObjectParams::handles`].
    pub(super) handle: usize,
    /// The jaw lies within the alignment tolerances of the bar.
    pub(super) aligned: bool,
}

/// Stage 1 (per arm): the jaw opens or closes at its rated speed (`cmd` ∈ [−1, 1], already
/// speed-scaled), stops on the bar when it closes on a handle it is aligned with, and the
/// grasp is taken (closing on it) or released (opened 2 mm past the bar). `reach`: the handle
/// whose bar the tool point is within the capture radius of (the contact), if any; a jaw not
/// aligned with it closes past it without taking it. `tool`, `object`: world poses. A jaw
/// that lost the handle by slipping takes it again only after opening past it.
#[allow(clippy::too_many_arguments)]
pub(super) fn update_jaw(
    a: &mut ArmState,
    jaw: &JawParams,
    op: &ObjectParams,
    reach: Option<Reach>,
    cmd: f64,
    tool: &Isometry3<f64>,
    object: &Isometry3<f64>,
    dt: f64,
) {
    // A holding jaw is closed on its bar whether or not the tool point is still within the
    // capture radius of it (a slipping bar slides in the jaw).
    let seat = a.holding || reach.is_some_and(|r| r.aligned);
    let was_open_enough = a.jaw_opening_m >= op.handle_width_m - 1e-9;
    let stop = if seat && was_open_enough {
        op.handle_width_m
    } else {
        0.0
    };
    a.jaw_opening_m = (a.jaw_opening_m + cmd * jaw.speed_m_s * dt).clamp(stop, jaw.max_opening_m);
    let closed_on_handle = seat && was_open_enough && a.jaw_opening_m <= op.handle_width_m + 1e-9;
    a.clamp_force_n = clamp_force(a.clamp_force_n, jaw, closed_on_handle, cmd);
    if a.grip.lost && a.jaw_opening_m > op.handle_width_m + RELEASE_GAP_M {
        a.grip.lost = false;
    }
    if let (false, false, true, true, Some(r)) =
        (a.holding, a.grip.lost, closed_on_handle, cmd < 0.0, reach)
    {
        a.holding = true;
        a.grasp_rel = object.inverse() * tool;
        let centre = op.handles[r.handle].centre_m;
        a.grip.grasped(
            r.handle,
            (a.grasp_rel.inverse() * Point3::from(centre)).coords,
        );
    } else if a.holding && a.jaw_opening_m > op.handle_width_m + RELEASE_GAP_M {
        a.holding = false;
        a.contact_wrench = [0.0; 6];
    }
    a.contact = reach.is_some() || a.holding;
}

/// The jaw's clamp force (N) after a step with command `cmd`, from `current`: while closed on
/// a grip and closing, the rated clamp force (Lim Table 1-1) times the command, never
/// decreasing while the command holds; 0 when not closed on a grip or opening.
pub(super) fn clamp_force(current: f64, jaw: &JawParams, closed_on: bool, cmd: f64) -> f64 {
    if closed_on && cmd < 0.0 {
        jaw.clamp_force_n * (-cmd).min(1.0).max(current / jaw.clamp_force_n)
    } else if !closed_on || cmd > 0.0 {
        0.0
    } else {
        current
    }
}

/// Stage 2 outside cooperative control (per arm): the operator's valve commands (open loop),
/// or, when the input carries a joint-velocity reference (clamped to ±2× the nominal speeds;
/// Cartesian mode), the joint servo's — or, in the closed chain, rate control. `speed` is the
/// validated speed scale. `chain`: both jaws hold the object (the chain arms–object is
/// closed); then `held_share_n` is the upward force (N, world z) this arm's jaw is taken to
/// carry of the object (half its weight in the medium, the equal share of eq. 3.46).
///
/// **Rate control in the closed chain.** Each valve opens by what moves its joint at the
/// reference rate in steady state against the joint's static load
/// ([`hydraulics::steady_opening`]; the load: gravity and buoyancy of the arm, G(q) by RNEA,
/// plus Jᵀ·w with w the arm's last contact wrench on the object — the equal share of the
/// weight before there is one), and the servo's reference follows the arm, so no position
/// loop acts: the two arms cannot wind the chain up against each other (two position loops
/// through one rigid object integrate any disagreement into pressure, [`control::joint_servo`]).
/// A zero reference centres the valves, which lock the cylinders (eqs 3.49–3.50). With the
/// measured load the valve delivers the commanded flow whatever the load, as a
/// pressure-compensated proportional valve does, so the two arms move as commanded and the
/// chain keeps whatever internal force it had. With the model's equal share instead (the
/// first design) each arm's rate erred by its load's difference from the share, and that
/// mismatch wound the chain up until the valves' droop (eq. 3.48) balanced it: on the
/// restored arm (issue 27 item 5), a pair lifted in joint mode (406 N locked in) then moved
/// up at 4 mm/s in Cartesian mode in air reached 922 N and let go at 53 s; with the measured
/// load it stays at 380–400 N for the 60 s (held_load_stays_held.rs).
/// Measured, two free Magnum arms rate-commanded 4 mm/s up: with q̇_ref/q̇_nominal alone they
/// rose at 4.4 mm/s and drifted 2 mm towards each other in 20 s (the orifice areas differ by
/// the rod and the loads by joint); with the steady inverse, 3.99 and 4.01 mm/s, 0.16 mm.
#[allow(clippy::too_many_arguments)]
pub(super) fn operator_spools(
    a: &mut ArmState,
    input: &ArmInput,
    model: &Model,
    ap: &ArmParams,
    sp: &StepParams,
    work: &mut ArmWork,
    speed: f64,
    cp: &ControlParams,
    chain: bool,
    held_share_n: f64,
) -> [f64; N_ACT] {
    let hp = &ap.hydraulics;
    let nominal: [f64; N_ACT] = core::array::from_fn(|j| hp.actuators[j].nominal_speed_rad_s);
    match input.joint_velocity_ref {
        Some(r) => {
            if !a.servo_active {
                a.servo_ref = a.q;
                a.servo_active = true;
            }
            let qd_ref: [f64; N_ACT] = core::array::from_fn(|j| {
                (finite_or(r[j], 0.0) * speed).clamp(-2.0 * nominal[j], 2.0 * nominal[j])
            });
            if chain {
                a.servo_ref = a.q;
                rate_control(a, &qd_ref, model, ap, sp, work, held_share_n)
            } else {
                control::joint_servo(&qd_ref, &a.q, &mut a.servo_ref, &nominal, sp.dt_s, cp)
            }
        }
        None => {
            a.servo_active = false;
            let v: [f64; N_ACT] =
                core::array::from_fn(|j| finite_or(input.valves[j], 0.0).clamp(-1.0, 1.0));
            control::open_loop(&v, speed)
        }
    }
}

/// The closed chain's rate control ([`operator_spools`]): per joint the steady opening for
/// q̇_ref against the static load G(q) + Jᵀ·w (the arm's contact wrench; J_zᵀ·`held_share_n`
/// before the first) (`work` holds the kinematics of
/// the state's q; its dynamics scratch is reused). Zero for a zero reference (no RNEA then).
fn rate_control(
    a: &ArmState,
    qd_ref: &[f64; N_ACT],
    model: &Model,
    ap: &ArmParams,
    sp: &StepParams,
    work: &mut ArmWork,
    held_share_n: f64,
) -> [f64; N_ACT] {
    if qd_ref.iter().all(|v| *v == 0.0) {
        return [0.0; N_ACT];
    }
    let mut load = [0.0; N_ACT];
    dynamics::rnea(
        model,
        &ap.inertials,
        &work.kin,
        &[0.0; N_ACT],
        &[0.0; N_ACT],
        &sp.gravity,
        sp.environment.density_kgm3(),
        &mut load,
        &mut work.dynd,
    );
    let hp = &ap.hydraulics;
    let supply = ap.faults.supply_pa(hp);
    core::array::from_fn(|j| {
        let act = &hp.actuators[j];
        let (_, jh) = act.linkage.coordinate(a.q[j]);
        // The jaw's load: the arm's last contact wrench on the object (Jᵀ·w), the equal
        // share of the weight before the first one.
        let w = Vector6::from(a.contact_wrench);
        let tau = if w.iter().any(|v| *v != 0.0) {
            load[j] + (work.jw.column(j)).dot(&w)
        } else {
            load[j] + work.jw[(2, j)] * held_share_n
        };
        if jh == 0.0 {
            return 0.0;
        }
        hydraulics::steady_opening(act, supply, hp.return_pa, jh * qd_ref[j], tau / jh)
    })
}

/// Stage 4 (per arm): H, C q̇ + G and J̇q̇ in one pass over the links (eq. 3.38, world frame,
/// [`dynamics::step_terms`]), the actuator linkages, and the factor of H̃ with the implicit
/// damping and end stops. `work` holds the kinematics of the state's q; `flow` is the water's
/// motion (unused in air); `h` is the sub-step;
/// `load`: a held panel item's load on the jaw, linearly implicit (h·JᵀCJ + h²·JᵀKJ and the
/// lumped mass m·J_vᵀJ_v in H̃, Jᵀ·(F − h·K·J·q̇) on the right-hand side). The contacts
/// come after, from this factor ([`add_contacts`]).
#[allow(clippy::too_many_arguments)]
pub(super) fn arm_terms(
    model: &Model,
    ap: &ArmParams,
    sp: &StepParams,
    work: &ArmWork,
    a: &ArmState,
    flow: &water::Flow,
    h: f64,
    load: Option<&ToolLoad>,
) -> ArmTerms {
    let rho = sp.environment.density_kgm3();
    let terms =
        dynamics::step_terms::<N_ACT>(model, &ap.inertials, &work.kin, &a.qd, &sp.gravity, rho);
    let hp = &ap.hydraulics;
    let mut out = ArmTerms {
        factor: None,
        bias: Vector6::zeros(),
        damp: [0.0; N_ACT],
        x0: [0.0; N_ACT],
        jhat: [0.0; N_ACT],
        q0: a.q,
        z: Matrix6::zeros(),
        jdqd: Vector6::from(terms.tool_bias),
        supply_pa: ap.faults.supply_pa(hp),
        bulk_modulus_pa: ap.faults.bulk_modulus_pa(hp),
        leak: core::array::from_fn(|j| ap.faults.leak_m3_s_pa(j)),
        ext: None,
        matrix: Matrix6::zeros(),
    };
    // H̃ = H + h·(damping, end stops) on the diagonal.
    let mut m = terms.mass_matrix;
    for r in 0..N_ACT {
        let act = &hp.actuators[r];
        let (x, jh) = act.linkage.coordinate(a.q[r]);
        out.x0[r] = x;
        out.jhat[r] = jh;
        out.damp[r] = act.damping * jh * jh;
        m[(r, r)] += h * out.damp[r];
        if end_stop_penetration(a.q[r], model.joints[r].limits) != 0.0 {
            // End stop engaged at the start of the step: implicit spring-damper.
            m[(r, r)] += h * sp.stop_damping + h * h * sp.stop_stiffness;
        }
        out.bias[r] = terms.bias[r];
    }
    if let Some(w) = sp.environment.water() {
        // The links' added mass and the linearly implicit part of their drag into H̃, the
        // drag at the current q̇ onto the right-hand side ([`water::arm_hydro`]).
        let hydro = water::arm_hydro(model, &ap.inertials, &work.kin, &a.qd, w, flow, h);
        m += hydro.matrix;
        out.bias -= hydro.torque;
    }
    if let Some(l) = load {
        let j = &work.jw;
        let jv = j.fixed_rows::<3>(0);
        m += j.transpose() * (l.damping * h + l.stiffness * (h * h)) * j
            + jv.transpose() * jv * l.mass_kg;
        let qd = Vector6::from(a.qd);
        out.ext = Some(j.transpose() * (l.wrench - l.stiffness * (j * qd) * h));
    }
    out.matrix = m;
    out.factor = Ldlt::factor(&m);
    if let (Some(f), true) = (&out.factor, a.holding) {
        // Only a holding arm enters the constraint solve.
        out.z = f.forward_columns(&work.jw.transpose());
    }
    out
}

/// Per joint: `q` past its limits (at its end stop; [`super::Event::EndStop`]).
pub(super) fn at_end_stops(model: &Model, q: &[f64; N_ACT]) -> [bool; N_ACT] {
    core::array::from_fn(|j| end_stop_penetration(q[j], model.joints[j].limits) != 0.0)
}

/// Stage 5b (per arm in contact): the contacts' implicit terms into H̃ (`contact.rs`: their
/// h·(c + h·k)·J_pᵀnnᵀJ_p and friction damping) and onto the right-hand side, and the factor
/// (and Z, for a holding arm, whose tool Jacobian is `jw`) again.
pub(super) fn add_contacts(t: &mut ArmTerms, load: &ArmLoad, jw: &Matrix6<f64>, holding: bool) {
    t.matrix += load.matrix;
    t.ext = Some(t.ext.unwrap_or_else(Vector6::zeros) + load.torque);
    t.factor = Ldlt::factor(&t.matrix);
    t.z = match (&t.factor, holding) {
        (Some(f), true) => f.forward_columns(&jw.transpose()),
        _ => Matrix6::zeros(),
    };
}

/// How far `q` is past its limits (rad; negative below the lower one), 0 within them.
fn end_stop_penetration(q: f64, limits: [f64; 2]) -> f64 {
    if q < limits[0] {
        q - limits[0]
    } else if q > limits[1] {
        q - limits[1]
    } else {
        0.0
    }
}

/// Sub-step, per arm: every actuator's chamber pressures by backward Euler
/// ([`hydraulics::update_chambers`], eqs 3.48–3.50, 3.56) at the arm's current q, q̇.
/// Returns which actuators have a relief valve open.
pub(super) fn update_pressures(
    a: &mut ArmState,
    hp: &HydraulicParams,
    t: &ArmTerms,
    h: f64,
) -> [bool; N_ACT] {
    core::array::from_fn(|j| {
        let jh = t.jhat[j];
        let x = t.x0[j] + jh * (a.q[j] - t.q0[j]);
        hydraulics::update_chambers(
            &hp.actuators[j],
            hp,
            t.supply_pa,
            t.bulk_modulus_pa,
            t.leak[j],
            a.spool[j],
            x,
            jh * a.qd[j],
            h,
            &mut a.p_in[j],
            &mut a.p_out[j],
        )
        .relief_open
    })
}

/// Sub-step, per arm: the joint acceleration without contact forces,
/// q̈ = H̃⁻¹(T − Cq̇ − G − Dq̇ − end stops) with the actuator torques T = Ĵ·(A_I P_I − A_O P_O)
/// (eqs 3.52–3.54); also records the actuator torques net of damping in `a.torque`.
pub(super) fn free_acceleration(
    a: &mut ArmState,
    model: &Model,
    hp: &HydraulicParams,
    t: &ArmTerms,
    sp: &StepParams,
) -> Vector6<f64> {
    let mut rhs = Vector6::zeros();
    for j in 0..N_ACT {
        let act = &hp.actuators[j];
        let torque = t.jhat[j] * (act.area_in * a.p_in[j] - act.area_out * a.p_out[j]);
        a.torque[j] = torque - t.damp[j] * a.qd[j];
        rhs[j] = torque - t.bias[j] - t.damp[j] * a.qd[j];
        let pen = end_stop_penetration(a.q[j], model.joints[j].limits);
        if pen != 0.0 {
            rhs[j] -= sp.stop_stiffness * pen + sp.stop_damping * a.qd[j];
        }
    }
    if let Some(e) = &t.ext {
        rhs += e;
    }
    match &t.factor {
        Some(f) => f.solve(&rhs),
        None => Vector6::zeros(),
    }
}

/// Sub-step, per arm: semi-implicit (symplectic) Euler, q̇ += h·q̈ then q += h·q̇, with a hard
/// backstop [`HARD_STOP_RAD`] beyond the elastic end stop (never reached in normal use) that
/// keeps q bounded whatever happens.
pub(super) fn integrate(a: &mut ArmState, model: &Model, qdd: &Vector6<f64>, h: f64) {
    for j in 0..N_ACT {
        a.qd[j] += h * qdd[j];
        a.q[j] += h * a.qd[j];
        let lim = model.joints[j].limits;
        if a.q[j] < lim[0] - HARD_STOP_RAD {
            a.q[j] = lim[0] - HARD_STOP_RAD;
            a.qd[j] = a.qd[j].max(0.0);
        } else if a.q[j] > lim[1] + HARD_STOP_RAD {
            a.q[j] = lim[1] + HARD_STOP_RAD;
            a.qd[j] = a.qd[j].min(0.0);
        }
    }
}
