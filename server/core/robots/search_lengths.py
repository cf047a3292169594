"""Which Magnum link lengths give Table 1-1's reach of 1.5 m and make Lim's case-study
workspace reachable at the studies' start pose? (docs/physics.md, "Link lengths"; issue 27
item 5.) Standard library only: `python3 search_lengths.py` (a few seconds).

The studies hold the tool's approach axis horizontal along +X (pitch 90°, yaw 90°,
`seaarms_core::studies`) and sweep X 0.9–1.4 m at Z 0–0.5 m (Lim §4.3.1.1–2; seeds README).
At swing 0 and yaw 0 the pitch axis then sits lw = l4 + l5 + l6 behind the tool point and
the shoulder l1 in front of the swing axis, so a tool point (X, Z) needs the wrist point
(X − l1 − lw, Z) within the shoulder–elbow pair's annulus (elbow range 130°) and the pitch
−(q2 + q3) within its range. With the reach R = l1 + l2 + l3 + lw (the straight arm's jaw
centre from the swing axis), the far top corner (1.4, 0.5) — 1.487 m from the swing axis —
needs (1.4 − a)² + 0.5² ≤ (R − a)² with a = l1 + lw, i.e.

    a ≤ (R² − 2.21) / (2R − 2.8):   0.20 m at R = 1.50 m, 0.32 m at R = 1.51 m,

so Table 1-1's reach and the workspace together ask for a compact wrist.

The studies' measure is Yoshikawa's w of the translational Jacobian (Lim eq. 3.62). At swing 0
and yaw 0 it splits into an out-of-plane part (swing lever X, yaw lever l5 + l6) and the
in-plane shoulder/elbow/pitch block, so w² = (X² + (l5 + l6)²) · Σ_{i<j} (r_i × r_j)²
(Cauchy–Binet; r_i from each in-plane axis to the tool point); the Rust studies print the same
(`cargo test -p seaarms-core --test manipulability_studies -- --nocapture`).

The search: l1 ∈ {0.05, 0.08, 0.10}, lw 0.10–0.34 m, l2 0.40–1.00 m (2 cm steps), l3 = R − l1
− l2 − lw ≥ 0.30 m, R ∈ {1.50, 1.505, 1.51} m (Table 1-1 ± 1 cm); shoulder 0..90° and elbow
−130..0° as before (q = 0, Table 1-1's full extension, stays inside), the pitch's 115° placed
(lower limit −35 … −85°) so the workspace is reachable; kept: every 1 cm grid point of the
workspace reachable. Ranked by the thesis's qualitative figures: the X-sweep maximum inside
0.9–1.4 m at Z = 0, 0.2, 0.4, 0.5 m (§4.3.1.1: "approximately 1.3m") and the Yoshikawa rising
with Z (§4.3.1.1: "As the Z coordinate was increased, the manipulability increased") — the
fraction of X (5 cm steps) where it rises over all four levels, and the peak's rise with Z.
"""
import math

R = math.radians


def frange(a, b, s):
    n = int(round((b - a) / s))
    return [a + i * s for i in range(n + 1)]


def ik(x, z, arm, lim):
    """Shoulder, elbow, pitch (rad) putting the tool at (x, z) with a horizontal approach,
    elbow up, within `lim`; or None."""
    l1, l2, l3, lw, _ = arm
    wx, wz = x - l1 - lw, z
    c3 = (wx * wx + wz * wz - l2 * l2 - l3 * l3) / (2 * l2 * l3)
    if abs(c3) > 1:
        return None
    q3 = -math.acos(c3)
    q2 = math.atan2(wz, wx) - math.atan2(l3 * math.sin(q3), l2 + l3 * math.cos(q3))
    q = (q2, q3, -q2 - q3)
    if all(lo - 1e-9 <= v <= hi + 1e-9 for v, (lo, hi) in zip(q, lim)):
        return q
    return None


