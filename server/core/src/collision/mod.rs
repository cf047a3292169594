//! Collision geometry of everything the arms can touch, and the narrow phase that finds the
//! contacts, with dimforge's `parry3d-f64` (the geometric queries; the contact forces are
//! `sim`'s, see its `contact` stage and docs/physics.md "Contacts").
//!
//! # Shapes
//! * **Arm** (data beside the robot model: the `collision` section of a robot file,
//!   [`CollisionSpec`]): each link a capsule along its link vector (joint origin to the next
//!   joint's origin; the last link to a point in the tool frame), the wrist plate and the two
//!   jaw fingers boxes in the tool frame, the fingers at the jaw opening. The
//!   Magnum's values are the drawing's (web/arms.js), so what the trainee sees is what
//!   collides.
//! * **World** ([`WorldGeometry`], with the simulation's parameters): the seabed (a half-space
//!   at the seabed height), the box (a cuboid) and its two handle bars (capsules), the panel
//!   plate (a cuboid), its valve stem and T-bar (capsules; the bar turns with the valve), the
//!   hot stab (a capsule from its grip to its tip; holster and receptacle sit flush in the
//!   plate face), the vehicle's front (a cuboid behind the arm bases) and each arm's pedestal
//!   (a capsule below its base), and the other arm.
//!
//! # Queries
//! Broad phase: an axis-aligned box per shape, recomputed every step; only overlapping pairs
//! reach the narrow phase. Narrow phase: parry's GJK and, for overlapping cores, its EPA
//! (deepest point pair, normal, depth) on the shapes' polyhedral cores (a capsule's segment, a
//! box), the capsule radii added after — what [`parry3d_f64::query::contact`] runs for convex
//! shapes, but on cores (EPA on a round shape iterates towards a tolerance, and its buffers
//! grow with the iterations) and with one EPA kept warm ([`Epa`]) because that call allocates
//! a new one per penetrating pair; against the seabed [`parry3d_f64::query::contact`] with the half-space
//! first (parry 0.31.1 gets the depth wrong in the other order: its shape–half-space routine
//! passes the relative pose un-inverted to the half-space–shape one), and a link capsule
//! against the seabed is queried as its two end spheres (the deepest points of a capsule against a plane
//! are its segment's ends; one query of the whole capsule gives only one of them, and a link
//! lying on the seabed would rock between its ends).
//!
//! parry3d-f64 0.31 (the newest) works in glam types; no parry release uses our nalgebra 0.35
//! (0.23–0.25 use nalgebra 0.34, 0.26 on glam), so poses are converted at this boundary
//! ([`to_pose`], [`to_vec`]).

use nalgebra::{Isometry3, Point3, Vector3};
use parry3d_f64::bounding_volume::{Aabb, BoundingVolume};
use parry3d_f64::math::{Pose, Rotation, Vector};
use parry3d_f64::query;
use parry3d_f64::query::epa::EPA;
use parry3d_f64::query::gjk::{self, CsoPoint, GJKResult, VoronoiSimplex};
use parry3d_f64::shape::{Ball, Capsule, Cuboid, HalfSpace, Shape, SupportMap};
use serde::{Deserialize, Serialize};

use crate::Error;

/// Collision shapes of an arm (the `collision` section of a robot file). Points and sizes in
/// metres; tool-frame values are in the end-effector frame (z along the jaw, y across the
/// opening, as the drawing).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CollisionSpec {
    /// Where the numbers come from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
    /// Capsule radius of each link (one per joint), along its link vector.
    pub link_radii_m: Vec<f64>,
    /// End of the last link's capsule, tool frame (the back of the wrist plate).
    pub last_link_end_m: [f64; 3],
    /// Centre of the wrist plate, a box square to the tool z axis, tool frame.
    pub wrist_centre_m: [f64; 3],
    /// Half extents (x, y, z) of the wrist plate, tool axes.
    pub wrist_half_extents_m: [f64; 3],
    /// Half extents (x, y, z) of each finger, a box whose inner face is at ± half the jaw
    /// opening along tool y, centred on the tool point along x and z.
    pub finger_half_extents_m: [f64; 3],
}

