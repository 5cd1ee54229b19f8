#!/usr/bin/env python3
"""Independent reference values for the Delta ISIR88 examples (tests/fixtures/delta.json).

This script does not import or run anything from the lsdc project. It re-implements, from the
thesis equations as corrected in the project's notes on the Delta seed ("seed-delta"):

* the direct geometric model (MGD) by the authors' circumcircle method (notes §3.2);
* the inverse geometric model (MGI) of notes §3.3, with the [fix] corrections
  (beta = atan2(-z_i, x_i - r); delta uses l1, not l2; alpha = beta - delta);
* the forward kinematics of examples/delta_isir88_reduced.lsd, written with exactly that file's
  frames and coordinate conventions, and a Gauss-Newton solve of its two loop closures at
  alpha = (40, 40, 40) deg.

It checks its own MGD/MGI against the tables T4 and T5 of the notes (to 1e-4 mm and 1e-6 deg, the
printed precision), the closure |P - C_i| = l2, the MGD/MGI round trip, and that the nacelle of the
closed reduced model is where the MGD puts it (to 1e-12 m) and parallel to the base.

Usage:  python3 bench/delta_reference.py [--guesses] [OUTPUT.json]     (needs numpy)
Default output: tests/fixtures/delta.json next to this script's parent directory.
"""

import json
import math
import os
import sys

import numpy as np

# --------------------------------------------------------------------------------------------
# Parameters (notes §2), SI units.

L1 = 0.200          # arm length l1 (m)
L2 = 0.300          # rod length l2 (m)
R1 = 0.150          # base radius (m)
R2 = 0.024          # nacelle radius (m)
R = R1 - R2         # r = R1 - R2 = 0.126 m, the thesis's simplification
PHI = [0.0, 2.0 * math.pi / 3.0, 4.0 * math.pi / 3.0]
W = 0.025           # half-width of a rod pair in delta_isir88.lsd (invented, not in the thesis)

DEG = math.pi / 180.0


# --------------------------------------------------------------------------------------------
# Geometric models.

def elbow(alpha_i, phi_i):
    """C_i in R0 (notes III.4 with the alpha fix): ((r + l1 cos a) cos phi, (...) sin phi, -l1 sin a)."""
    rho = R + L1 * math.cos(alpha_i)
    return np.array([rho * math.cos(phi_i), rho * math.sin(phi_i), -L1 * math.sin(alpha_i)])


class NoAssembly(ValueError):
    pass


def mgd(alpha):
    """Direct geometric model, circumcircle method (notes §3.2 steps 1-8)."""
    c1, c2, c3 = (elbow(a, p) for a, p in zip(alpha, PHI))
    a = np.linalg.norm(c2 - c1)                    # |C1C2|
    b = np.linalg.norm(c3 - c2)                    # |C2C3|
    c = np.linalg.norm(c3 - c1)                    # |C1C3|
    if min(a, b, c) == 0.0:
        raise NoAssembly("two elbows coincide (on Oz): P is not determined")
    v1 = (c2 - c1) / a
    ot = (c1 + c2) / 2.0
    s_vec = np.cross(c1 - c3, c2 - c1)             # C3C1 x C1C2 = S n
    s = np.linalg.norm(s_vec)
    if s == 0.0:
        raise NoAssembly("elbows collinear")
    n = s_vec / s
    p = a + b + c
    circum = a * b * c / math.sqrt(p * (p - 2 * a) * (p - 2 * b) * (p - 2 * c))
    omega = math.copysign(1.0, b * b + c * c - a * a) * np.cross(n, v1)
    tl = math.sqrt(max(circum * circum - a * a / 4.0, 0.0))
    if circum > L2:
        raise NoAssembly("circumradius %.6g > l2: no assembly" % circum)
    lp = math.sqrt(L2 * L2 - circum * circum)
    return ot + tl * omega - lp * n


def mgi(pos):
    """Inverse geometric model (notes §3.3 with the fixes), branch alpha = beta - delta."""
    x, y, z = pos
    out = []
    for phi in PHI:
        xi = math.cos(phi) * x + math.sin(phi) * y
        yi = -math.sin(phi) * x + math.cos(phi) * y
        zi = z
        e2 = L2 * L2 - yi * yi
        if e2 < 0:
            raise NoAssembly("sphere misses the arm plane")
        ab = math.hypot(zi, xi - R)
        if ab == 0.0:
            raise NoAssembly("beta undefined: P projects onto A_i")
        beta = math.atan2(-zi, xi - R)
        cosd = (L1 * L1 + ab * ab - e2) / (2 * L1 * ab)
        if abs(cosd) > 1:
            raise NoAssembly("unreachable")
        out.append(beta - math.acos(cosd))
    return out