def yoshikawa(x, z, q, arm):
    l1, l2, l3, lw, c = arm
    ex, ez = l2 * math.cos(q[0]), l2 * math.sin(q[0])
    px, pz = ex + l3 * math.cos(q[0] + q[1]), ez + l3 * math.sin(q[0] + q[1])
    t = (x - l1, z)
    rs, re, rp = t, (t[0] - ex, t[1] - ez), (t[0] - px, t[1] - pz)
    cr = lambda a, b: a[0] * b[1] - a[1] * b[0]
    g = cr(rs, re) ** 2 + cr(rs, rp) ** 2 + cr(re, rp) ** 2
    return math.sqrt((x * x + c * c) * g)


def workspace_ok(arm, lim):
    return all(
        ik(x, z, arm, lim) is not None
        for x in frange(0.9, 1.4, 0.01)
        for z in frange(0.0, 0.5, 0.01)
    )


def x_sweep(z, arm, lim):
    rows = []
    for x in frange(0.9, 2.0, 0.01):
        q = ik(x, z, arm, lim)
        if q is None:
            if rows:
                break
            continue
        rows.append((x, yoshikawa(x, z, q, arm)))
    return rows


def limits(lo4):
    return [(0.0, R(90)), (R(-130), 0.0), (R(lo4), R(lo4 + 115))]


LEVELS = (0.0, 0.2, 0.4, 0.5)


def figures(arm, lim):
    peaks = [max(x_sweep(z, arm, lim), key=lambda r: r[1]) for z in LEVELS]
    inside = all(0.9 < p[0] < 1.4 for p in peaks)
    xs = frange(0.9, 1.4, 0.05)
    rising = sum(
        all(a < b for a, b in zip(w, w[1:]))
        for w in ([yoshikawa(x, z, ik(x, z, arm, lim), arm) for z in LEVELS] for x in xs)
    ) / len(xs)
    return inside, rising, peaks


found = []
for reach in (1.50, 1.505, 1.51):
    for l1 in (0.05, 0.08, 0.10):
        for lw in frange(0.10, 0.34, 0.02):
            a = l1 + lw
            for l2 in frange(0.40, 1.00, 0.02):
                l3 = reach - a - l2
                if l3 < 0.30 or math.hypot(1.4 - a, 0.5) > l2 + l3:
                    continue
                arm = (l1, l2, l3, lw, max(lw - 0.04, 0.08))
                for lo4 in (-35, -45, -55, -65, -75, -85):
                    if workspace_ok(arm, limits(lo4)):
                        inside, rising, peaks = figures(arm, limits(lo4))
                        found.append((inside, rising, reach, arm, lo4, peaks))
                        break
print(f"{len(found)} arms reach the whole workspace; the best by the qualitative figures:")
for inside, rising, reach, arm, lo4, peaks in sorted(
    found, key=lambda f: (f[0], f[1], f[3][3]), reverse=True
)[:8]:
    print(
        f"  R {reach:.3f}: l1 {arm[0]:.2f} l2 {arm[1]:.2f} l3 {arm[2]:.3f} lw {arm[3]:.2f}, "
        f"pitch {lo4}..{lo4 + 115}: peak inside {inside}, rising at {rising:.0%} of X, "
        "X maxima " + " / ".join(f"{p[0]:.2f} ({p[1]:.3f})" for p in peaks)
    )

CHOSEN = (0.05, 0.70, 0.56, 0.20, 0.16)
lim = limits(-35)
inside, rising, peaks = figures(CHOSEN, lim)
print(f"shipped arm (l1 0.05, l2 0.70, l3 0.56, lw 0.20 m, pitch -35..80): workspace "
      f"{workspace_ok(CHOSEN, lim)}, X maxima " + " / ".join(f"{p[0]:.2f}" for p in peaks)
      + f", rising with Z at {rising:.0%} of X")
print("X     " + "  ".join(f"Z {z:.1f}" for z in (0, 0.1, 0.2, 0.3, 0.4, 0.5)))
for x in frange(0.9, 1.4, 0.05):
    print(f"{x:.2f}  " + "  ".join(
        f"{yoshikawa(x, z, ik(x, z, CHOSEN, lim), CHOSEN):.3f}" for z in (0, 0.1, 0.2, 0.3, 0.4, 0.5)
    ))
