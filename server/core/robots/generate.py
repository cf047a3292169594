"""Writes the built-in robot files from the tables below (angles in degrees here, radians in the JSON)."""
import json, math, os
HERE = os.path.dirname(os.path.abspath(__file__))
r = math.radians
def j(kind="revolute", a=0.0, alpha=0.0, d=0.0, theta=0.0, lim=None, vel=None, name=None, twist=None):
    o = {}
    if name: o["name"] = name
    o["type"] = kind; o["a"] = a; o["alpha"] = r(alpha); o["d"] = d; o["theta"] = r(theta)
    if twist: o["twist_axis"] = twist
    if lim: o["limits"] = [r(lim[0]), r(lim[1])]
    if vel: o["max_velocity"] = r(vel)
    return o
L = dict(l1=0.05, l2=0.70, l3=0.56, l4=0.04, l5=0.04, l6=0.12)
models = {
 "magnum": {
  "name": "magnum",
  "source": "Lim 2005, Table 3-1 and eqs 3.1-3.9 (DH, link 5 twist about Y); joint ranges and nominal speeds from Table 1-1",
  "dh": "standard",
  "joints": [
    j(a=L["l1"], alpha=90, lim=(-25, 25), vel=20, name="swing"),
    j(a=L["l2"], alpha=0, lim=(0, 90), vel=20, name="shoulder"),
    j(a=L["l3"], alpha=0, lim=(-130, 0), vel=30, name="elbow"),
    j(a=L["l4"], alpha=-90, lim=(-35, 80), vel=30, name="pitch"),
    j(a=L["l5"], alpha=90, twist="y", lim=(-60, 60), vel=30, name="yaw"),
    j(d=L["l6"], vel=150, name="rotate"),
  ],
  "collision": {
   "source": "The drawing's shapes (web/arms.js), so what the trainee sees is what collides: each link a capsule along its link vector with the drawn tube radius (0.06, 0.045, 0.04, 0.035, 0.032, 0.03 m; the joint housings and hydraulic cylinders beside the links are not included), the last link's capsule ending inside the wrist plate (its end cap reaching 5 cm behind the tool point, where the drawn tube ends) (a 9 x 9 x 2 cm plate 5.5 cm behind the tool point, the area of the 5 cm radius disc drawn before), and two 3.5 x 1.6 x 4 cm fingers on either side of the jaw opening, centred on the tool point (their tips reach the far side of the 4 cm handle bar they close on, which sits 3 cm above the box's top face, so a jaw on a handle clears the box)",
   "link_radii_m": [0.06, 0.045, 0.04, 0.035, 0.032, 0.03],
   "last_link_end_m": [0.0, 0.0, -0.08],
   "wrist_centre_m": [0.0, 0.0, -0.055],
   "wrist_half_extents_m": [0.045, 0.045, 0.01],
   "finger_half_extents_m": [0.0175, 0.008, 0.02],
  },
  "notes": "The thesis prints no link lengths (Table 3-1 names l1..l6 only). Chosen (docs/physics.md 'Link lengths', server/core/robots/search_lengths.py): l1=0.05 (swing axis to shoulder), l2=0.70 (shoulder to elbow), l3=0.56 (elbow to pitch), l4=0.04 (pitch to yaw), l5=0.04 (yaw to rotate), l6=0.12 (rotate to jaw centre) m: the straight arm's jaw centre is 1.51 m from the swing axis, Table 1-1's reach of 1.5 m (within 1 cm), and with the studies' horizontal approach (Lim 4.3.1, pitch 90 / yaw 90) every point of the case-study workspace X 0.9-1.4 m, Z 0-0.5 m (seeds README) is reachable. The far top corner (1.4, 0.5) is 1.487 m from the swing axis, so it is reachable with a horizontal approach only if the swing-axis-to-shoulder offset plus the pitch-axis-to-jaw length l1 + l4 + l5 + l6 is at most 0.32 m at a 1.51 m reach (0.20 m at 1.50 m): hence the compact wrist (0.20 m from the pitch axis to the jaw centre). Ranges are the Table 1-1 spans (swing 50, shoulder 90, elbow 130, pitch 115, yaw 120 deg), placed so that the Table 1-1 full-extension posture q = 0 is inside and the whole workspace is reachable at the 90/90 start pose (the pitch needs 76 deg at X 0.9, Z 0): swing -25..25, shoulder 0..90 (horizontal to vertical; the straight arm lies on its lower limit), elbow -130..0 (straight at its upper limit), pitch -35..80, yaw -60..60 deg; rotate is continuous (no limits)",
 },
 "orion": {
  "name": "orion",
  "source": "Jun, Lee, Kim 2008, Table 1 (ORION 7P, standard DH, joint limits); the 'q_i (deg)' column is the twist alpha",
  "dh": "standard",
  "joints": [
    j(a=0.0711, alpha=90, lim=(-60, 60), vel=30),
    j(a=0.5664, alpha=0, lim=(-30, 90), vel=30),
    j(a=0.1346, alpha=90, lim=(-90, 30), vel=30),
    j(d=0.5004, alpha=-90, lim=(-135, 135), vel=60),
    j(alpha=90, lim=(-30, 90), vel=60),
    j(d=0.4089, alpha=0, lim=(-180, 180), vel=60),
  ],
  "notes": "Joint 3's '+90' offset of Table 1 is not applied: with it omitted the paper's example posture gives TMM 0.41 and JLM 0.09 (seeds README). Velocity limits are not in the paper: 30 deg/s (arm) and 60 deg/s (wrist) assumed.",
 },
 "rx90": {
  "name": "rx90",
  "source": "Staubli RX90 lab report (Ecole Centrale de Nantes), part II: Khalil-Kleinfinger modified DH, D3 = RL4 = 0.45 m",
  "dh": "modified",
  "joints": [
    j(alpha=0, lim=(-160, 160), vel=236),
    j(alpha=90, lim=(-137.5, 137.5), vel=200),
    j(a=0.45, alpha=0, lim=(-142.5, 142.5), vel=286),
    j(alpha=-90, d=0.45, lim=(-270, 270), vel=401),
    j(alpha=90, lim=(-105, 120), vel=320),
    j(alpha=-90, lim=(-270, 270), vel=580),
  ],
  "notes": "Limits and speeds are not in the report: representative Staubli RX90 catalogue values, for the joint-limit measure and polytopes only.",
 },
 "puma560": {
  "name": "puma560",
  "source": "PUMA 560 standard DH as in Corke, 'A robotics toolbox for MATLAB' (1996) after Armstrong et al. (1986); Kilic 2005 uses this arm but prints no table",
  "dh": "standard",
  "joints": [
    j(alpha=90, lim=(-160, 160), vel=80),
    j(a=0.4318, lim=(-45, 225), vel=80),
    j(a=0.0203, d=0.15005, alpha=-90, lim=(-225, 45), vel=80),
    j(d=0.4318, alpha=90, lim=(-110, 170), vel=150),
    j(alpha=-90, lim=(-100, 100), vel=150),
    j(lim=(-266, 266), vel=150),
  ],
  "notes": "Limits from Corke's toolbox model; velocity limits assumed (80 deg/s arm, 150 deg/s wrist).",
 },
 "pa10": {
  "name": "pa10",
  "source": "Mitsubishi PA-10 (7 DOF) standard DH as commonly published (d = 0.317, 0.45, 0.48, 0.07 m); Kilic 2005 uses this arm but prints no table",
  "dh": "standard",
  "joints": [
    j(d=0.317, alpha=-90, lim=(-177, 177), vel=57),
    j(alpha=90, lim=(-94, 94), vel=57),
    j(d=0.45, alpha=-90, lim=(-174, 174), vel=114),
    j(alpha=90, lim=(-137, 137), vel=114),
    j(d=0.48, alpha=-90, lim=(-255, 255), vel=360),
    j(alpha=90, lim=(-165, 165), vel=360),
    j(d=0.07, lim=(-255, 255), vel=360),
  ],
  "notes": "Limits and speeds as commonly quoted for the PA-10 (S1/S2 57 deg/s, S3/E1 114 deg/s, E2/W1/W2 360 deg/s).",
 },
 "planar2r": {
  "name": "planar2r",
  "source": "Lim 2005 section 2.4.2 (planar RR arm, l1 = l2 = 1)",
  "dh": "standard",
  "joints": [j(a=1.0), j(a=1.0)],
  "notes": "Unit velocity limits; no position limits.",
 },
}
for n, m in models.items():
    for jj in m["joints"]:
        if "max_velocity" not in jj: jj["max_velocity"] = 1.0
    json.dump(m, open(os.path.join(HERE, f"{n}.json"), "w"), indent=2)
    open(os.path.join(HERE, f"{n}.json"), "a").write("\n")