impl CollisionSpec {
    /// One radius per joint, all sizes finite and positive (radii and half extents up to 1 m),
    /// points finite.
    pub fn check(&self, joints: usize) -> Result<(), Error> {
        let bad = |reason: &str| {
            Err(Error::InvalidModel {
                reason: format!("collision: {reason}"),
            })
        };
        if self.link_radii_m.len() != joints {
            return bad("link_radii_m needs one radius per joint");
        }
        let sizes = self
            .link_radii_m
            .iter()
            .chain(&self.wrist_half_extents_m)
            .chain(&self.finger_half_extents_m);
        for &s in sizes {
            if !(s.is_finite() && s > 0.0 && s <= 1.0) {
                return bad("radii and half sizes must be in (0, 1] m");
            }
        }
        let points = self.last_link_end_m.iter().chain(&self.wrist_centre_m);
        if points
            .into_iter()
            .any(|v| !(v.is_finite() && v.abs() <= 10.0))
        {
            return bad("points must be finite and within ±10 m");
        }
        Ok(())
    }
}

/// The part of an arm in a contact.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ArmPart {
    /// Link `i` (0-based, the link moved by joint `i`).
    Link(usize),
    /// The wrist plate behind the jaw.
    Wrist,
    /// Jaw finger 0 (−y) or 1 (+y).
    Finger(usize),
}

/// What an arm touches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Partner {
    /// The seabed.
    Seabed,
    /// The box or one of its handles.
    Object,
    /// The panel: plate, valve or hot stab.
    Panel,
    /// The vehicle's front or an arm pedestal.
    Vehicle,
    /// The other arm.
    OtherArm,
}

impl Partner {
    /// Every partner, in [`Partner::index`] order.
    pub const ALL: [Partner; 5] = [
        Partner::Seabed,
        Partner::Object,
        Partner::Panel,
        Partner::Vehicle,
        Partner::OtherArm,
    ];

    /// Index into per-partner tables ([`Partner::ALL`] order).
    pub const fn index(self) -> usize {
        match self {
            Partner::Seabed => 0,
            Partner::Object => 1,
            Partner::Panel => 2,
            Partner::Vehicle => 3,
            Partner::OtherArm => 4,
        }
    }

    /// Short name for events and logs.
    pub fn as_str(self) -> &'static str {
        match self {
            Partner::Seabed => "seabed",
            Partner::Object => "box",
            Partner::Panel => "panel",
            Partner::Vehicle => "vehicle",
            Partner::OtherArm => "other-arm",
        }
    }
}

/// Which world item a shape is (for the grasp exclusions).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Item {
    /// The box body.
    BoxBody,
    /// Box handle `k` (`ObjectParams::handles`): its bar, and a T-handle's post.
    Handle(usize),
    /// The panel plate.
    Plate,
    /// The valve stem and T-bar.
    Valve,
    /// The hot stab.
    Stab,
    /// The vehicle's front.
    Vehicle,
    /// The pedestal below arm `k`'s base.
    Pedestal(usize),
}

impl Item {
    fn partner(self) -> Partner {
        match self {
            Item::BoxBody | Item::Handle(_) => Partner::Object,
            Item::Plate | Item::Valve | Item::Stab => Partner::Panel,
            Item::Vehicle | Item::Pedestal(_) => Partner::Vehicle,
        }
    }
}

