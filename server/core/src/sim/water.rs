//! The medium the arms work in: air (the thesis's setting) or sea water with buoyancy,
//! quadratic (Morison-type) drag on the velocity relative to a uniform current, and added
//! mass, for the object and every link of both arms.
//!
//! # Model
//! * **Buoyancy** ρ·V·g at the centre of volume, taken at the COM (uniform bodies). Displaced
//!   volumes: a link's V = m / ρ_link from its mass and the documented mean link density
//!   ([`crate::dynamics::MAGNUM_LINK_DENSITY_KGM3`]; [`crate::dynamics::LinkInertia::volume_m3`]);
//!   the box's V = a·b·c from its dimensions (0.30 × 0.40 × 0.20 m = 0.024 m³, 24.6 kg of sea
//!   water, so the 50 kg box weighs 249 N in water).
//! * **Links** are circular cylinders along their link vector (joint origin to the next joint's
//!   origin, the last one to the tool point; lengths L read from the model, never hard-coded),
//!   of the diameter that gives the link its displaced volume, D = √(4V/(πL)). Each link is cut
//!   into [`LINK_SEGMENTS`] equal pieces; on each, at its centre x:
//!   - drag on the normal component of the relative velocity (Morison's equation for a
//!     slender cylinder, DNV-RP-C205 (2010) §6.2.1, eq. 6.1, tangential drag neglected):
//!     F = −½ρ·C_D·D·ℓ·|w|w, w = P(v − u), P = 1 − t·tᵀ (t the link axis), v = J_x·q̇,
//!     u the current, ℓ = L / [`LINK_SEGMENTS`];
//!   - added mass in the normal plane, C_A·ρ·(V / [`LINK_SEGMENTS`])·P (ibid. eq. 6.1's
//!     inertia term with C_A = 1 for a circular section);
//!   - both enter the joint equation through the point's Jacobian transpose: τ = J_xᵀF and
//!     ΔH = J_xᵀ·M_a·J_x (symmetric positive semi-definite, so H + ΔH stays SPD and the
//!     step's fixed-size LDLᵀ factor takes it unchanged).
//!
//!   Three pieces: a link turning about its own joint gets ∫₀ᴸ s·s² ds = L⁴/4 from the
//!   midpoint rule as 0.236·L⁴ (5.6 % low); one piece would give 0.125·L⁴ (50 % low).
//! * **Object** (the box, bluff body): drag per body axis on the relative velocity,
//!   F_k = −½ρ·C_D·A_k·|v_k|v_k (A_k the face normal to axis k; the usual component form for
//!   box-like ROVs and payloads, Fossen (2011) "Handbook of Marine Craft Hydrodynamics and
//!   Motion Control" §6.4), and an isotropic added mass C_A·ρ·V in translation (effective mass
//!   m + m_a; the box's 3:4:2 sides are taken as a cube's; rotational added inertia and
//!   rotational drag are neglected — the box is held or resting in every exercise).
//! * The current is uniform in space. An instructor's change does not apply at once: the
//!   flow u(t) follows the set current u_set as a critically damped second-order lag
//!   ([`Flow::advance`]), ü = (u_set − u)/τ² − 2u̇/τ with τ = [`CURRENT_TIME_CONSTANT_S`]
//!   (1.5 s: 10–90 % of a change in 5.0 s, u̇ continuous from zero, peak u̇ = Δu/(e·τ),
//!   0.61 m/s² for 0 → 2.5 m/s). A real current changes over minutes (tides); the ramp
//!   keeps the training control responsive while sparing the arms a force step that no sea
//!   produces — the 0 → 2.5 m/s step dropped a held box (issue 27). While the flow
//!   accelerates, every body in it feels the Morison inertia force (DNV-RP-C205 (2010) §6.2.1,
//!   eq. 6.1, with C_M = 1 + C_A): the Froude–Krylov force ρV·u̇ of the accelerating
//!   pressure field and the added mass's C_A·ρV·u̇ — on the box (1 + C_A)ρV·u̇, isotropic
//!   (its added mass is taken isotropic), on each link piece (1 + C_A)ρ(V/N)·P·u̇ in the
//!   normal plane (the slender-member form of eq. 6.1, tangential inertia neglected as the
//!   tangential drag is). The body's own acceleration term C_A·ρV·v̇ is the added mass
//!   already in its inertia.
//!
//! # Coefficients
//! * [`CYLINDER_DRAG`] C_D = 1.2: smooth circular cylinder, subcritical Reynolds number
//!   (Re = |v|D/ν ≈ 10⁴–10⁵ here: 0.5 m/s past a 0.11 m link), DNV-RP-C205 (2010) §6.7.1
//!   (C_D ≈ 1.2 below the drag crisis); Sumer & Fredsøe (2006) "Hydrodynamics around
//!   cylindrical structures", Fig. 2.1.
//! * [`CYLINDER_ADDED_MASS`] C_A = 1.0: circular cylinder, potential flow, DNV-RP-C205 (2010)
//!   Table D-1; Newman (1977) "Marine Hydrodynamics" §4.13 (m_a = ρπr² per unit length).
//! * [`BOX_DRAG`] C_D = 1.05: cube face-on, Hoerner (1965) "Fluid-Dynamic Drag" ch. 3
//!   (three-dimensional bluff bodies); DNV-RP-H103 (2011) App. B lists bluff 3-D bodies at
//!   1.0–1.2.
//! * [`BOX_ADDED_MASS`] C_A = 0.67: cube, DNV-RP-H103 (2011) Table A-2 (V_R = a³).
//!
//! # Integration
//! Link drag is linearly implicit (Rosenbrock–Euler): its Jacobian
//! ∂F/∂v = −½ρC_D·D·ℓ(|w|P + w·wᵀ/|w|) goes into H̃ as h·J_xᵀKJ_x next to the actuator damping,
//! so the drag term is stable at any speed. The object's drag stays explicit: its rate
//! λ = ρC_D·A·|v|/(m + m_a) is 3.8 s⁻¹ at the box's terminal speed (1.96 m/s, face-on), h·λ =
//! 0.004 ≪ 2 (explicit Euler's limit); a held box moves with the arms' much larger effective
//! mass. Neglected: the added mass's velocity-product terms (J̇q̇ of each piece) — at the
//! arms' ≤ 0.5 rad/s they are below 1 % of the added mass's share of the inertia torques.

