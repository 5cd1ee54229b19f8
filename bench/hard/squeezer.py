#!/usr/bin/env python3
"""Reference for examples/hard/squeezer.lsd, Andrews' squeezing mechanism.

Source: the problem "Andrews' squeezing mechanism" of the Test Set for IVP Solvers
(F. Mazzia, C. Magherini et al., University of Bari, formerly CWI Amsterdam; problem
"andrews", source file andrews.f, revision 1.2 of 2006/10/02), taken from E. Hairer & G. Wanner, "Solving Ordinary Differential Equations
II", 2nd ed., Springer 1996, section VII.7, after G. C. Andrews (1986) and W. Schiehlen
(Multibody Systems Handbook, 1990). Seven bodies, planar, without gravity; coordinates
y = (beta, theta, gamma, phi, delta, omega, epsilon) as in the test set; a drive torque
mom = 0.033 N m on beta and a spring (c0 = 4530 N/m, natural length l0 = 0.07785 m) between the
fixed point C and the point D of body 3. The parameters below are those of the test set.

Reference values at t = 0.03 s: the test set's reference solution, "computed at Cray C90, using
Cray double precision" with PSIDE at rtol = atol = 1e-14 (subroutine `andsoln` of the test set's
andrews.f), positions y1..y7 and velocities y8..y14:
    beta      0.1581077119629904e+2    beta'    0.1139920302151208e+4
    theta    -0.1575637105984298e+2    theta'  -0.1424379294994111e+4
    gamma     0.4082224013073101e-1    gamma'   0.1103291221937134e+2
    phi      -0.5347301163226948e+0    phi'     0.1929337464421385e+2
    delta     0.5244099658805304e+0    delta'   0.5735699284790808e+0
    omega     0.5347301163226948e+0    omega'  -0.1929337464421385e+2
    epsilon   0.1048080741042263e+1    epsilon' 0.3231791658026955e+0

Independent check of the data here: the equations of motion of the test set (mass matrix M(y),
forces f(y, y'), the six constraints g(y) = 0 and their Jacobian G = dg/dy, written out below
from the problem description) are integrated in the index-1 form
    [M  G^T] [y'']   [f        ]
    [G  0  ] [lam] = [-G'(y) y']
(the constraint's second derivative, G' y' computed by complex-step differentiation) with
scipy's DOP853 at rtol = atol = 1e-13 and compared with the published values; the result is
stored in tests/fixtures/hard/squeezer_reference.json (`--write`).

Usage:
  bench/hard/squeezer.py --write        integrate, compare with the test set, write the fixture
  bench/hard/squeezer.py FILE.csv       compare lsdc's last sample (t = 0.03) with the reference
"""

import json
import math
import os
import sys

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from hardlib import read_csv  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
FIXTURE = os.path.join(ROOT, "tests", "fixtures", "hard", "squeezer_reference.json")

P = dict(m1=.04325, m2=.00365, m3=.02373, m4=.00706, m5=.07050, m6=.00706, m7=.05498,
         i1=2.194e-6, i2=4.410e-7, i3=5.255e-6, i4=5.667e-7, i5=1.169e-5, i6=5.667e-7, i7=1.912e-5,
         xa=-.06934, ya=-.00227, xb=-.03635, yb=.03273, xc=.014, yc=.072, c0=4530.0,
         d=28e-3, da=115e-4, e=2e-2, ea=1421e-5, rr=7e-3, ra=92e-5, l0=7785e-5, ss=35e-3,
         sa=1874e-5, sb=1043e-5, sc=18e-3, sd=2e-2, ta=2308e-5, tb=916e-5, u=4e-2, ua=1228e-5,
         ub=449e-5, zf=2e-2, zt=4e-2, fa=1421e-5, mom=33e-3)
NAMES = ["beta", "theta", "gamma", "phi", "delta", "omega", "epsilon"]
Y0 = [-0.0617138900142764496358948458001, 0.0, 0.455279819163070380255912382449,
      0.222668390165885884674473185609, 0.487364979543842550225598953530,
      -0.222668390165885884674473185609, 1.23054744454982119249735015568]
PUBLISHED_Q = [0.1581077119629904e2, -0.1575637105984298e2, 0.4082224013073101e-1, -0.5347301163226948,
               0.5244099658805304, 0.5347301163226948, 0.1048080741042263e1]
PUBLISHED_V = [0.1139920302151208e4, -0.1424379294994111e4, 0.1103291221937134e2, 0.1929337464421385e2,
               0.5735699284790808, -0.1929337464421385e2, 0.3231791658026955]