# --------------------------------------------------------------------------------------------
# Tables T4 and T5 of the notes (mm, deg), used only to check the models above.

T4 = [
    ((30, 30, 30), (0, 0, -121.8247)),
    ((40, 40, 40), (0, 0, -238.2954)),
    ((45, 45, 45), (0, 0, -277.3839)),
    ((48.205906, 48.205906, 48.205906), (0, 0, -300.0000)),
    ((60, 60, 60), (0, 0, -370.4967)),
    ((90, 90, 90), (0, 0, -472.2572)),
    ((20, 40, 60), (62.0701, 42.1437, -225.8404)),
    ((30, 50, 70), (76.6578, 51.7214, -294.4160)),
    ((50, 30, 40), (-33.4866, 17.7675, -235.1534)),
    ((35, 60, 45), (43.8350, -35.3691, -282.7488)),
]

T5 = [
    ((0, 0, -200), (35.773894, 35.773894, 35.773894)),
    ((0, 0, -250), (41.426661, 41.426661, 41.426661)),
    ((0, 0, -300), (48.205906, 48.205906, 48.205906)),
    ((0, 0, -350), (56.236116, 56.236116, 56.236116)),
    ((0, 0, -400), (66.107493, 66.107493, 66.107493)),
    ((0, 0, -450), (79.902760, 79.902760, 79.902760)),
    ((50, 0, -300), (35.918223, 55.496007, 55.496007)),
    ((0, 50, -300), (49.430761, 37.826467, 59.626524)),
    ((50, 50, -300), (37.169142, 45.934296, 66.035512)),
    ((-60, 30, -280), (61.968300, 31.515345, 46.554832)),
    ((100, 0, -250), (13.467871, 59.779961, 59.779961)),
]


# --------------------------------------------------------------------------------------------
# Rigid transforms (4x4), complex-safe so the Jacobian can be taken by complex step.

def rot(axis, q):
    c, s = np.cos(q), np.sin(q)
    dtype = complex if isinstance(q, complex) or np.iscomplexobj(q) else float
    m = np.eye(4, dtype=dtype)
    if axis == "x":
        m[1, 1], m[1, 2], m[2, 1], m[2, 2] = c, -s, s, c
    elif axis == "y":
        m[0, 0], m[0, 2], m[2, 0], m[2, 2] = c, s, -s, c
    elif axis == "z":
        m[0, 0], m[0, 1], m[1, 0], m[1, 1] = c, -s, s, c
    return m


def trans(v):
    m = np.eye(4)
    m[:3, 3] = v
    return m


def inv(t):
    out = np.eye(4, dtype=t.dtype)
    out[:3, :3] = t[:3, :3].T
    out[:3, 3] = -t[:3, :3].T @ t[:3, 3]
    return out


def chain(phi, p):
    """LSD `chain(phi, p) = (phi || [0, 0, 1]) * (p ++ 1)`: rotate about z by phi, then move by p."""
    return rot("z", phi) @ trans(p)


# --------------------------------------------------------------------------------------------
# The reduced model, exactly as examples/delta_isir88_reduced.lsd writes it:
#
#   join chain(phi_i, [r, 0, 0]) @ earth and arm_i with revolute([0, 1, 0]) as A_i ;
#   join [l1, 0, 0] ++ 1 @ arm_i and rod_i with universal([0, 1, 0], [1, 0, 0]) as C_i ;
#   join chain(phi_i, [0, 0, 0]) @ nacelle and [0, 0, -l2] ++ 1 @ rod_i
#        with universal([0, 1, 0], [1, 0, 0]) as P_i ;
#
# `join F1 and F2 with L` means pose(F1) * D_L = pose(F2); revolute(ax) is q || ax and
# universal(u, v) is (a || u) * (b || v).

REDUCED_NAMES = [f"{j}{i}.{c}" for i in (1, 2, 3) for j, cs in (("A", "q"), ("C", "ab"), ("P", "ab"))
                 for c in cs]