use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};

use crate::Error;
use crate::dynamics::Inertials;
use crate::hydraulics::N_ACT;
use crate::kinematics::KinData;
use crate::model::{JointKind, Model};

/// Drag coefficient of a link (circular cylinder in cross-flow, subcritical Re): 1.2
/// (DNV-RP-C205 (2010) §6.7.1; see the module docs).
pub const CYLINDER_DRAG: f64 = 1.2;
/// Added-mass coefficient of a link (circular section): 1.0 (DNV-RP-C205 (2010) Table D-1;
/// Newman (1977) §4.13).
pub const CYLINDER_ADDED_MASS: f64 = 1.0;
/// Drag coefficient of the box, per face (cube face-on): 1.05 (Hoerner (1965) ch. 3).
pub const BOX_DRAG: f64 = 1.05;
/// Added-mass coefficient of the box (cube, reference volume a³): 0.67 (DNV-RP-H103 (2011)
/// Table A-2).
pub const BOX_ADDED_MASS: f64 = 0.67;
/// Pieces each link is cut into for drag and added mass: 3 (see the module docs for the
/// quadrature error).
pub const LINK_SEGMENTS: usize = 3;
/// Sea-water density (kg/m³): 1 025 (DNV-RP-C205 (2010) §2; 35 ‰ salinity near 10 °C).
pub const SEA_WATER_DENSITY_KGM3: f64 = 1025.0;
/// Time constant τ of the current's ramp after an instructor's change (s): 1.5 (see the
/// module docs: a critically damped second-order lag, 10–90 % in 3.36·τ = 5.0 s).
pub const CURRENT_TIME_CONSTANT_S: f64 = 1.5;
/// Largest current an instructor may set (m/s): 2.5 (≈ 5 knots; stronger than the tidal
/// streams work-class ROVs operate in, which are limited to about 1.5–2 m/s).
pub const MAX_CURRENT_M_S: f64 = 2.5;
/// Largest |heading| accepted (degrees): 360; the heading is then reduced to [0, 360).
pub const MAX_HEADING_DEG: f64 = 360.0;

