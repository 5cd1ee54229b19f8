#!/usr/bin/env python3
"""Independent reference for `lsdc inverse` on the Delta ISIR88 driven along a nacelle path
(tests/fixtures/delta_path/).

This script does not import or run anything from the lsdc project. For a harmonic path of the
nacelle (a circle of radius 0.05 m about the z axis at z = -0.30 m, with a vertical harmonic of
0.02 m, one turn a second: the seed's harmonic trajectory law in each coordinate) it computes:

* the arm angles by the closed-form inverse geometric model of the seed (notes on the Delta
  seed, "seed-delta", §3.3 with its [fix] corrections: beta = atan2(-z_i, x_i - r),
  delta = arccos((l1^2 + AB^2 - e^2) / (2 l1 AB)), alpha = beta - delta);
* their rates and accelerations by differentiating the closure |P - C_i|^2 = l2^2 once and
  twice (exact: no differences);
* the three arm torques by virtual power on the full model of examples/delta_isir88.lsd (its
  bodies as that file and examples/lib/delta_masses.lsd declare them: each arm with its wheel,
  a body of mass m_b + m_r at their common centre of mass with the moment J1 about the pivot;
  six thin rods of mass M2/2 with m l^2/12 across and nothing about their axis; the nacelle a
  point mass M3 at P; gravity 9.81 m/s^2 down; each arm braked by its shorted motor,
  -c alpha', c = 12^2 K_i K_e / R):

      tau_k = sum over bodies [ m (a_G - g) . dG/dalpha_k + (dH/dt) . domega/dalpha_k ] + c alpha'_k

  where the partial velocities come from dP/dalpha = J^-1, J the inverse Jacobian of the seed
  (alpha' = J P', row i = (P - C_i)^T / ((P - C_i) . dC_i/dalpha_i)). A rod's angular momentum
  about its centre is I_perp u x u' (u its unit direction; its spin carries none), so its rate
  is I_perp u x u''.

Writes path.csv (the nacelle's position, rate and acceleration: the input of `lsdc inverse
--motion path.csv --frame nacelle`) and torques.csv (the arm angles, rates, accelerations and
torques), both with this provenance in '#' lines.

Usage:  python3 bench/delta_path_torques.py [OUTPUT_DIR]      (needs numpy)
Default: tests/fixtures/delta_path next to this script's parent directory.
"""

import math
import os
import sys

import numpy as np

# Geometry (notes §2 and examples/delta_isir88.lsd), SI units.
L1 = 0.200
L2 = 0.300
R = 0.150 - 0.024
W = 0.025
PHI = [0.0, 2.0 * math.pi / 3.0, 4.0 * math.pi / 3.0]
G = np.array([0.0, 0.0, -9.81])

# Masses (examples/lib/delta_masses.lsd).
DA = 3.73 * math.pi / 180.0
M_B, D_B = 0.08366, 0.05886
M_R, D_R = 0.18683, 0.034455
J1 = 0.0071126
M2 = 2 * 0.01438
M3 = 0.0416
M_ARM = M_B + M_R
ARM_COM = (M_B * D_B * np.array([math.cos(DA), 0.0, math.sin(DA)])
           + M_R * D_R * np.array([-math.sin(DA), 0.0, math.cos(DA)])) / M_ARM
J_ARM = J1 - M_ARM * ARM_COM.dot(ARM_COM)      # about the arm's centre of mass, every axis
M_ROD = M2 / 2
I_ROD = M_ROD * L2 ** 2 / 12                    # across the rod
C_SHORT = 12 ** 2 * 0.119 * 0.1194 / 1.35       # shorted motor's brake, N m s / rad

# The path: one turn a second.
RADIUS, Z0, HEAVE, OMEGA = 0.05, -0.30, 0.02, 2.0 * math.pi
DURATION, STEP = 1.0, 0.01


def path(t):
    """P, P', P'' at time t."""
    c, s = math.cos(OMEGA * t), math.sin(OMEGA * t)
    p = np.array([RADIUS * c, RADIUS * s, Z0 + HEAVE * s])
    v = OMEGA * np.array([-RADIUS * s, RADIUS * c, HEAVE * c])
    a = -OMEGA ** 2 * np.array([RADIUS * c, RADIUS * s, HEAVE * s])
    return p, v, a


def rz(phi):
    c, s = math.cos(phi), math.sin(phi)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def ry(q):
    c, s = math.cos(q), math.sin(q)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def ry_prime(q):
    c, s = math.cos(q), math.sin(q)
    return np.array([[-s, 0.0, c], [0.0, 0.0, 0.0], [-c, 0.0, -s]])


def ry_second(q):
    return -ry(q) + np.diag([0.0, 1.0, 0.0])


def elbow(alpha, phi):
    """C_i, dC_i/dalpha, d2C_i/dalpha2 in R0."""
    e, z = np.array([math.cos(phi), math.sin(phi), 0.0]), np.array([0.0, 0.0, 1.0])
    c = (R + L1 * math.cos(alpha)) * e - L1 * math.sin(alpha) * z
    dc = -L1 * math.sin(alpha) * e - L1 * math.cos(alpha) * z
    ddc = -L1 * math.cos(alpha) * e + L1 * math.sin(alpha) * z
    return c, dc, ddc