def reduced_nacelle_via(i, q, ca, cb, pa, pb):
    """Pose of the nacelle's reference frame reached through chain i (0-based)."""
    phi = PHI[i]
    arm = chain(phi, [R, 0.0, 0.0]) @ rot("y", q)              # A_i
    rod = arm @ trans([L1, 0.0, 0.0]) @ rot("y", ca) @ rot("x", cb)  # C_i
    rod_lower = rod @ trans([0.0, 0.0, -L2])
    socket = rod_lower @ inv(rot("y", pa) @ rot("x", pb))     # P_i: socket * D = rod_lower
    return socket @ inv(chain(phi, [0.0, 0.0, 0.0]))           # socket = chain(phi, 0) @ nacelle


def vee_skew(m):
    """Rotation error vector of a rotation matrix close to the identity."""
    return 0.5 * np.array([m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1]])


def reduced_residual(free, alpha):
    """The 12 loop-closure equations: nacelle pose via chains 2 and 3 equals the pose via chain 1."""
    x = np.asarray(free)
    poses = [reduced_nacelle_via(i, alpha[i], *x[4 * i:4 * i + 4]) for i in range(3)]
    res = []
    for k in (1, 2):
        res.extend(poses[k][:3, 3] - poses[0][:3, 3])
        res.extend(vee_skew(poses[0][:3, :3].T @ poses[k][:3, :3]))
    return np.array(res)


def gauss_newton(fun, x0, tol=1e-14, max_iter=50):
    x = np.array(x0, dtype=float)
    for _ in range(max_iter):
        f = fun(x)
        if np.max(np.abs(f)) < tol:
            break
        # Jacobian by complex step: exact to rounding.
        h = 1e-30
        jac = np.empty((len(f), len(x)))
        for j in range(len(x)):
            xc = x.astype(complex)
            xc[j] += 1j * h
            jac[:, j] = fun(xc).imag / h
        step, *_ = np.linalg.lstsq(jac, -f, rcond=None)
        x = x + step
    return x, np.max(np.abs(fun(x)))


def reduced_closed(alpha, guess):
    free, res = gauss_newton(lambda x: reduced_residual(x, alpha), guess)
    coords = {}
    for i in range(3):
        coords[f"A{i + 1}.q"] = alpha[i]
        for name, value in zip(("C{}.a", "C{}.b", "P{}.a", "P{}.b"), free[4 * i:4 * i + 4]):
            coords[name.format(i + 1)] = float(value)
    nacelle = reduced_nacelle_via(0, alpha[0], *free[0:4])
    return coords, nacelle, res


def reduced_analytic(pos):
    """Closed-form coordinates of the reduced model with the nacelle translated to `pos`
    (used for rough starting guesses and as a cross-check of the Gauss-Newton solution)."""
    alpha = mgi(pos)
    out = {}
    for i, phi in enumerate(PHI):
        c = elbow(alpha[i], phi)
        u = (np.asarray(pos) - c) / L2                     # rod direction C -> P in R0
        ui = rot("z", -phi)[:3, :3] @ u                    # in R_i
        b = math.asin(ui[1])                               # ui = (-cos b sin psi, sin b, -cos b cos psi)
        psi = math.atan2(-ui[0], -ui[2])
        out[f"A{i + 1}.q"] = alpha[i]
        out[f"C{i + 1}.a"] = psi - alpha[i]
        out[f"C{i + 1}.b"] = b
        out[f"P{i + 1}.a"] = psi
        out[f"P{i + 1}.b"] = b
    return out


def bryant_xyz(m):
    """Angles (a, b, c) with m = Rx(a) Ry(b) Rz(c) (the stdlib `spherical`)."""
    b = math.asin(max(-1.0, min(1.0, m[0, 2])))
    a = math.atan2(-m[1, 2], m[2, 2])
    c = math.atan2(-m[0, 1], m[0, 0])
    return a, b, c


def full_guess(pos):
    """Coordinates of delta_isir88.lsd (parallelogram rods, spins chosen zero at the arm end)
    with the nacelle translated to `pos`; used to write that file's starting guesses."""
    red = reduced_analytic(pos)
    out = {}
    for i, phi in enumerate(PHI):
        k = i + 1
        q = red[f"A{k}.q"]
        # Relative rotation arm -> rod: Ry(psi - alpha) Rx(b); rods translate with the
        # equivalent rod, so both rods of the pair share it.
        rel = (rot("y", red[f"C{k}.a"]) @ rot("x", red[f"C{k}.b"]))[:3, :3]
        top = bryant_xyz(rel)
        # socket (axes of R_i) -> rod lower end: Ry(alpha) * rel
        bottom = bryant_xyz(rot("y", q)[:3, :3] @ rel)
        out[f"A{k}.q"] = q
        for side in ("p", "m"):
            for name, v in zip("abc", top):
                out[f"C{k}{side}.{name}"] = v
            for name, v in zip("abc", bottom):
                out[f"P{k}{side}.{name}"] = v
    return out