/// The fixed world geometry that is not in other parameters (sizes of the drawn handles,
/// valve, vehicle and pedestals; m). Defaults in [`WorldGeometry::standard`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorldGeometry {
    /// Handle bar radius: 0.02 (the jaws close on 0.04, `ObjectParams::handle_width_m`).
    pub handle_radius_m: f64,
    /// Radius of a T-handle's post (`grasp::Posts::Centre`): 0.015 (as drawn; thinner than
    /// the bar, so the fingers closing on the bar straddle it). The bars' lengths and axes are
    /// the handles' own (`grasp::Handle`).
    pub post_radius_m: f64,
    /// Valve stem radius: 0.012 (as drawn).
    pub valve_stem_radius_m: f64,
    /// T-bar radius: 0.015 (as drawn); its length is `ValveParams::bar_length_m`.
    pub valve_bar_radius_m: f64,
    /// Vehicle front, world frame: centre (−0.60, 0.50, 0.0) and half extents
    /// (0.35, 1.10, 0.40) — a box from x = −0.95 to −0.25 behind both arm bases, y −0.6..1.6,
    /// z −0.4..0.4 (assumed: the front of a work-class ROV's tool skid carrying the arms).
    pub vehicle_centre_m: Vector3<f64>,
    /// Half extents of the vehicle front (see `vehicle_centre_m`).
    pub vehicle_half_extents_m: Vector3<f64>,
    /// Pedestal below each arm base (as drawn): a capsule of radius 0.09 from 0.05 m to
    /// 0.35 m below the base.
    pub pedestal_radius_m: f64,
    /// Pedestal top and bottom below the base (m): (0.05, 0.35); see `pedestal_radius_m`.
    pub pedestal_span_m: [f64; 2],
}

impl WorldGeometry {
    /// The values in the field docs.
    pub fn standard() -> WorldGeometry {
        WorldGeometry {
            handle_radius_m: 0.02,
            post_radius_m: 0.015,
            valve_stem_radius_m: 0.012,
            valve_bar_radius_m: 0.015,
            vehicle_centre_m: Vector3::new(-0.60, 0.50, 0.0),
            vehicle_half_extents_m: Vector3::new(0.35, 1.10, 0.40),
            pedestal_radius_m: 0.09,
            pedestal_span_m: [0.05, 0.35],
        }
    }
}

impl Default for WorldGeometry {
    fn default() -> Self {
        Self::standard()
    }
}

/// nalgebra → parry (glam) vector.
pub fn to_vec(v: &Vector3<f64>) -> Vector {
    Vector::new(v.x, v.y, v.z)
}

/// parry (glam) → nalgebra vector.
pub fn from_vec(v: Vector) -> Vector3<f64> {
    Vector3::new(v.x, v.y, v.z)
}

/// nalgebra → parry (glam) pose.
pub fn to_pose(p: &Isometry3<f64>) -> Pose {
    let q = p.rotation.coords; // (i, j, k, w)
    Pose::from_parts(
        to_vec(&p.translation.vector),
        Rotation::from_xyzw(q.x, q.y, q.z, q.w),
    )
}

/// A convex shape of the scene: a polyhedral core with a round margin, so that the usual
/// shallow contact is GJK's closest points of the cores (exact, robust, cheap) and EPA —
/// which fails on degenerate overlaps (e.g. parallel faces of two thin boxes) — only sees
/// deep ones.
#[derive(Debug, Clone, Copy)]
pub enum Solid {
    /// Capsule (segment ends in world coordinates; its pose is the identity): a segment core
    /// with the radius as margin.
    Capsule(Capsule),
    /// Box: `full` is the box; `core` the box shrunk by `margin` on every side (a box with
    /// edges rounded by `margin`, [`box_margin`]).
    Cuboid {
        /// The whole box.
        full: Cuboid,
        /// The core.
        core: Cuboid,
        /// Rounding radius (m).
        margin: f64,
    },
}

/// Rounding of a box's edges for the narrow phase (m): three quarters of its smallest half
/// extent, at most 2 cm (a finger 1.6 cm thick: 6 mm; the box: 2 cm) — well beyond the
/// millimetre penetrations of the contacts, and small against the shapes.
pub fn box_margin(half: &Vector3<f64>) -> f64 {
    (0.75 * half.min()).min(0.02)
}

impl Solid {
    fn shape(&self) -> &dyn Shape {
        match self {
            Solid::Capsule(c) => c,
            Solid::Cuboid { full, .. } => full,
        }
    }

