#!/usr/bin/env python3
"""Reference for examples/hard/watt_six_bar.lsd, a Watt six-bar linkage (two four-bars in series).

Source: the Watt chain (two adjacent ternary links) of the classical six-bar classification
(e.g. Hartenberg & Denavit, "Kinematic Synthesis of Linkages", McGraw-Hill 1964, ch. 3); the
dimensions are chosen for this test set: ground O1 = (0, 0), O2 = (4, 0), O3 = (7, 2); crank
O1A = 1; coupler AB = 3.5; ternary rocker O2-B-C with O2B = 3 and C = (2.5, 0.5) in its frame
(x axis along O2B); coupler CD = 3; rocker O3D = 3. Loop 1 (O1 A B O2) is a Grashof
crank-rocker, loop 2 (O2 C D O3) stays assemblable over the whole turn of the crank (the squared
half-chord of its circle intersection stays above 0.2 of the squared coupler length).

Method (independent of lsdc): position analysis in closed form, B and D as intersections of two
circles on fixed branches (the ones of the starting configuration, theta = 1 rad, B above the
ground line); from lsdc's crank angle the script checks every other joint angle, the energy
(uniform bars of 1 kg/m along their x axes, the ternary rocker as its bar O2B only, C being a
massless point of it, gravity 9.81 along -y) computed here, and crank.q(t) against the reduced Lagrange equation
integrated by scipy (M and V interpolated on 256 points over a turn, bench/hard/hardlib.py).

Usage: bench/hard/watt.py FILE.csv   (JSON summary)   |   bench/hard/watt.py --initial
"""

import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from hardlib import Body, OneDof, read_csv, rotz, trans, wrap  # noqa: E402

O2, O3 = np.array([4.0, 0.0]), np.array([7.0, 2.0])
L1, L2, L3, CX, CY, L4, L5 = 1.0, 3.5, 3.0, 2.5, 0.5, 3.0, 3.0
SB, SD = 1.0, 1.0  # branches (sign of the normal offset), those of the starting configuration
GRAVITY = [0.0, -9.81, 0.0]


def inter(p, r1, q, r2, s):
    d = np.linalg.norm(q - p)
    a = (r1 ** 2 - r2 ** 2 + d ** 2) / (2 * d)
    h = math.sqrt(max(r1 ** 2 - a ** 2, 0.0))
    u = (q - p) / d
    return p + a * u + s * h * np.array([-u[1], u[0]])


def angles(th):
    """Absolute angles (crank, coupler1, rocker1, coupler2, rocker2) for crank angle th."""
    a = np.array([math.cos(th), math.sin(th)]) * L1
    b = inter(a, L2, O2, L3, SB)
    phi1 = math.atan2(b[1] - a[1], b[0] - a[0])
    psi1 = math.atan2(b[1] - O2[1], b[0] - O2[0])
    c = O2 + np.array([[math.cos(psi1), -math.sin(psi1)], [math.sin(psi1), math.cos(psi1)]]) @ [CX, CY]
    d = inter(c, L4, O3, L5, SD)
    phi2 = math.atan2(d[1] - c[1], d[0] - c[0])
    psi2 = math.atan2(d[1] - O3[1], d[0] - O3[0])
    return th, phi1, psi1, phi2, psi2


def joints(th):
    """The LSD joins' coordinates: crank, cA, rocker, cB, cC, r2, cD."""
    t, p1, s1, p2, s2 = angles(th)
    c = O2 + np.array([[math.cos(s1), -math.sin(s1)], [math.sin(s1), math.cos(s1)]]) @ [CX, CY]
    return {"crank.q": t, "cA.q": p1 - t, "rocker.q": s1, "cB.q": s1 - p1, "cC.q": p2 - s1,
            "r2.q": s2, "cD.q": s2 - p2}


def poses(th):
    t, p1, s1, p2, s2 = angles(th)
    a = [L1 * math.cos(t), L1 * math.sin(t)]
    c = O2 + np.array([[math.cos(s1), -math.sin(s1)], [math.sin(s1), math.cos(s1)]]) @ [CX, CY]
    rk = trans(O2[0], O2[1], 0.0) @ rotz(s1)
    return [rotz(t), trans(a[0], a[1], 0.0) @ rotz(p1), rk,
            trans(c[0], c[1], 0.0) @ rotz(p2), trans(O3[0], O3[1], 0.0) @ rotz(s2)]


def bar(l):
    return Body(l, [l / 2, 0, 0], [1e-4 * l, l ** 3 / 12, l ** 3 / 12])


MODEL = OneDof([bar(L1), bar(L2), bar(L3), bar(L4), bar(L5)], poses, GRAVITY).fit(n=256)


def check(path):
    s = read_csv(path)
    t = s["time"]
    if len(t) < 2:
        return {"ok": False, "reason": "fewer than two samples"}
    th, om = s["crank.q"], s["crank.q'"]
    err = 0.0
    for i, x in enumerate(th):
        ref = joints(x)
        err = max(err, max(abs(float(wrap(s[k][i] - v))) for k, v in ref.items()))
    e = np.array([MODEL.energy(a, b) for a, b in zip(th, om)])
    drift = float(np.abs(e - e[0]).max() / max(abs(e[0]), 1e-12))
    ref1, _ = MODEL.integrate(th[0], om[0], t)
    traj = float(np.abs(wrap(th - ref1)).max())
    return {"closed_form_angles": err, "energy_drift_reference": drift, "crank_vs_reduced_ode": traj,
            "t_end": float(t[-1]), "ok": err < 1e-6 and drift < 1e-5 and traj < 1e-4}


if __name__ == "__main__":
    if sys.argv[1] == "--initial":
        print(", ".join("%s = %.15g" % kv for kv in joints(1.0).items()))
    else:
        print(json.dumps(check(sys.argv[1]), indent=1))