def spherical(a, b, c):
    return rot("x", a) @ rot("y", b) @ rot("z", c)


def full_nacelle_via(coords, k, side):
    """delta_isir88.lsd: nacelle pose reached through rod `side` ("p": +w, "m": -w) of chain k:

      join chain(phi_k, [r, 0, 0]) @ earth and arm_k with revolute([0, 1, 0]) as A_k ;
      join [l1, +-w, 0] ++ 1 @ arm_k and rod_k+- with spherical as C_k+- ;
      join chain(phi_k, [0, +-w, 0]) @ nacelle and [0, 0, -l2] ++ 1 @ rod_k+- with spherical as P_k+- ;
    """
    phi = PHI[k - 1]
    sw = W if side == "p" else -W
    g = lambda n: (coords[f"{n}.a"], coords[f"{n}.b"], coords[f"{n}.c"])
    arm = chain(phi, [R, 0.0, 0.0]) @ rot("y", coords[f"A{k}.q"])
    rod = arm @ trans([L1, sw, 0.0]) @ spherical(*g(f"C{k}{side}"))
    socket = rod @ trans([0.0, 0.0, -L2]) @ inv(spherical(*g(f"P{k}{side}")))
    return socket @ inv(chain(phi, [0.0, sw, 0.0]))


# --------------------------------------------------------------------------------------------