/// A uniform horizontal current: speed and the direction it flows towards.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Current {
    /// Speed (m/s), 0..=[`MAX_CURRENT_M_S`].
    pub speed_m_s: f64,
    /// Direction the water flows towards (degrees), in the horizontal world plane from +x
    /// (straight ahead of the arms, away from the vehicle) towards +y (to the left arm's
    /// side), i.e. counter-clockwise seen from above; in [0, 360).
    pub heading_deg: f64,
}

impl Current {
    /// A checked current: finite speed in [0, [`MAX_CURRENT_M_S`]] and finite heading within
    /// ±[`MAX_HEADING_DEG`] (reduced to [0, 360)).
    pub fn new(speed_m_s: f64, heading_deg: f64) -> Result<Current, Error> {
        if !speed_m_s.is_finite() || !(0.0..=MAX_CURRENT_M_S).contains(&speed_m_s) {
            return Err(Error::InvalidParameter {
                what: "current speed_m_s",
                reason: format!("must be a number in [0, {MAX_CURRENT_M_S}] m/s"),
            });
        }
        if !heading_deg.is_finite() || heading_deg.abs() > MAX_HEADING_DEG {
            return Err(Error::InvalidParameter {
                what: "current heading_deg",
                reason: format!("must be a number in [-{MAX_HEADING_DEG}, {MAX_HEADING_DEG}]°"),
            });
        }
        Ok(Current {
            speed_m_s,
            heading_deg: heading_deg.rem_euclid(360.0),
        })
    }

    /// The current's velocity (m/s), world frame (horizontal).
    pub fn velocity(&self) -> Vector3<f64> {
        let a = self.heading_deg.to_radians();
        Vector3::new(a.cos(), a.sin(), 0.0) * self.speed_m_s
    }
}

/// The water's present motion (world frame): the current ramping towards the set one.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Flow {
    /// Velocity u (m/s).
    pub velocity_m_s: Vector3<f64>,
    /// Acceleration u̇ (m/s²).
    pub acceleration_m_s2: Vector3<f64>,
}

impl Flow {
    /// A current that has been flowing steadily at `current` (no acceleration).
    pub fn steady(current: &Current) -> Flow {
        Flow {
            velocity_m_s: current.velocity(),
            acceleration_m_s2: Vector3::zeros(),
        }
    }

    /// One step of `dt_s` towards the set current `set` (m/s, world): the critically damped
    /// lag ü = (u_set − u)/τ² − 2u̇/τ, τ = [`CURRENT_TIME_CONSTANT_S`], by semi-implicit Euler
    /// (dt/τ ≤ 0.007 at the 10 ms largest step: stable and within 0.5 % of the exact
    /// response). Reaches the set current without overshoot.
    pub fn advance(&mut self, set: &Vector3<f64>, dt_s: f64) {
        let tau = CURRENT_TIME_CONSTANT_S;
        let jerk_free =
            (set - self.velocity_m_s) / (tau * tau) - self.acceleration_m_s2 * (2.0 / tau);
        self.acceleration_m_s2 += jerk_free * dt_s;
        self.velocity_m_s += self.acceleration_m_s2 * dt_s;
    }
}

/// Sea water: density and current.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Water {
    /// Density (kg/m³): [`SEA_WATER_DENSITY_KGM3`].
    pub density_kgm3: f64,
    /// The current (still water by default).
    pub current: Current,
}

impl Default for Water {
    fn default() -> Self {
        Water {
            density_kgm3: SEA_WATER_DENSITY_KGM3,
            current: Current::default(),
        }
    }
}

