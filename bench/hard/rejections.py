#!/usr/bin/env python3
"""How many steps would dopri5 reject on the hard set's spatial linkages if their equations were
as smooth as can be: the reduced one-coordinate Lagrange equation of bench/hard/bennett.py and
bench/hard/bricard.py (independent of lsdc), integrated here by the Dormand-Prince 5(4) pair
with lsdc's step control (src/integrate/control.rs: Hairer's proportional-integral gains for
DOPRI5, safety 0.9, factors in [0.2, 10], no growth after a rejection, Gustafsson's predictive
limit) and, for comparison, with scipy's RK45 (elementary control). Same start (the state lsdc
assembles, read from its CSV), same 3 s, rtol = atol = TOL on the two components.

Usage: bench/hard/rejections.py BENNETT.csv BRICARD.csv   (CSV files of `lsdc simulate`)
Prints, per linkage and tolerance: accepted steps and rejected attempts of each controller.
"""

import math
import os
import sys

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bennett  # noqa: E402
import bricard  # noqa: E402
from hardlib import read_csv  # noqa: E402

C = [0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1, 1]
A = [[], [1 / 5], [3 / 40, 9 / 40], [44 / 45, -56 / 15, 32 / 9],
     [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729],
     [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656],
     [35 / 384, 0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84]]
B = A[6] + [0]
E = [71 / 57600, 0, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40]


def dopri5(f, y0, t_end, tol, h):
    """(accepted, rejected) with lsdc's controller from step h."""
    t, y, k1 = 0.0, y0.copy(), f(y0)
    accepted = rejected = 0
    previous_error, previous, just_rejected = 1e-4, None, False
    while t < t_end:
        if t + 1.01 * h >= t_end:
            h = t_end - t
        k = [k1]
        for i in range(1, 7):
            k.append(f(y + h * sum(a * kj for a, kj in zip(A[i], k))))
        y_new = y + h * sum(b * kj for b, kj in zip(B, k))
        scale = tol + tol * np.maximum(abs(y), abs(y_new))
        error = math.sqrt(np.mean((h * sum(e * kj for e, kj in zip(E, k)) / scale) ** 2))
        if error > 1.0:
            rejected += 1
            just_rejected = True
            h *= max(0.2, min(1.0, 0.9 * error ** -0.2))
            continue
        accepted += 1
        error = max(error, 1e-10)
        top = 1.0 if just_rejected else 10.0
        factor = min(max(0.9 * error ** -(0.2 - 0.75 * 0.04) * previous_error ** 0.04, 0.2), top)
        if previous:
            growth = (previous[0] / h) * (error * error / previous[1]) ** 0.2
            factor = min(factor, min(max(0.9 / growth, 0.2), top))
        previous_error, previous, just_rejected = max(error, 1e-4), (h, max(error, 1e-2)), False
        t, y, k1, h = t + h, y_new, k[6], h * factor
    return accepted, rejected


def first_step(f, y0, tol):
    """lsdc's first step (src/integrate/driver.rs, after Hairer, Norsett and Wanner II.4)."""
    f0 = f(y0)
    scale = tol + tol * abs(y0)
    size_y, size_f = (math.sqrt(np.mean((x / scale) ** 2)) for x in (y0, f0))
    guess = 1e-6 if min(size_y, size_f) < 1e-5 else 0.01 * size_y / size_f
    change = (f(y0 + guess * f0) - f0) / guess
    largest = max(size_f, math.sqrt(np.mean((change / scale) ** 2)))
    return min(100 * guess, (0.01 / largest) ** (1 / 6))


def reduced(model):
    def f(y):
        m = model._m(y[0])
        return np.array([y[1], (-model._v(y[0], 1) - 0.5 * model._m(y[0], 1) * y[1] ** 2) / m])
    return f


def main():
    bricard.MODEL.fit(n=128)
    for (name, module), path in zip([("bennett", bennett), ("bricard", bricard)], sys.argv[1:3]):
        s = read_csv(path)
        y0 = np.array([s["j1.q"][0], s["j1.q'"][0]])
        f = reduced(module.MODEL)
        for tol in [1e-4, 1e-5, 1e-6, 1e-7, 1e-8]:
            ours = dopri5(f, y0, 3.0, tol, first_step(f, y0, tol))
            sol = solve_ivp(lambda _, y: f(y), (0, 3), y0, method="RK45", rtol=tol, atol=tol)
            scipy = (len(sol.t) - 1, round((sol.nfev - 2) / 6) - (len(sol.t) - 1))
            print(f"{name} {tol:.0e}: lsdc's control {ours[0]} ({ours[1]} rejected), "
                  f"scipy RK45 {scipy[0]} ({scipy[1]} rejected)")


if __name__ == "__main__":
    main()