def constraints(y):
    p = P
    be, th, ga, ph, de, om, ep = y
    ex = p["rr"] * np.cos(be) - p["d"] * np.cos(be + th)
    ey = p["rr"] * np.sin(be) - p["d"] * np.sin(be + th)
    return np.array([
        ex - p["ss"] * np.sin(ga) - p["xb"],
        ey + p["ss"] * np.cos(ga) - p["yb"],
        ex - p["e"] * np.sin(ph + de) - p["zt"] * np.cos(de) - p["xa"],
        ey + p["e"] * np.cos(ph + de) - p["zt"] * np.sin(de) - p["ya"],
        ex - p["zf"] * np.cos(om + ep) - p["u"] * np.sin(ep) - p["xa"],
        ey - p["zf"] * np.sin(om + ep) + p["u"] * np.cos(ep) - p["ya"]])


def jac(y):
    h = 1e-30
    return np.array([np.imag(constraints(np.asarray(y, complex) + 1j * h * e)) / h for e in np.eye(7)]).T


def mass(y):
    p = P
    be, th, ga, ph, de, om, ep = y
    m = np.zeros((7, 7))
    m[0, 0] = p["m1"] * p["ra"] ** 2 + p["m2"] * (p["rr"] ** 2 - 2 * p["da"] * p["rr"] * math.cos(th) + p["da"] ** 2) + p["i1"] + p["i2"]
    m[1, 0] = m[0, 1] = p["m2"] * (p["da"] ** 2 - p["da"] * p["rr"] * math.cos(th)) + p["i2"]
    m[1, 1] = p["m2"] * p["da"] ** 2 + p["i2"]
    m[2, 2] = p["m3"] * (p["sa"] ** 2 + p["sb"] ** 2) + p["i3"]
    ee = p["e"] - p["ea"]
    m[3, 3] = p["m4"] * ee ** 2 + p["i4"]
    m[4, 3] = m[3, 4] = p["m4"] * (ee ** 2 + p["zt"] * ee * math.sin(ph)) + p["i4"]
    m[4, 4] = p["m4"] * (p["zt"] ** 2 + 2 * p["zt"] * ee * math.sin(ph) + ee ** 2) + p["m5"] * (p["ta"] ** 2 + p["tb"] ** 2) + p["i4"] + p["i5"]
    ff = p["zf"] - p["fa"]
    m[5, 5] = p["m6"] * ff ** 2 + p["i6"]
    m[6, 5] = m[5, 6] = p["m6"] * (ff ** 2 - p["u"] * ff * math.sin(om)) + p["i6"]
    m[6, 6] = p["m6"] * (ff ** 2 - 2 * p["u"] * ff * math.sin(om) + p["u"] ** 2) + p["m7"] * (p["ua"] ** 2 + p["ub"] ** 2) + p["i6"] + p["i7"]
    return m


def forces(y, v):
    p = P
    be, th, ga, ph, de, om, ep = y
    bp, tp, gp, pp, dp, op, epp = v
    xd = p["sd"] * math.cos(ga) + p["sc"] * math.sin(ga) + p["xb"]
    yd = p["sd"] * math.sin(ga) - p["sc"] * math.cos(ga) + p["yb"]
    lang = math.hypot(xd - p["xc"], yd - p["yc"])
    force = -p["c0"] * (lang - p["l0"]) / lang
    fx, fy = force * (xd - p["xc"]), force * (yd - p["yc"])
    ee, ff = p["e"] - p["ea"], p["zf"] - p["fa"]
    return np.array([
        p["mom"] - p["m2"] * p["da"] * p["rr"] * tp * (tp + 2 * bp) * math.sin(th),
        p["m2"] * p["da"] * p["rr"] * bp ** 2 * math.sin(th),
        fx * (p["sc"] * math.cos(ga) - p["sd"] * math.sin(ga)) + fy * (p["sd"] * math.cos(ga) + p["sc"] * math.sin(ga)),
        p["m4"] * p["zt"] * ee * dp ** 2 * math.cos(ph),
        -p["m4"] * p["zt"] * ee * pp * (pp + 2 * dp) * math.cos(ph),
        -p["m6"] * p["u"] * ff * epp ** 2 * math.cos(om),
        p["m6"] * p["u"] * ff * op * (op + 2 * epp) * math.cos(om)])