def mgi(p):
    """Arm angles of the seed's inverse geometric model (notes §3.3, branch beta - delta)."""
    alpha = []
    for phi in PHI:
        xi = math.cos(phi) * p[0] + math.sin(phi) * p[1]
        yi = -math.sin(phi) * p[0] + math.cos(phi) * p[1]
        zi = p[2]
        e2 = L2 ** 2 - yi ** 2
        ab = math.hypot(zi, xi - R)
        beta = math.atan2(-zi, xi - R)
        delta = math.acos((L1 ** 2 + ab ** 2 - e2) / (2 * L1 * ab))
        alpha.append(beta - delta)
    return np.array(alpha)


def torques(t):
    p, pd, pdd = path(t)
    alpha = mgi(p)
    elbows = [elbow(a, phi) for a, phi in zip(alpha, PHI)]
    for c, _, _ in elbows:
        assert abs(np.linalg.norm(p - c) - L2) < 1e-12, "closure"
    # Rates and accelerations from the closure, differentiated once and twice.
    jac = np.array([(p - c) / (p - c).dot(dc) for c, dc, _ in elbows])
    alpha_d = jac @ pd
    alpha_dd = np.empty(3)
    for i, (c, dc, ddc) in enumerate(elbows):
        rel_v = pd - dc * alpha_d[i]
        alpha_dd[i] = (rel_v.dot(rel_v) + (p - c).dot(pdd - ddc * alpha_d[i] ** 2)) / (p - c).dot(dc)
    dp_dalpha = np.linalg.inv(jac)                     # column k: dP/dalpha_k
    tau = C_SHORT * alpha_d.copy()
    for k in range(3):
        # The nacelle.
        tau[k] += M3 * (pdd - G).dot(dp_dalpha[:, k])
        for i, phi in enumerate(PHI):
            c, dc, ddc = elbows[i]
            dc_k = dc if i == k else np.zeros(3)
            # Arm i: it turns about y_i; its centre of mass moves only with alpha_i.
            y_i = rz(phi) @ np.array([0.0, 1.0, 0.0])
            a = alpha[i]
            com_d1 = rz(phi) @ ry_prime(a) @ ARM_COM
            com_d2 = rz(phi) @ ry_second(a) @ ARM_COM
            a_com = com_d2 * alpha_d[i] ** 2 + com_d1 * alpha_dd[i]
            if i == k:
                tau[k] += M_ARM * (a_com - G).dot(com_d1) + J_ARM * alpha_dd[i]
            # The two rods of chain i: centres (C_i + P)/2 +- w y_i, direction u = (P - C_i)/l2.
            c_dd = ddc * alpha_d[i] ** 2 + dc * alpha_dd[i]
            a_rod = (c_dd + pdd) / 2
            v_rod_k = (dc_k + dp_dalpha[:, k]) / 2
            u = (p - c) / L2
            u_dd = (pdd - c_dd) / L2
            omega_k = np.cross(u, (dp_dalpha[:, k] - dc_k) / L2)
            h_dot = I_ROD * np.cross(u, u_dd)
            tau[k] += 2 * (M_ROD * (a_rod - G).dot(v_rod_k) + h_dot.dot(omega_k))
    return p, pd, pdd, alpha, alpha_d, alpha_dd, tau


def number(x):
    return repr(float(x))


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "tests", "fixtures", "delta_path")
    os.makedirs(out, exist_ok=True)
    provenance = [
        "# Written by bench/delta_path_torques.py (numpy, independent of lsdc): the Delta ISIR88 of",
        "# examples/delta_isir88.lsd, its nacelle on a circle of radius 0.05 m at z = -0.30 m with a",
        "# vertical harmonic of 0.02 m, one turn a second; closed-form inverse geometric model (seed",
        "# notes §3.3), rates and accelerations from the closure differentiated, torques by virtual power.",
    ]
    times = [round(k * STEP, 12) for k in range(int(round(DURATION / STEP)) + 1)]
    path_rows = ["time,nacelle.x,nacelle.y,nacelle.z,nacelle.x',nacelle.y',nacelle.z',nacelle.x'',nacelle.y'',nacelle.z''"]
    torque_rows = ["time,A1.q,A2.q,A3.q,A1.q',A2.q',A3.q',A1.q'',A2.q'',A3.q'',A1.drive_effort,A2.drive_effort,A3.drive_effort"]
    for t in times:
        p, pd, pdd, alpha, alpha_d, alpha_dd, tau = torques(t)
        path_rows.append(",".join(number(x) for x in [t, *p, *pd, *pdd]))
        torque_rows.append(",".join(number(x) for x in [t, *alpha, *alpha_d, *alpha_dd, *tau]))
    with open(os.path.join(out, "path.csv"), "w") as f:
        f.write("\n".join(provenance + path_rows) + "\n")
    with open(os.path.join(out, "torques.csv"), "w") as f:
        f.write("\n".join(provenance + torque_rows) + "\n")
    print(f"wrote {len(times)} rows to {out}/path.csv and torques.csv")


if __name__ == "__main__":
    main()