    /// The polyhedral core and the margin around it.
    fn core(&self) -> (&dyn SupportMap, f64) {
        match self {
            Solid::Capsule(c) => (&c.segment, c.radius),
            Solid::Cuboid { core, margin, .. } => (core, *margin),
        }
    }

    fn cuboid(half: &Vector3<f64>) -> Solid {
        let margin = box_margin(half);
        Solid::Cuboid {
            full: Cuboid::new(to_vec(half)),
            core: Cuboid::new(to_vec(&half.add_scalar(-margin))),
            margin,
        }
    }
}

/// parry's EPA (penetration depth of two convex shapes) with its buffers kept between
/// queries: `parry3d_f64::query::contact` builds a new one, which allocates, on every
/// penetrating pair; this one is warmed up when made, so the step does not allocate.
#[derive(Default)]
pub struct Epa(EPA);

impl Epa {
    /// An EPA whose buffers have grown on deep overlaps of every pair of shape kinds here.
    pub fn warm() -> Epa {
        let mut e = Epa::default();
        let shapes = [
            Solid::Capsule(Capsule::new(Vector::ZERO, Vector::new(0.4, 0.1, 0.0), 0.05)),
            Solid::cuboid(&Vector3::new(0.045, 0.045, 0.01)),
            Solid::cuboid(&Vector3::new(0.15, 0.2, 0.1)),
        ];
        for a in &shapes {
            for b in &shapes {
                for k in 0..8 {
                    let t = 0.01 * k as f64;
                    let axis = Vector::new(1.0, 2.0 + t, 3.0 - t).normalize();
                    let pose = Pose::new(Vector::new(t, 0.5 * t, -t), axis * (0.3 * k as f64));
                    let pa = Posed::new(*a, Pose::IDENTITY);
                    let pb = Posed::new(*b, pose);
                    let _ = convex_contact(&pa, &pb, &mut e);
                }
            }
        }
        e
    }
}

impl Clone for Epa {
    fn clone(&self) -> Self {
        Epa::warm()
    }
}

impl core::fmt::Debug for Epa {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("Epa")
    }
}

/// Contact of two convex shapes by parry's GJK on their polyhedral cores and, when the cores
/// overlap, its EPA (what `query::contact` runs for support maps, with a kept EPA and the
/// margins added after): (point on `a`, point on `b`, unit normal out of `a`, signed
/// distance), world frame; `None` when apart.
fn convex_contact(a: &Posed, b: &Posed, epa: &mut Epa) -> Option<(Vector, Vector, Vector, f64)> {
    let pos12 = a.pose.inv_mul(&b.pose);
    let ((g1, r1), (g2, r2)) = (a.solid.core(), b.solid.core());
    let margin = r1 + r2;
    let dir = pos12.translation.try_normalize().unwrap_or(Vector::X);
    let mut simplex = VoronoiSimplex::new();
    simplex.reset(CsoPoint::from_shapes(&pos12, g1, g2, dir));
    // Points and normal in a's frame; the core distance (negative: core penetration).
    let (p1, p2, n1, core_dist) =
        match gjk::closest_points(&pos12, g1, g2, margin, true, &mut simplex) {
            GJKResult::ClosestPoints(p1, p2, n1) => (p1, p2, n1, (p2 - p1).dot(n1)),
            GJKResult::Intersection => {
                // Cores overlap (a penetration deeper than the margins): EPA, or for two
                // boxes, whose overlap EPA may find degenerate, parry's SAT.
                if let (Solid::Cuboid { core: c1, .. }, Solid::Cuboid { core: c2, .. }) =
                    (&a.solid, &b.solid)
                {
                    let c = query::details::contact_cuboid_cuboid(&pos12, c1, c2, 0.0)?;
                    let p2 = pos12 * c.point2;
                    (c.point1, p2, c.normal1, c.dist)
                } else {
                    let (p1, p2, n1) = epa.0.closest_points(&pos12, g1, g2, &simplex)?;
                    (p1, p2, n1, (p2 - p1).dot(n1))
                }
            }
            GJKResult::NoIntersection(_) | GJKResult::Proximity(_) => return None,
        };
    let dist = core_dist - margin;
    if dist >= 0.0 {
        return None;
    }
    Some((
        a.pose * (p1 + n1 * r1),
        a.pose * (p2 - n1 * r2),
        a.pose.rotation * n1,
        dist,
    ))
}