/// Where the arms work.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Environment {
    /// In air: no buoyancy, drag or added mass (the thesis's simulations, Lim §4.2).
    #[default]
    Air,
    /// Submerged in sea water (the training default).
    Subsea(Water),
}

impl Environment {
    /// Sea water at rest ([`Water::default`]).
    pub fn subsea() -> Environment {
        Environment::Subsea(Water::default())
    }

    /// The water, if submerged.
    pub fn water(&self) -> Option<&Water> {
        match self {
            Environment::Air => None,
            Environment::Subsea(w) => Some(w),
        }
    }

    /// Fluid density for buoyancy (kg/m³): the water's, 0 in air (air's buoyancy on a
    /// 4 000 kg/m³ arm is 0.03 % of its weight and is neglected, as in the thesis).
    pub fn density_kgm3(&self) -> f64 {
        self.water().map_or(0.0, |w| w.density_kgm3)
    }

    /// `"air"` or `"subsea"`.
    pub fn name(&self) -> &'static str {
        match self {
            Environment::Air => "air",
            Environment::Subsea(_) => "subsea",
        }
    }
}

/// The medium by name, as an exercise or a request states it (`"air"` or `"subsea"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Medium {
    /// [`Environment::Air`].
    Air,
    /// [`Environment::subsea`] (still water; the instructor may set a current).
    #[default]
    Subsea,
}

impl Medium {
    /// The environment it names.
    pub fn environment(self) -> Environment {
        match self {
            Medium::Air => Environment::Air,
            Medium::Subsea => Environment::subsea(),
        }
    }
}

/// The box's translational hydrodynamics in water.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoxHydro {
    /// Displaced volume a·b·c (m³).
    pub volume_m3: f64,
    /// Added mass C_A·ρ·V (kg), isotropic.
    pub added_mass_kg: f64,
    /// ½ρ·C_D·A_k per body axis (kg/m): F_k = −coef_k·|v_k|v_k.
    pub drag_kg_m: Vector3<f64>,
    /// The current's velocity (m/s), world.
    pub current_m_s: Vector3<f64>,
    /// Morison inertia force of the accelerating current, (1 + C_A)ρV·u̇ (N, world).
    pub inertia_n: Vector3<f64>,
}

impl BoxHydro {
    /// For a box of sides `size_m` in `water` moving as `flow`.
    pub fn new(size_m: &Vector3<f64>, water: &Water, flow: &Flow) -> BoxHydro {
        let rho = water.density_kgm3;
        let volume = size_m.x * size_m.y * size_m.z;
        let faces = Vector3::new(
            size_m.y * size_m.z,
            size_m.x * size_m.z,
            size_m.x * size_m.y,
        );
        BoxHydro {
            volume_m3: volume,
            added_mass_kg: BOX_ADDED_MASS * rho * volume,
            drag_kg_m: faces * (0.5 * rho * BOX_DRAG),
            current_m_s: flow.velocity_m_s,
            inertia_n: flow.acceleration_m_s2 * ((1.0 + BOX_ADDED_MASS) * rho * volume),
        }
    }

    /// Drag force (N, world) on a box with rotation `rot` (body to world) moving at
    /// `velocity` (m/s, world): per body axis on the velocity relative to the current.
    pub fn drag(&self, rot: &Matrix3<f64>, velocity: &Vector3<f64>) -> Vector3<f64> {
        let vb = rot.transpose() * (velocity - self.current_m_s);
        let fb = Vector3::new(
            -self.drag_kg_m.x * vb.x.abs() * vb.x,
            -self.drag_kg_m.y * vb.y.abs() * vb.y,
            -self.drag_kg_m.z * vb.z.abs() * vb.z,
        );
        rot * fb
    }
}

/// One arm's hydrodynamic terms at one (q, q̇).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmHydro {
    /// Added to H̃: Σ J_xᵀ(M_a + h·K)J_x over the link pieces (added mass and the implicit
    /// part of the drag, K = −∂F/∂v).
    pub matrix: Matrix6<f64>,
    /// Drag joint torques Σ J_xᵀF at the current q̇ (N·m).
    pub torque: Vector6<f64>,
}