def main():
    here = os.path.dirname(os.path.abspath(__file__))
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    output = args[0] if args else os.path.join(here, "..", "tests", "fixtures", "delta.json")

    forward = []
    worst_t4 = 0.0
    for alpha_deg, p_mm in T4:
        alpha = [a * DEG for a in alpha_deg]
        pos = mgd(alpha)
        worst_t4 = max(worst_t4, max(abs(1000 * pos[k] - p_mm[k]) for k in range(3)))
        for i in range(3):
            assert abs(np.linalg.norm(pos - elbow(alpha[i], PHI[i])) - L2) < 1e-14
        back = mgi(pos)
        assert max(abs(back[i] - alpha[i]) for i in range(3)) < 1e-12, (alpha_deg, back)
        forward.append({"alpha_deg": list(alpha_deg), "alpha": alpha, "position": [float(v) for v in pos]})
    # Printed to 4 decimals: agreement to rounding (<= 0.5e-4 mm) plus float noise.
    assert worst_t4 <= 0.5e-4 + 1e-9, worst_t4

    inverse = []
    worst_t5 = 0.0
    for p_mm, alpha_deg in T5:
        pos = [v / 1000.0 for v in p_mm]
        alpha = mgi(pos)
        worst_t5 = max(worst_t5, max(abs(alpha[i] / DEG - alpha_deg[i]) for i in range(3)))
        assert np.max(np.abs(mgd(alpha) - np.array(pos))) < 1e-12
        inverse.append({"position_mm": list(p_mm), "position": pos, "alpha": alpha})
    assert worst_t5 <= 0.5e-6 + 1e-9, worst_t5

    # Symmetric closed form z(alpha) = -l1 sin a - sqrt(l2^2 - (r + l1 cos a)^2).
    for a_deg in (30, 40, 45, 60, 90):
        a = a_deg * DEG
        z = -L1 * math.sin(a) - math.sqrt(L2 ** 2 - (R + L1 * math.cos(a)) ** 2)
        assert abs(mgd([a] * 3)[2] - z) < 1e-14

    # Unreachable pose T3.
    try:
        mgd([0.0, 0.0, 0.0])
        raise AssertionError("alpha = 0 should not assemble")
    except NoAssembly:
        pass

    # Reduced model closed at alpha = 40 deg x 3, by Gauss-Newton from rough guesses (the values
    # written as `initial` in delta_isir88_reduced.lsd).
    alpha40 = [40 * DEG] * 3
    rough = [0.50, 0.0, 1.20, 0.0,  0.50, 0.0, 1.20, 0.0,  0.50, 0.0, 1.20, 0.0]
    coords, nacelle, res = reduced_closed(alpha40, rough)
    assert res < 1e-12, res
    p_mgd = mgd(alpha40)
    assert np.max(np.abs(nacelle[:3, 3] - p_mgd)) < 1e-12, (nacelle[:3, 3], p_mgd)
    assert np.max(np.abs(nacelle[:3, :3] - np.eye(3))) < 1e-12   # parallel to the base
    analytic = reduced_analytic(p_mgd)
    assert max(abs(coords[k] - analytic[k]) for k in coords) < 1e-12

    # The full model's closed configuration used for its guesses: all six rod paths give the
    # same translated nacelle.
    for alpha_f in (alpha40, [20 * DEG, 40 * DEG, 60 * DEG]):
        p_f = mgd(alpha_f)
        full = full_guess(p_f)
        for k in (1, 2, 3):
            for side in "pm":
                pose = full_nacelle_via(full, k, side)
                assert np.max(np.abs(pose[:3, 3] - p_f)) < 1e-12
                assert np.max(np.abs(pose[:3, :3] - np.eye(3))) < 1e-12

    # Also a less symmetric pose, as a check of the solver and conventions (not recorded).
    alpha_b = [20 * DEG, 40 * DEG, 60 * DEG]
    guess_b = [analytic_v for k, analytic_v in reduced_analytic(mgd(alpha_b)).items() if not k.startswith("A")]
    coords_b, nacelle_b, res_b = reduced_closed(alpha_b, [round(v, 1) for v in guess_b])
    assert res_b < 1e-12 and np.max(np.abs(nacelle_b[:3, 3] - mgd(alpha_b))) < 1e-12
    assert np.max(np.abs(nacelle_b[:3, :3] - np.eye(3))) < 1e-12

    data = {
        "provenance": (
            "Computed by bench/delta_reference.py (numpy; independent of lsdc). Delta ISIR88, "
            "Nadour & Mokhtari, ENP Alger 2016, as summarised in the project's notes on the Delta seed (\"seed-delta\"). "
            "forward: MGD by the circumcircle method (notes 3.2) at the alpha rows of table T4 "
            "(the 48.205906 deg row uses that printed value); inverse: MGI of notes 3.3 with the "
            "[fix] corrections (beta = atan2(-z_i, x_i - r), delta with l1, alpha = beta - delta) at "
            "the positions of table T5. Both reproduce T4 (to the printed 1e-4 mm) and T5 (to the "
            "printed 1e-6 deg), round-trip to 1e-12 and satisfy |P - C_i| = l2 to 1e-14 m. "
            "reduced_closed_40deg: examples/delta_isir88_reduced.lsd (frames and join directions of "
            "that file) closed by Gauss-Newton with the arm angles fixed at 40 deg, loop residual "
            "< 1e-12; its nacelle is parallel to the base and at the MGD position to 1e-12 m. "
            "Convention: alpha_i is the notes' alpha (positive downwards), the angle of the "
            "revolute A_i about +y_i of the chain frame R_i = Rz(phi_i); z up, workspace z < 0. "
            "Units: m, rad."
        ),
        "parameters": {
            "l1": L1, "l2": L2, "R1": R1, "R2": R2, "r": R,
            "phi": PHI,
            "rod_pair_half_width": W,
            "rod_pair_half_width_note": "invented for examples/delta_isir88.lsd; not in the thesis",
        },
        "forward": [{"alpha": f["alpha"], "position": f["position"]} for f in forward],
        "inverse": [{"position": i["position"], "alpha": i["alpha"]} for i in inverse],
        "reduced_closed_40deg": {
            "alpha": alpha40,
            "coords": {k: coords[k] for k in REDUCED_NAMES},
            "nacelle_position": [float(v) for v in nacelle[:3, 3]],
            "loop_residual": float(res),
        },
    }
    os.makedirs(os.path.dirname(os.path.abspath(output)), exist_ok=True)
    with open(output, "w") as f:
        json.dump(data, f, indent=2)
        f.write("\n")

    # Report (and the rounded guesses written in the example files).
    print(f"T4 worst |P - table| = {worst_t4:.3g} mm; T5 worst |alpha - table| = {worst_t5:.3g} deg")
    print(f"reduced 40 deg: residual {res:.3g}, nacelle {nacelle[:3, 3]}, MGD {p_mgd}")
    if "--guesses" in sys.argv:
        for label, table in (("reduced 40deg", coords),
                             ("reduced P=(0,0,-0.3)", reduced_analytic([0, 0, -0.3])),
                             ("full 40deg", full_guess(p_mgd))):
            print(label)
            for k, v in table.items():
                print(f"  {k} = {v:.6f}  ({v / DEG:.3f} deg)")
    print(f"wrote {output}")


if __name__ == "__main__":
    main()