/// A posed shape with its world bounding box.
#[derive(Debug, Clone, Copy)]
pub struct Posed {
    /// The shape.
    pub solid: Solid,
    /// Its pose (world).
    pub pose: Pose,
    /// World axis-aligned bounding box.
    pub aabb: Aabb,
}

impl Posed {
    fn new(solid: Solid, pose: Pose) -> Posed {
        let aabb = solid.shape().compute_aabb(&pose);
        Posed { solid, pose, aabb }
    }

    /// A capsule between world points `a` and `b`.
    pub fn capsule(a: &Vector3<f64>, b: &Vector3<f64>, r: f64) -> Posed {
        let (a, b) = (to_vec(a), to_vec(b));
        let m = Vector::splat(r);
        Posed {
            solid: Solid::Capsule(Capsule::new(a, b, r)),
            pose: Pose::IDENTITY,
            // Directly: parry's `compute_aabb` would first copy the capsule through the pose.
            aabb: Aabb::new(a.min(b) - m, a.max(b) + m),
        }
    }

    /// A box of half extents `half` at `pose`.
    pub fn cuboid(half: &Vector3<f64>, pose: &Isometry3<f64>) -> Posed {
        Posed::new(Solid::cuboid(half), to_pose(pose))
    }
}

/// Number of collision parts of an arm: six links, the wrist plate, two fingers.
pub const ARM_PARTS: usize = 9;

/// One arm's shapes at the current configuration.
#[derive(Debug, Clone, Copy)]
pub struct ArmShapes {
    /// The parts, in [`ArmShapes::part`] order.
    pub parts: [Posed; ARM_PARTS],
    /// The bounding box of all parts.
    pub aabb: Aabb,
}

impl ArmShapes {
    /// The arm's shapes from its joint-frame origins `origins` (world, 6), the tool pose
    /// `tool` (world) and the jaw opening (m).
    pub fn new(
        spec: &CollisionSpec,
        origins: &[Vector3<f64>; 6],
        tool: &Isometry3<f64>,
        jaw_opening_m: f64,
    ) -> ArmShapes {
        let tp = |p: &[f64; 3]| (tool * Point3::new(p[0], p[1], p[2])).coords;
        let last_end = tp(&spec.last_link_end_m);
        let link = |i: usize| {
            let b = if i + 1 < 6 { origins[i + 1] } else { last_end };
            Posed::capsule(&origins[i], &b, spec.link_radii_m[i])
        };
        let c = spec.wrist_centre_m;
        let wrist = Posed::cuboid(
            &Vector3::from(spec.wrist_half_extents_m),
            &(tool * Isometry3::translation(c[0], c[1], c[2])),
        );
        let h = Vector3::from(spec.finger_half_extents_m);
        let finger = |side: f64| {
            let y = side * (0.5 * jaw_opening_m.max(0.0) + h.y);
            Posed::cuboid(&h, &(tool * Isometry3::translation(0.0, y, 0.0)))
        };
        let parts = [
            link(0),
            link(1),
            link(2),
            link(3),
            link(4),
            link(5),
            wrist,
            finger(-1.0),
            finger(1.0),
        ];
        let aabb = parts[1..]
            .iter()
            .fold(parts[0].aabb, |acc, p| acc.merged(&p.aabb));
        ArmShapes { parts, aabb }
    }

    /// Placeholder shapes (all at the origin), to be overwritten.
    pub fn empty() -> ArmShapes {
        let p = Posed::capsule(&Vector3::zeros(), &Vector3::zeros(), 0.0);
        ArmShapes {
            parts: [p; ARM_PARTS],
            aabb: p.aabb,
        }
    }

