#!/usr/bin/env python3
"""Reference for examples/hard/bricard.lsd, a line-symmetric Bricard 6R linkage.

Source: R. Bricard, "Memoire sur la theorie de l'octaedre articule", J. Math. Pures Appl. 3
(1897) 113-148; the line-symmetric conditions in Denavit-Hartenberg form as listed by
J. E. Baker, "An analysis of the Bricard linkages", Mech. Mach. Theory 15 (1980) 267-286:
a_{i+3} = a_i, alpha_{i+3} = alpha_i, d_{i+3} = d_i. The values themselves are chosen for this
test (a = 1.0, 0.7, 0.9; alpha = 70, 110, 50 degrees; d = 0.2, -0.1, 0.3).

Method (independent of lsdc):
  * the loop T1 ... T6 = I (standard DH, T_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i)) is solved
    here for theta2..theta6 given theta1 by Gauss-Newton (least squares on the 12 entries of the
    rotation and translation), continued along theta1 from the starting configuration, which
    `python3 bricard.py --start` finds from random guesses (two assembly modes at theta1 = 0.5;
    the LSD file uses the first); the rank of the 6x6 closure Jacobian is 5 there (mobility 1);
  * relation checked on lsdc's output: theta_{i+3} = theta_i (line symmetry of the motion) and the
    closure of lsdc's six angles by the DH product computed here;
  * energy computed independently from the poses (bars of 1 kg/m along x, gravity 9.80665 (standard) along -z);
  * theta1(t) compared with the reduced one-coordinate Lagrange equation integrated with scipy
    (DOP853, rtol 1e-12), M(theta1) and V(theta1) replaced by trigonometric interpolants on 128
    points over a full turn of theta1 (the crank turns fully in this linkage; the continuation
    checks that the branch closes on itself after one turn).

Usage: bench/hard/bricard.py FILE.csv   (prints a JSON summary)
"""

import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from hardlib import Body, OneDof, dh, read_csv, rotz, wrap  # noqa: E402

DEG = math.pi / 180
A = [1.0, 0.7, 0.9] * 2
AL = [70 * DEG, 110 * DEG, 50 * DEG] * 2
D = [0.2, -0.1, 0.3] * 2
START = np.array([0.5, -0.315991, 2.885019, 0.5, -0.315991, 2.885019])
GRAVITY = [0.0, 0.0, -9.80665]  # standard gravity, as the `gravity` library's `weight`


def loop(th):
    m = np.eye(4)
    for i in range(6):
        m = m @ dh(th[i], D[i], A[i], AL[i])
    return m


def residual(th):
    m = loop(th)
    return np.concatenate([(m[:3, :3] - np.eye(3)).ravel(), m[:3, 3]])


def solve(t1, guess):
    x = np.array(guess[1:], float)
    for _ in range(50):
        th = np.concatenate([[t1], x])
        r = residual(th)
        if np.abs(r).max() < 1e-15:
            break
        J = np.array([(residual(th + 1e-7 * e) - residual(th - 1e-7 * e)) / 2e-7 for e in np.eye(6)[1:]]).T
        x = x - np.linalg.lstsq(J, r, rcond=None)[0]
    return np.concatenate([[t1], x])


class Branch:
    """The closed configurations along theta1, by continuation from START."""

    def __init__(self):
        self.pts = {0.5: solve(0.5, START)}

    def __call__(self, t1):
        keys = np.array(sorted(self.pts))
        k = keys[np.argmin(np.abs(keys - t1))]
        cur = self.pts[k]
        while abs(k - t1) > 0.02:  # continue in small steps
            k = k + math.copysign(0.02, t1 - k)
            cur = solve(k, cur)
            self.pts[k] = cur
        return solve(t1, cur)


BRANCH = Branch()


def poses(t1):
    th = BRANCH(t1)
    out, m = [], np.eye(4)
    for i in range(5):
        m = m @ rotz(th[i])
        out.append(m)
        m = m @ dh(0.0, D[i], A[i], AL[i])
    return out


def bar(l):
    return Body(l, [l / 2, 0, 0], [1e-4 * l, l ** 3 / 12, l ** 3 / 12])


MODEL = OneDof([bar(A[i]) for i in range(5)], poses, GRAVITY)


def check(path):
    s = read_csv(path)
    t = s["time"]
    if len(t) < 2:
        return {"ok": False, "reason": "fewer than two samples"}
    q = np.array([s["j%d.q" % (i + 1)] for i in range(6)]).T
    t1, w1 = q[:, 0], s["j1.q'"]
    clos = max(float(np.abs(loop(row) - np.eye(4)).max()) for row in q)
    sym = float(np.abs(wrap(q[:, 3:] - q[:, :3])).max())
    e = np.array([MODEL.energy(a, b) for a, b in zip(t1, w1)])
    scale = max(abs(e[0]), float(np.abs(e - MODEL.potential(t1[0])).max()), 1e-12)
    drift = float(np.abs(e - e[0]).max() / scale)
    if not hasattr(MODEL, "_m"):
        MODEL.fit(n=128)
    ref1, _ = MODEL.integrate(t1[0], w1[0], t)
    traj = float(np.abs(wrap(t1 - ref1)).max())
    return {"closure_dh": clos, "symmetry_theta_i3_minus_theta_i": sym,
            "energy_drift_reference": drift, "theta1_vs_reduced_ode": traj, "t_end": float(t[-1]),
            "ok": clos < 1e-6 and sym < 1e-6 and traj < 1e-4 and drift < 1e-5}


def start():
    from scipy.optimize import least_squares
    rng = np.random.default_rng(1)
    sols = []
    for _ in range(200):
        r = least_squares(lambda x: residual(np.concatenate([[0.5], x])), rng.uniform(-math.pi, math.pi, 5),
                          xtol=1e-15, ftol=1e-15, gtol=1e-15)
        if np.abs(r.fun).max() < 1e-10:
            x = wrap(r.x)
            if not any(np.allclose(x, y, atol=1e-6) for y in sols):
                sols.append(x)
    for x in sols:
        th = np.concatenate([[0.5], x])
        J = np.array([(residual(th + 1e-7 * e) - residual(th - 1e-7 * e)) / 2e-7 for e in np.eye(6)]).T
        print("closed:", np.round(th, 6).tolist(), "rank", int(np.sum(np.linalg.svd(J, compute_uv=False) > 1e-8)))


if __name__ == "__main__":
    if sys.argv[1] == "--start":
        start()
    else:
        print(json.dumps(check(sys.argv[1]), indent=1))
