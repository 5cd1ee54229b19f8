#!/usr/bin/env python3
"""Reference for examples/hard/bennett.lsd, the Bennett 4R linkage.

Source: G. T. Bennett, "A new mechanism", Engineering 76 (1903) 777; the input-output relation
in Denavit-Hartenberg form as given by K. J. Waldron (1968) and J. E. Baker (1979): with the
standard DH convention T_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i), loop T1 T2 T3 T4 = I,
a1 = a3, a2 = a4, alpha1 = alpha3, alpha2 = alpha4, a1/sin(alpha1) = a2/sin(alpha2), d_i = 0:

    tan(theta1/2) tan(theta2/2) = sin((alpha2 + alpha1)/2) / sin((alpha2 - alpha1)/2),
    theta3 = -theta1,  theta4 = -theta2.

(The signs in this convention were confirmed here numerically: the loop product closes to
rounding for every theta1 with these relations, and with no other choice of signs.)

Method (independent of lsdc): given the crank angle theta1(t) and its rate from lsdc's CSV
output (columns j1.q, j1.q'), the script
  1. checks j2.q, j3.q, j4.q against the closed form (angles compared modulo 2 pi);
  2. checks the closure of the loop with lsdc's four angles by the DH product computed here;
  3. computes the energy independently (bench/hard/hardlib.py: poses from the closed form,
     uniform bars of 1 kg/m, gravity 9.81 along -y) and reports its drift;
  4. integrates the reduced one-coordinate Lagrange equation with scipy (DOP853, rtol 1e-11)
     from lsdc's initial theta1, theta1' and compares theta1(t); M(theta1) and V(theta1) are
     replaced for that by their trigonometric interpolants on 256 points (spectral accuracy).

Usage: bench/hard/bennett.py FILE.csv   (prints a JSON summary)
"""

import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from hardlib import Body, OneDof, dh, read_csv, rotz, wrap  # noqa: E402

A1 = 1.0
ALPHA1 = math.pi / 3
ALPHA2 = math.pi / 2
A2 = A1 * math.sin(ALPHA2) / math.sin(ALPHA1)
K = math.sin((ALPHA2 + ALPHA1) / 2) / math.sin((ALPHA2 - ALPHA1) / 2)
GRAVITY = [0.0, -9.81, 0.0]


def theta2_of(theta1):
    return 2 * np.arctan2(K * np.cos(theta1 / 2), np.sin(theta1 / 2))


def bar(l):
    return Body(l, [l / 2, 0, 0], [1e-4 * l, l ** 3 / 12, l ** 3 / 12])


def poses(theta1):
    t2 = theta2_of(theta1)
    b1 = rotz(theta1)
    b2 = b1 @ dh(0.0, 0.0, A1, ALPHA1) @ rotz(t2)
    b3 = b2 @ dh(0.0, 0.0, A2, ALPHA2) @ rotz(-theta1)
    return [b1, b2, b3]


MODEL = OneDof([bar(A1), bar(A2), bar(A1)], poses, GRAVITY).fit(n=256)


def closure(t1, t2, t3, t4):
    m = dh(t1, 0, A1, ALPHA1) @ dh(t2, 0, A2, ALPHA2) @ dh(t3, 0, A1, ALPHA1) @ dh(t4, 0, A2, ALPHA2)
    return float(np.abs(m - np.eye(4)).max())


def check(path):
    s = read_csv(path)
    t, t1, w1 = s["time"], s["j1.q"], s["j1.q'"]
    if len(t) < 2:
        return {"ok": False, "reason": "fewer than two samples"}
    cf2 = theta2_of(t1)
    err2 = float(np.abs(wrap(s["j2.q"] - cf2)).max())
    err3 = float(np.abs(wrap(s["j3.q"] + t1)).max())
    err4 = float(np.abs(wrap(s["j4.q"] + cf2)).max())
    clos = max(closure(a, b, c, d) for a, b, c, d in zip(t1, s["j2.q"], s["j3.q"], s["j4.q"]))
    e = np.array([MODEL.energy(a, b) for a, b in zip(t1, w1)])
    scale = max(abs(e[0]), float(np.abs(e - MODEL.potential(t1[0])).max()), 1e-12)
    drift = float(np.abs(e - e[0]).max() / scale)
    ref1, _ = MODEL.integrate(t1[0], w1[0], t)
    traj = float(np.abs(wrap(t1 - ref1)).max())
    return {"closed_form_theta2": err2, "closed_form_theta3": err3, "closed_form_theta4": err4,
            "closure_dh": clos, "energy_drift_reference": drift, "theta1_vs_reduced_ode": traj,
            "t_end": float(t[-1]),
            "ok": max(err2, err3, err4, clos) < 1e-6 and traj < 1e-4 and drift < 1e-5}


if __name__ == "__main__":
    print(json.dumps(check(sys.argv[1]), indent=1))
