#!/usr/bin/env python3
"""Side-by-side: scipy.optimize.minimize(method='SLSQP') on the same ORION optimal-posture
problem as seaarms' multi-start SLSQP (Jun 2008 eqs 17-18), from the same feasible starts.

ORION (Jun Table 1; seeds README convention): standard DH in metres, point = frame-6 origin,
theta3's "+90" offset NOT applied. f(q) = -a*TOMM - (1-a)*JLM, TOMM = sqrt(det(Jv Jv^T))
(translational rows), JLM = prod(1 - x_i^2) (eq. 16, factors clamped at 0), subject to
p(q) = target and the joint limits. Gradients as in seaarms: TOMM in closed form from the
Jacobian derivative (central differences if singular), JLM analytic; constraint Jacobian = Jv.
Note: scipy's time is dominated by evaluating the numpy model (Python call overhead on
6x6 arrays), not by the SLSQP solver itself (the same Kraft algorithm as NLopt's).

Usage:
    python3 benches/scipy_slsqp.py            # runs the Rust side (cargo test --release ...)
    python3 benches/scipy_slsqp.py case.txt   # or reads its SCIPY_CASE lines from a file
Requires numpy and scipy (pip install numpy scipy). A benchmark script, not part of the product.
"""
import json
import os
import subprocess
import sys
import time

# Single-threaded BLAS, like the Rust side (threaded BLAS on 6x6 matrices only adds overhead).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
from scipy.optimize import minimize  # noqa: E402

# Jun Table 1: a (m), alpha (rad), d (m); limits (deg).
A = np.array([0.0711, 0.5664, 0.1346, 0.0, 0.0, 0.0])
ALPHA = np.radians([90.0, 0.0, 90.0, -90.0, 90.0, 0.0])
D = np.array([0.0, 0.0, 0.0, 0.5004, 0.0, 0.4089])
LIM = np.radians([[-60, 60], [-30, 90], [-90, 30], [-135, 135], [-30, 90], [-180, 180]])
LO, HI = LIM[:, 0], LIM[:, 1]
H = 1e-6


def frames(q):
    """z axes and origins of frames 0..5 (joint axes) and the tool point."""
    t = np.eye(4)
    zs, os = [], []
    for i in range(6):
        zs.append(t[:3, 2].copy())
        os.append(t[:3, 3].copy())
        ct, st = np.cos(q[i]), np.sin(q[i])
        ca, sa = np.cos(ALPHA[i]), np.sin(ALPHA[i])
        a = np.array([[ct, -st * ca, st * sa, A[i] * ct],
                      [st, ct * ca, -ct * sa, A[i] * st],
                      [0.0, sa, ca, D[i]],
                      [0.0, 0.0, 0.0, 1.0]])
        t = t @ a
    return zs, os, t[:3, 3].copy()


def jv(q):
    zs, os, p = frames(q)
    return np.column_stack([np.cross(z, p - o) for z, o in zip(zs, os)]), p


def tomm(q):
    j, _ = jv(q)
    return np.sqrt(max(np.linalg.det(j @ j.T), 0.0))


def tomm_grad_fd(q):
    g = np.zeros(6)
    for i in range(6):
        e = np.zeros(6)
        e[i] = H
        g[i] = (tomm(q + e) - tomm(q - e)) / (2 * H)
    return g


def tomm_grad(q):
    """Closed form, as seaarms' tomm_gradient_analytic: dw/dq_k = w tr(M^-1 Jv dJv^T/dq_k);
    revolute joints: dJv_i/dq_k = z_k x Jv_i (k < i), z_i x Jv_k (k >= i). Falls back to
    central differences when M is singular."""
    zs, os, p = frames(q)
    j = np.column_stack([np.cross(z, p - o) for z, o in zip(zs, os)])
    m = j @ j.T
    try:
        b = np.linalg.solve(m, j)
    except np.linalg.LinAlgError:
        return tomm_grad_fd(q)
    w = np.sqrt(max(np.linalg.det(m), 0.0))
    g = np.zeros(6)
    for k in range(6):
        dj = np.column_stack([np.cross(zs[k], j[:, i]) if i > k else np.cross(zs[i], j[:, k]) for i in range(6)])
        g[k] = w * np.sum(b * dj)
    return g


def jlm_and_grad(q):
    d = 2.0 / (HI - LO)
    x = d * q - (HI + LO) / (HI - LO)
    f = np.maximum(1.0 - x * x, 0.0)
    p = np.prod(f)
    g = np.zeros(6)
    for i in range(6):
        if f[i] > 0.0:
            g[i] = -2.0 * x[i] * d[i] * np.prod(np.delete(f, i))
    return p, g


def make_problem(alpha, target):
    def fun(q):
        return -(alpha * tomm(q) + (1.0 - alpha) * jlm_and_grad(q)[0])

    def jac(q):
        gt = tomm_grad(q) if alpha != 0.0 else np.zeros(6)
        return -(alpha * gt + (1.0 - alpha) * jlm_and_grad(q)[1])

    cons = {"type": "eq",
            "fun": lambda q: jv(q)[1] - target,
            "jac": lambda q: jv(q)[0]}
    return fun, jac, cons


def run_case(case):
    alpha, target = case["alpha"], np.array(case["target"])
    fun, jac, cons = make_problem(alpha, target)
    starts = [np.array(s) for s in case["starts"]]
    best = None
    nfev = 0
    reps = 5
    t0 = time.perf_counter()
    for _ in range(reps):
        best = None
        nfev = 0
        for s in starts:
            r = minimize(fun, s, jac=jac, method="SLSQP", bounds=list(zip(LO, HI)), constraints=[cons],
                         options={"ftol": 1e-12, "maxiter": 400})
            nfev += r.nfev
            viol = np.linalg.norm(jv(r.x)[1] - target)
            if viol <= 1e-6 and (best is None or r.fun < best[0]):
                best = (r.fun, r.x, viol)
    ms = (time.perf_counter() - t0) * 1e3 / reps
    ours = case["ours"]
    # Cross-check: our FK/objective agrees with the Rust objective at the Rust optimum.
    f_rust_here = fun(np.array(ours["q"]))
    print(f"alpha {alpha}: scipy SLSQP best f = {best[0]:.6f} (violation {best[2]:.1e} m, {nfev} fevals) "
          f"in {ms:.2f} ms | seaarms f = {ours['objective']:.6f} in {ours['time_ms']:.3f} ms "
          f"(numpy f at seaarms q = {f_rust_here:.6f}) | speed-up x{ms / ours['time_ms']:.0f}, "
          f"objective {'equal or better' if ours['objective'] <= best[0] + 1e-9 else 'WORSE'}")
    return ms / ours["time_ms"]


def main():
    if len(sys.argv) > 1:
        text = open(sys.argv[1]).read()
    else:
        cmd = ["cargo", "test", "--release", "-p", "seaarms-core", "--test", "scipy_comparison", "--",
               "--ignored", "--nocapture"]
        text = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    cases = [json.loads(line.split(" ", 1)[1]) for line in text.splitlines() if line.startswith("SCIPY_CASE ")]
    if not cases:
        sys.exit("no SCIPY_CASE lines found")
    for c in cases:
        run_case(c)


if __name__ == "__main__":
    main()
