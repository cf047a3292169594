"""Which Magnum link lengths put Lim's §4.3 maxima where the thesis says? (docs/physics.md,
"Link lengths"; issue 17 item 4.) Standard library only: `python3 search_lengths.py`.

The studies' measure is Yoshikawa's w of the translational Jacobian (Lim eq. 3.62) with the
tool's approach axis held horizontal along +X (pitch 90°, yaw 90°, `seaarms_core::studies`).
At swing 0 and yaw 0 the Jacobian splits into an out-of-plane part (swing lever X, yaw lever
l5 + l6, both along Y; rotate moves the tool point not at all) and the in-plane part of
shoulder, elbow and pitch (lever vectors r_s, r_e, r_p from each axis to the tool point), so

    w² = (X² + (l5 + l6)²) · Σ_{i<j} (r_i × r_j)²      (Cauchy–Binet on the 2×3 block)

with the elbow-up branch of the closed-form IK (Lim eqs 3.10–3.19 in the plane) and the joint
ranges of Table 1-1 (spans 90° / 130° / 115°) placed as given. The first two lines printed
check this against the Rust studies (`cargo test -p seaarms-core --test manipulability_studies
-- --nocapture`): the shipped arm (l2 0.60, l3 0.40, lw 0.51 m) gives X-sweep maxima 1.33 /
1.32 / 1.29 / 1.27 m and the Z-sweep maximum at X = 1.4 m at Z = 0.40 m; the first arm we
shipped (l2 0.56, l3 0.50, lw 0.34 m) gave 1.23 / 1.23 / 1.19 / 1.16 m and 0.14 m.

Then three searches (X-sweep from 0.9 m, Z-sweep from 0 m, 1 cm steps; a sweep ends at the
first unreachable row after a reachable one, as the Rust studies do):
(only arms whose Z-sweeps at X = 0.9 … 1.3 m have rows count: the thesis sweeps them)
  1. reach from the shoulder l2 + l3 + lw = 1.5 m (lw = l4 + l5 + l6, pitch axis to jaw
     centre): the best Z-sweep maximum at X = 1.4 m among arms whose X-sweep maxima are all in
     1.3 ± 0.05 m;
  2. the reach free (1.40–1.70 m): the arms meeting both figures (X maxima in 1.3 ± 0.05 m, Z
     maximum at X = 1.4 m in 0.42 ± 0.05 m), and their shortest reach;
  3. a 1 cm grid near the shortest (l1 0.10 m, reach from the shoulder 1.48–1.51 m): the arms
     with the largest margin — the shipped arm's l2 0.60, l3 0.40, lw 0.51 m is among them.
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


def sweep(points, arm, lim):
    rows = []
    for x, z in points:
        q = ik(x, z, arm, lim)
        if q is None:
            if rows:
                break
            continue
        rows.append(((x, z), yoshikawa(x, z, q, arm)))
    return rows


def maxima(arm, lim):
    """X-sweep maxima at Z = 0, 0.2, 0.4, 0.5 and the Z-sweep maximum at X = 1.4 (m)."""
    xs = []
    for z in (0.0, 0.2, 0.4, 0.5):
        rows = sweep([(x, z) for x in frange(0.9, 2.0, 0.01)], arm, lim)
        xs.append(max(rows, key=lambda r: r[1])[0][0] if rows else float("nan"))
    rows = sweep([(1.4, z) for z in frange(0.0, 1.5, 0.01)], arm, lim)
    zmax = max(rows, key=lambda r: r[1])[0][1] if rows else float("nan")
    return xs, zmax


def workspace_ok(arm, lim):
    """The Z-sweeps at X = 0.9 … 1.3 m (Lim §4.3.1.2 sweeps X = 0.9 to 1.4) each reach
    at least 5 rows: the case-study workspace is usable at the start pose."""
    return all(
        len(sweep([(x, z) for z in frange(0.0, 1.5, 0.01)], arm, lim)) >= 5
        for x in (0.9, 1.0, 1.1, 1.2, 1.3)
    )


def fmt(xs):
    return " / ".join(f"{x:.2f}" for x in xs)


# (l1, l2, l3, lw = l4 + l5 + l6, l5 + l6) in m; the ranges as shipped.
SHIPPED = (0.10, 0.60, 0.40, 0.51, 0.26)
FIRST = (0.10, 0.56, 0.50, 0.34, 0.22)
SHIPPED_LIM = [(0.0, R(90)), (R(-130), 0.0), (R(-55), R(60))]
for name, arm in (("shipped arm", SHIPPED), ("first arm", FIRST)):
    xs, zm = maxima(arm, SHIPPED_LIM)
    print(f"{name}: X-sweep maxima {fmt(xs)} m, Z-sweep maximum at X = 1.4: {zm:.2f} m")

best1, meets = None, []
for l1 in (0.05, 0.10, 0.15):
    for l2 in frange(0.30, 0.85, 0.025):
        for lw in frange(0.34, 0.75, 0.025):
            for l3 in frange(0.30, 0.80, 0.025):
                reach = l2 + l3 + lw
                if not 1.40 - 1e-9 <= reach <= 1.70 + 1e-9:
                    continue
                # l4 = 0.12 m here; the yaw lever l5 + l6 moves the maxima by ≤ 0.01 m.
                arm = (l1, l2, l3, lw, lw - 0.12)
                for lo2, lo4 in ((0, -50), (-10, -50), (0, -30)):
                    lim = [(R(lo2), R(lo2 + 90)), (R(-130), 0.0), (R(lo4), R(lo4 + 115))]
                    xs, zm = maxima(arm, lim)
                    if not all(abs(x - 1.3) <= 0.05 + 1e-9 for x in xs):
                        continue
                    if not workspace_ok(arm, lim):
                        continue
                    if abs(reach - 1.5) < 1e-6 and (best1 is None or zm > best1[0]):
                        best1 = (zm, arm, xs)
                    if abs(zm - 0.42) <= 0.05 + 1e-9:
                        meets.append((reach, arm, xs, zm))
                    break
if best1 is None:
    print("1. reach from the shoulder 1.5 m: no arm has every X-sweep maximum in 1.3 ± 0.05 m")
else:
    zm, arm, xs = best1
    print(f"1. reach from the shoulder 1.5 m: best Z-sweep maximum {zm:.2f} m "
          f"(l1 {arm[0]:.3f}, l2 {arm[1]:.3f}, l3 {arm[2]:.3f}, lw {arm[3]:.3f}; X maxima {fmt(xs)})")
print(f"2. arms meeting both figures: {len(meets)}")
if meets:
    span = lambda k: f"{min(m[1][k] for m in meets):.3f}–{max(m[1][k] for m in meets):.3f}"
    print(f"   l1 {span(0)}, l2 {span(1)}, l3 {span(2)}, lw {span(3)} m; "
          f"swing axis to jaw centre ≥ {min(m[0] + m[1][0] for m in meets):.3f} m")
for reach, arm, xs, zm in sorted(meets)[:8]:
    print(f"   reach {reach:.3f} m: l1 {arm[0]:.3f}, l2 {arm[1]:.3f}, l3 {arm[2]:.3f}, "
          f"lw {arm[3]:.3f}; X maxima {fmt(xs)}, Z maximum {zm:.2f}")

# 3. A 1 cm grid near the shortest arms (l1 = 0.10 m, reach from the shoulder 1.48–1.51 m,
#    the ranges as shipped): the arms meeting both figures with the largest margin, i.e. the
#    smallest worst-case distance from 1.3 m (X maxima) and 0.42 m (Z maximum).
fine = []
for l2 in frange(0.58, 0.78, 0.01):
    for l3 in frange(0.26, 0.45, 0.01):
        for reach in (1.48, 1.49, 1.50, 1.51):
            lw = reach - l2 - l3
            if not 0.35 <= lw <= 0.62:
                continue
            arm = (0.10, l2, l3, lw, 0.26)
            xs, zm = maxima(arm, SHIPPED_LIM)
            if any(math.isnan(x) for x in xs) or math.isnan(zm) or not workspace_ok(arm, SHIPPED_LIM):
                continue
            err = max(max(abs(x - 1.3) for x in xs), abs(zm - 0.42))
            if err <= 0.05 + 1e-9:
                fine.append((round(err, 3), reach, arm, xs, zm))
print(f"3. 1 cm grid, l1 0.10, reach from the shoulder 1.48–1.51 m: {len(fine)} arms meet both")
for err, reach, arm, xs, zm in sorted(fine, key=lambda f: (f[0], f[1]))[:6]:
    print(f"   worst error {err:.3f} m, reach {reach:.2f}: l2 {arm[1]:.2f}, l3 {arm[2]:.2f}, "
          f"lw {arm[3]:.2f}; X maxima {fmt(xs)}, Z maximum {zm:.2f}")
