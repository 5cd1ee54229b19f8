#!/usr/bin/env python3
"""Reference for the rigid (mobility-0) mechanisms examples/hard/truss.lsd and
examples/hard/double_revolute.lsd.

Source: the mechanisms are made up for this test set; the method is the classical first-order
rigidity test (e.g. Asimow & Roth, "The rigidity of graphs", Trans. AMS 245 (1978) 279): a
configuration at which the constraint Jacobian in absolute coordinates has a trivial kernel is
rigid (isolated), whatever higher-order terms say.

Method (independent of lsdc): every moving body gets 6 absolute coordinates (a small translation
t and rotation vector w applied on the world side of its pose); a revolute about z at the world
point p between bodies a and b gives 5 rows: the gap between the two copies of the point
(t_a + R(w_a) p) - (t_b + R(w_b) p), and the components along x and y of z_a x z_b. The
Jacobian at the assembled configuration (central differences, exact for these functions up to
rounding) gives mobility = 6 (number of bodies) - rank (SVD, relative tolerance 1e-9). Then the
CSV output of lsdc is checked for "nothing moves": every coordinate keeps its starting value and
every rate stays 0.

Usage: bench/hard/rigid.py truss|double_revolute [FILE.csv]   (prints a JSON summary)
"""

import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from hardlib import read_csv  # noqa: E402

C = (0.5, 0.8, 0.0)
MECHANISMS = {
    # bodies (earth is 0), pins (body a, body b, world point)
    "truss": (3, [(0, 1, (0, 0, 0)), (0, 2, (1, 0, 0)), (1, 2, (1, 0, 0)), (2, 3, C), (3, 1, (0, 0, 0))]),
    "double_revolute": (1, [(0, 1, (0, 0, 0)), (0, 1, (1, 0, 0))]),
}


def rot(w):
    th = np.linalg.norm(w)
    if th == 0:
        return np.eye(3)
    k = w / th
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(th) * K + (1 - math.cos(th)) * K @ K


def rows(x, nb, pins):
    dof = np.concatenate([np.zeros(6), x]).reshape(nb + 1, 6)
    out = []
    for a, b, p in pins:
        p = np.asarray(p, float)
        ra, rb = rot(dof[a, 3:]), rot(dof[b, 3:])
        out += list(dof[a, :3] + ra @ p - dof[b, :3] - rb @ p)
        c = np.cross(ra[:, 2], rb[:, 2])
        out += [c[0], c[1]]
    return np.array(out)


def mobility(name):
    nb, pins = MECHANISMS[name]
    h = 1e-6
    J = np.array([(rows(h * e, nb, pins) - rows(-h * e, nb, pins)) / (2 * h) for e in np.eye(6 * nb)]).T
    s = np.linalg.svd(J, compute_uv=False)
    rank = int(np.sum(s > 1e-9 * s[0]))
    return 6 * nb - rank, len(pins) * 5, rank


def check(name, path):
    m, nrows, rank = mobility(name)
    out = {"mechanism": name, "mobility_reference": m, "constraint_rows": nrows, "rank": rank}
    if path:
        s = read_csv(path)
        if len(s["time"]) < 2:
            out.update(ok=False, reason="fewer than two samples")
            return out
        qs = [k for k in s if k.endswith(".q")]
        vs = [k for k in s if k.endswith(".q'")]
        out["max_coordinate_change"] = max(float(np.abs(s[k] - s[k][0]).max()) for k in qs)
        out["max_rate"] = max(float(np.abs(s[k]).max()) for k in vs)
        out["t_end"] = float(s["time"][-1])
        out["ok"] = out["max_coordinate_change"] < 1e-9 and out["max_rate"] < 1e-9
    return out


if __name__ == "__main__":
    print(json.dumps(check(sys.argv[1], sys.argv[2] if len(sys.argv) > 2 else None), indent=1))