def rhs(_t, x):
    y, v = x[:7], x[7:]
    G = jac(y)
    # G'(y) v: derivative of G v along v, by complex step
    h = 1e-30
    gdot = np.imag(jac_c(np.asarray(y, complex) + 1j * h * v) @ v) / h
    a = np.block([[mass(y), G.T], [G, np.zeros((6, 6))]])
    sol = np.linalg.solve(a, np.concatenate([forces(y, v), -gdot]))
    return np.concatenate([v, sol[:7]])


def jac_c(y):
    """dg/dy at a complex point (central differences in a real direction would lose the
    complex step; use the analytic derivative of each row instead)."""
    p = P
    be, th, ga, ph, de, om, ep = y
    g = np.zeros((6, 7), dtype=complex)
    sx = -p["rr"] * np.sin(be) + p["d"] * np.sin(be + th)
    sy = p["rr"] * np.cos(be) - p["d"] * np.cos(be + th)
    for r in (0, 2, 4):
        g[r, 0], g[r, 1] = sx, p["d"] * np.sin(be + th)
        g[r + 1, 0], g[r + 1, 1] = sy, -p["d"] * np.cos(be + th)
    g[0, 2], g[1, 2] = -p["ss"] * np.cos(ga), -p["ss"] * np.sin(ga)
    g[2, 3], g[2, 4] = -p["e"] * np.cos(ph + de), -p["e"] * np.cos(ph + de) + p["zt"] * np.sin(de)
    g[3, 3], g[3, 4] = -p["e"] * np.sin(ph + de), -p["e"] * np.sin(ph + de) - p["zt"] * np.cos(de)
    g[4, 5], g[4, 6] = p["zf"] * np.sin(om + ep), p["zf"] * np.sin(om + ep) - p["u"] * np.cos(ep)
    g[5, 5], g[5, 6] = -p["zf"] * np.cos(om + ep), -p["zf"] * np.cos(om + ep) - p["u"] * np.sin(ep)
    return g


def reference(rtol=1e-13):
    sol = solve_ivp(rhs, (0.0, 0.03), np.concatenate([Y0, np.zeros(7)]), method="DOP853",
                    rtol=rtol, atol=rtol, t_eval=[0.03])
    return sol.y[:, -1], sol


def write():
    assert np.abs(jac(Y0) - jac_c(np.asarray(Y0, complex)).real).max() < 1e-15
    x, sol = reference()
    q, v = x[:7], x[7:]
    out = {
        "mechanism": "Andrews' squeezing mechanism (examples/hard/squeezer.lsd)",
        "t": 0.03,
        "coordinates": NAMES,
        "published": {
            "source": "Test Set for IVP Solvers (Mazzia, Magherini et al., Univ. Bari), problem andrews, "
                      "reference solution of subroutine andsoln: PSIDE on a Cray C90, rtol = atol = 1e-14",
            "positions": PUBLISHED_Q, "velocities": PUBLISHED_V},
        "computed": {
            "source": "bench/hard/squeezer.py: index-1 form of the test set's equations, scipy DOP853, "
                      "rtol = atol = 1e-13, no projection",
            "positions": q.tolist(), "velocities": v.tolist(),
            "constraint_residual": float(np.abs(constraints(q)).max()),
            "function_evaluations": int(sol.nfev)},
        "computed_minus_published": {
            "positions_max_abs": float(np.abs(q - PUBLISHED_Q).max()),
            "velocities_max_rel": float(np.abs((v - PUBLISHED_V) / np.maximum(np.abs(PUBLISHED_V), 1.0)).max())},
    }
    os.makedirs(os.path.dirname(FIXTURE), exist_ok=True)
    with open(FIXTURE, "w") as f:
        json.dump(out, f, indent=1)
        f.write("\n")
    print(json.dumps(out["computed_minus_published"]))


def check(path):
    s = read_csv(path)
    t = s["time"]
    if len(t) == 0 or abs(t[-1] - 0.03) > 1e-9:
        return {"ok": False, "reason": "no sample at t = 0.03", "t_end": float(t[-1]) if len(t) else None}
    q = np.array([s[n + ".q"][-1] for n in NAMES])
    v = np.array([s[n + ".q'"][-1] for n in NAMES])
    eq = float(np.abs(q - PUBLISHED_Q).max())
    ev = float(np.abs((v - PUBLISHED_V) / np.maximum(np.abs(PUBLISHED_V), 1.0)).max())
    return {"positions_max_abs_error": eq, "velocities_max_rel_error": ev, "t_end": float(t[-1]),
            "ok": eq < 1e-4 and ev < 1e-3}


if __name__ == "__main__":
    if sys.argv[1] == "--write":
        write()
    else:
        print(json.dumps(check(sys.argv[1]), indent=1))