/// The links' drag, added mass and the accelerating current's inertia force for one arm (see
/// the module docs): `kin` holds the frames of the state's q (world frame: the model carries
/// its base), `qd` the joint rates, `flow` the water's motion, `h` the sub-step (0 gives the
/// added mass alone in `matrix`). Allocation-free.
pub fn arm_hydro(
    model: &Model,
    inertials: &Inertials,
    kin: &KinData,
    qd: &[f64; N_ACT],
    water: &Water,
    flow: &Flow,
    h: f64,
) -> ArmHydro {
    let rho = water.density_kgm3;
    let u = flow.velocity_m_s;
    let accelerating = flow.acceleration_m_s2 != Vector3::zeros();
    let mut z = [Vector3::zeros(); N_ACT];
    let mut p = [Vector3::zeros(); N_ACT];
    for k in 0..N_ACT {
        z[k] = kin.joint_frames[k].rotation * model.joints[k].axis.into_inner();
        p[k] = kin.joint_frames[k].translation.vector;
    }
    let mut out = ArmHydro {
        matrix: Matrix6::zeros(),
        torque: Vector6::zeros(),
    };
    for i in 0..N_ACT {
        let start = p[i];
        let end = if i + 1 < N_ACT {
            p[i + 1]
        } else {
            kin.tool_point
        };
        let seg = end - start;
        let len = seg.norm();
        let volume = inertials.links[i].volume_m3;
        if len < 1e-6 || volume <= 0.0 {
            // A link of no length (coincident joints) or no volume: no cylinder to load.
            continue;
        }
        let t = seg / len;
        let proj = Matrix3::identity() - t * t.transpose();
        let diameter = (4.0 * volume / (std::f64::consts::PI * len)).sqrt();
        let piece = len / LINK_SEGMENTS as f64;
        let drag = 0.5 * rho * CYLINDER_DRAG * diameter * piece;
        let added = proj * (CYLINDER_ADDED_MASS * rho * volume / LINK_SEGMENTS as f64);
        // Morison inertia force of the accelerating current on each piece, normal plane.
        let inertia = if accelerating {
            proj * flow.acceleration_m_s2
                * ((1.0 + CYLINDER_ADDED_MASS) * rho * volume / LINK_SEGMENTS as f64)
        } else {
            Vector3::zeros()
        };
        for s in 0..LINK_SEGMENTS {
            let x = start + seg * ((s as f64 + 0.5) / LINK_SEGMENTS as f64);
            // Linear Jacobian of the point x: column k ≤ i is z_k × (x − p_k) (revolute) or
            // z_k (prismatic); joints past i do not move it (their columns are zero and are
            // skipped below).
            let mut jx = [Vector3::zeros(); N_ACT];
            let mut v = -u;
            for k in 0..=i {
                jx[k] = match model.joints[k].kind {
                    JointKind::Revolute => z[k].cross(&(x - p[k])),
                    JointKind::Prismatic => z[k],
                };
                v += jx[k] * qd[k];
            }
            let w = proj * v;
            let speed = w.norm();
            let force = w * (-drag * speed) + inertia;
            let mut m3 = added;
            if speed > 0.0 {
                m3 += (proj * speed + w * w.transpose() / speed) * (drag * h);
            }
            // τ = J_xᵀF; ΔH = J_xᵀ·M₃·J_x on the (i+1)×(i+1) block, upper triangle here.
            for a in 0..=i {
                out.torque[a] += jx[a].dot(&force);
                let ma = m3 * jx[a];
                for (b, jb) in jx.iter().enumerate().take(i + 1).skip(a) {
                    out.matrix[(a, b)] += ma.dot(jb);
                }
            }
        }
    }
    for a in 0..N_ACT {
        for b in 0..a {
            out.matrix[(a, b)] = out.matrix[(b, a)];
        }
    }
    out
}
