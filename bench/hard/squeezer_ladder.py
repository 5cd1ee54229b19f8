#!/usr/bin/env python3
"""Global error against tolerance on Andrews' squeezer, lsdc's dop853 beside scipy's DOP853.

The error at t = 0.03 s (largest position error against the test set's published solution, see
squeezer.py) over a ladder of tolerances rtol = atol = 10^(-6 - k/6), k = 0..18: lsdc
integrates examples/hard/squeezer.lsd (tree coordinates, the loops projected after each step),
scipy the test set's index-1 equations written out in squeezer.py (no projection). Both show
a tighter tolerance giving a larger error here and there (by up to 5 times): tolerance
proportionality of an adaptive method holds in the trend, not step by step of the ladder
(docs/guarantees.md, "Accuracy against tolerance").

Usage: bench/hard/squeezer_ladder.py PATH/TO/lsdc   (needs numpy and scipy)
"""

import csv
import os
import subprocess
import sys

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import squeezer  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PROGRAM = os.path.join(ROOT, "examples", "hard", "squeezer.lsd")


def lsdc_error(lsdc, tol):
    out = subprocess.run([lsdc, "simulate", PROGRAM, "--integrator", "dop853", "--tolerance",
                          repr(tol), "--every", "0.03"], capture_output=True, text=True, check=True)
    rows = list(csv.DictReader(l for l in out.stdout.splitlines() if not l.startswith("#")))
    q = np.array([float(rows[-1][n + ".q"]) for n in squeezer.NAMES])
    steps = out.stderr.split(" steps")[0].split(": ")[-1]
    return float(np.abs(q - squeezer.PUBLISHED_Q).max()), steps


def scipy_error(tol):
    x0 = np.concatenate([squeezer.Y0, np.zeros(7)])
    sol = solve_ivp(squeezer.rhs, (0.0, 0.03), x0, method="DOP853", rtol=tol, atol=tol)
    return float(np.abs(sol.y[:7, -1] - squeezer.PUBLISHED_Q).max()), len(sol.t) - 1


def main():
    print("| tolerance | scipy DOP853 error (steps) | lsdc dop853 error (steps) |")
    print("|---:|---:|---:|")
    for k in range(19):
        tol = 10 ** (-6 - k / 6)
        (e_scipy, n_scipy), (e_lsdc, n_lsdc) = scipy_error(tol), lsdc_error(sys.argv[1], tol)
        print(f"| {tol:.3g} | {e_scipy:.2e} ({n_scipy}) | {e_lsdc:.2e} ({n_lsdc}) |")


if __name__ == "__main__":
    main()