    /// What part index `k` is.
    pub fn part(k: usize) -> ArmPart {
        match k {
            0..6 => ArmPart::Link(k),
            6 => ArmPart::Wrist,
            _ => ArmPart::Finger(k - 7),
        }
    }
}

/// A world obstacle at the current step.
#[derive(Debug, Clone, Copy)]
pub struct Obstacle {
    /// What it is.
    pub item: Item,
    /// Its shape.
    pub shape: Posed,
}

/// Obstacles of the world (not the seabed, not the arms): at most the box, two handles, the
/// panel plate, valve stem and bar, the stab, the vehicle and two pedestals.
pub const MAX_OBSTACLES: usize = 10;

/// The world's obstacles at the current step.
#[derive(Debug, Clone, Copy)]
pub struct World {
    /// Seabed height (m).
    pub seabed_z_m: f64,
    /// The obstacles, `len` of them.
    pub obstacles: [Obstacle; MAX_OBSTACLES],
    /// How many obstacles are set.
    pub len: usize,
}

impl World {
    /// An empty world over the seabed at `seabed_z_m`.
    pub fn new(seabed_z_m: f64) -> World {
        let blank = Obstacle {
            item: Item::Vehicle,
            shape: Posed::capsule(&Vector3::zeros(), &Vector3::zeros(), 0.0),
        };
        World {
            seabed_z_m,
            obstacles: [blank; MAX_OBSTACLES],
            len: 0,
        }
    }

    /// Adds an obstacle (ignored beyond [`MAX_OBSTACLES`]).
    pub fn push(&mut self, item: Item, shape: Posed) {
        if self.len < MAX_OBSTACLES {
            self.obstacles[self.len] = Obstacle { item, shape };
            self.len += 1;
        }
    }

    /// The obstacles set.
    pub fn obstacles(&self) -> &[Obstacle] {
        &self.obstacles[..self.len]
    }
}

/// A contact found by the narrow phase, arm-side.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Touch {
    /// The arm's part.
    pub part: ArmPart,
    /// What it touches.
    pub partner: Partner,
    /// The world item (`None` for the seabed and the other arm).
    pub item: Option<Item>,
    /// The other arm's part (arm–arm contacts only).
    pub other_part: Option<ArmPart>,
    /// Deepest point of the arm's part inside the partner (world, m).
    pub point_arm: Vector3<f64>,
    /// Deepest point of the partner inside the arm's part (world, m).
    pub point_other: Vector3<f64>,
    /// Unit normal pointing from the partner into the arm (the direction the contact pushes
    /// the arm).
    pub normal: Vector3<f64>,
    /// Penetration depth (m, > 0).
    pub depth_m: f64,
}

/// parry's contact of `a` (the arm's part) and `b`, as a [`Touch`] when they overlap.
fn touch(
    a: &Posed,
    b: &Posed,
    epa: &mut Epa,
    part: ArmPart,
    partner: Partner,
    item: Option<Item>,
) -> Option<Touch> {
    if !a.aabb.intersects(&b.aabb) {
        return None;
    }
    let (p1, p2, n1, dist) = convex_contact(a, b, epa)?;
    if !(dist < 0.0 && n1.is_finite()) {
        return None;
    }
    // n1 points out of the arm's part towards the partner.
    Some(Touch {
        part,
        partner,
        item,
        other_part: None,
        point_arm: from_vec(p1),
        point_other: from_vec(p2),
        normal: -from_vec(n1),
        depth_m: -dist,
    })
}

/// Contacts of one arm's part `k` with the seabed, pushed to `out`.
fn seabed_touches(s: &Posed, k: usize, seabed_z: f64, out: &mut impl FnMut(Touch)) {
    if s.aabb.mins.z >= seabed_z {
        return;
    }
    let plane = HalfSpace::new(Vector::Z);
    let plane_pose = Pose::translation(0.0, 0.0, seabed_z);
    let part = ArmShapes::part(k);
    // The half-space goes first: parry 0.31.1's shape–half-space order passes the relative
    // pose un-inverted to the half-space–shape routine (wrong depths; tests/collisions.rs).
    let mut query_one = |shape: &dyn Shape, pose: &Pose| {
        if let Ok(Some(c)) = query::contact(&plane_pose, &plane, pose, shape, 0.0)
            && c.dist < 0.0
        {
            out(Touch {
                part,
                partner: Partner::Seabed,
                item: None,
                other_part: None,
                point_arm: from_vec(c.point2),
                point_other: from_vec(c.point1),
                normal: Vector3::z(),
                depth_m: -c.dist,
            });
        }
    };
    match &s.solid {
        Solid::Capsule(c) => {
            let ball = Ball::new(c.radius);
            for end in [c.segment.a, c.segment.b] {
                query_one(&ball, &Pose::from_translation(end));
            }
        }
        other => query_one(other.shape(), &s.pose),
    }
}

/// Which (part, item) pairs an arm's contacts skip: the jaw on what it grasps or is about to.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Exclusions {
    /// The arm's index: its first two links skip its own pedestal (they are mounted on it).
    pub arm: usize,
    /// The jaw (wrist and fingers) skips the whole box and its handles (the arm holds it).
    pub jaw_box: bool,
    /// The jaw skips handle `k` (it is closing on it).
    pub jaw_handle: [bool; crate::grasp::N_HANDLES],
    /// The jaw skips the valve (held, or the fingers within its capture radius).
    pub jaw_valve: bool,
    /// The jaw skips the stab (held, or the fingers within its capture radius).
    pub jaw_stab: bool,
}

impl Exclusions {
    fn skip(&self, part: ArmPart, item: Item) -> bool {
        let jaw = matches!(part, ArmPart::Wrist | ArmPart::Finger(_));
        match item {
            Item::BoxBody => jaw && self.jaw_box,
            Item::Handle(k) => jaw && (self.jaw_box || self.jaw_handle[k]),
            Item::Valve => jaw && self.jaw_valve,
            Item::Stab => jaw && self.jaw_stab,
            Item::Pedestal(k) => k == self.arm && matches!(part, ArmPart::Link(0 | 1)),
            Item::Plate | Item::Vehicle => false,
        }
    }
}

/// Every contact of `arm` with the seabed and the world's obstacles (not the other arm),
/// passed to `out`.
pub fn world_touches(
    arm: &ArmShapes,
    world: &World,
    ex: &Exclusions,
    epa: &mut Epa,
    mut out: impl FnMut(Touch),
) {
    for (k, s) in arm.parts.iter().enumerate() {
        seabed_touches(s, k, world.seabed_z_m, &mut out);
    }
    for o in world.obstacles() {
        if !arm.aabb.intersects(&o.shape.aabb) {
            continue;
        }
        for (k, s) in arm.parts.iter().enumerate() {
            let part = ArmShapes::part(k);
            if ex.skip(part, o.item) {
                continue;
            }
            if let Some(t) = touch(s, &o.shape, epa, part, o.item.partner(), Some(o.item)) {
                out(t);
            }
        }
    }
}

/// Every contact between the two arms, as (left's touch, right's touch) with opposite normals.
pub fn arm_touches(a: &ArmShapes, b: &ArmShapes, epa: &mut Epa, mut out: impl FnMut(Touch, Touch)) {
    if !a.aabb.intersects(&b.aabb) {
        return;
    }
    for (ka, sa) in a.parts.iter().enumerate() {
        if !sa.aabb.intersects(&b.aabb) {
            continue;
        }
        for (kb, sb) in b.parts.iter().enumerate() {
            let (pa, pb) = (ArmShapes::part(ka), ArmShapes::part(kb));
            if let Some(mut t) = touch(sa, sb, epa, pa, Partner::OtherArm, None) {
                t.other_part = Some(pb);
                let mirrored = Touch {
                    part: pb,
                    other_part: Some(pa),
                    point_arm: t.point_other,
                    point_other: t.point_arm,
                    normal: -t.normal,
                    ..t
                };
                out(t, mirrored);
            }
        }
    }
}
