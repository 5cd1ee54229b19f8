"""Shared helpers of the hard-set reference scripts (bench/hard/).

Written for these scripts only; it imports nothing from lsdc and reads nothing of it but the CSV
samples that `lsdc simulate` writes (a header line of column names, then one line per sample).

  * `dh(theta, d, a, alpha)`: the Denavit-Hartenberg matrix Rz(theta) Tz(d) Tx(a) Rx(alpha)
    (standard, "distal" convention; Denavit & Hartenberg 1955), complex-safe;
  * `read_csv(path)`: the samples as a dict of numpy arrays keyed by column name;
  * `OneDof`: the Lagrangian of a mobility-1 mechanism reduced to one coordinate theta, from the
    poses of its bodies as functions of theta (the loops solved in closed form or numerically by
    the caller): mass M(theta) = sum over bodies of m |dc/dtheta|^2 + w^T I w (w the angular
    velocity per unit rate, in body axes), potential V(theta) = -sum m g.c, energy
    E = 1/2 M theta'^2 + V, and the reduced equation theta'' = (-V' - 1/2 M' theta'^2) / M,
    integrated with scipy's DOP853 at tight tolerances.
"""

import csv
import math

import numpy as np
from scipy.integrate import solve_ivp


def rotx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1]], dtype=np.result_type(a, float))


def rotz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], dtype=np.result_type(a, float))


def trans(x, y, z):
    m = np.eye(4, dtype=np.result_type(x, y, z, float))
    m[0, 3], m[1, 3], m[2, 3] = x, y, z
    return m


def dh(theta, d, a, alpha):
    return rotz(theta) @ trans(0.0, 0.0, d) @ trans(a, 0.0, 0.0) @ rotx(alpha)


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, data = rows[0], np.array([[float(x) if x else float("nan") for x in r] for r in rows[1:] if r and not r[0].startswith("#")], dtype=float)
    if data.size == 0:
        data = np.zeros((0, len(header)))
    return {name: data[:, i] for i, name in enumerate(header)}


def wrap(x):
    """Angle difference wrapped into (-pi, pi]."""
    return (np.asarray(x) + math.pi) % (2 * math.pi) - math.pi


class Body:
    def __init__(self, mass, com, inertia):
        self.mass = float(mass)
        self.com = np.array(list(com) + [1.0])
        self.inertia = np.diag(inertia)


class OneDof:
    """poses(theta) -> list of 4x4 world poses, one per entry of `bodies` (principal axes of the
    bodies' inertia along their frame axes). gravity: acceleration vector."""

    def __init__(self, bodies, poses, gravity, h=1e-6):
        self.bodies, self.poses, self.g, self.h = bodies, poses, np.asarray(gravity, float), h

    def _derivs(self, th):
        h = self.h
        p0 = self.poses(th)
        pp, pm = self.poses(th + h), self.poses(th - h)
        return p0, [(a - b) / (2 * h) for a, b in zip(pp, pm)]

    def mass(self, th):
        p0, dp = self._derivs(th)
        m = 0.0
        for b, P, dP in zip(self.bodies, p0, dp):
            v = (dP @ b.com)[:3]
            R, dR = P[:3, :3], dP[:3, :3]
            W = R.T @ dR  # body-axis angular velocity per unit rate (skew)
            w = np.array([W[2, 1], W[0, 2], W[1, 0]])
            m += b.mass * v @ v + w @ b.inertia @ w
        return m

    def potential(self, th):
        return -sum(b.mass * self.g @ (P @ b.com)[:3] for b, P in zip(self.bodies, self.poses(th)))

    def energy(self, th, om):
        return 0.5 * self.mass(th) * om * om + self.potential(th)

    def accel(self, th, om):
        k = 1e-4
        dm = (self.mass(th + k) - self.mass(th - k)) / (2 * k)
        dv = (self.potential(th + k) - self.potential(th - k)) / (2 * k)
        return (-dv - 0.5 * dm * om * om) / self.mass(th)

    def fit(self, lo=None, hi=None, n=256):
        """Replace M and V by interpolants for the integration: a trigonometric interpolant on
        n points of [0, 2 pi) when lo is None (a mechanism periodic in theta), else a Chebyshev
        interpolant of degree n on [lo, hi]. Spectrally accurate for these smooth functions."""
        if lo is None:
            th = 2 * np.pi * np.arange(n) / n
            fm = np.fft.rfft([self.mass(x) for x in th]) / n
            fv = np.fft.rfft([self.potential(x) for x in th]) / n
            k = np.arange(len(fm))
            w = np.where((k == 0) | (k == n // 2), 1.0, 2.0)

            def ev(c, x, d):
                z = (1j * k) ** d * np.exp(1j * k * x)
                return float(np.real(np.sum(w * c * z)))

            self._m = lambda x, d=0: ev(fm, x, d)
            self._v = lambda x, d=0: ev(fv, x, d)
        else:
            from numpy.polynomial import chebyshev as C
            cm = C.Chebyshev.interpolate(self.mass, n, domain=[lo, hi])
            cv = C.Chebyshev.interpolate(self.potential, n, domain=[lo, hi])
            dm, dv = cm.deriv(), cv.deriv()
            self._m = lambda x, d=0: float(cm(x) if d == 0 else dm(x))
            self._v = lambda x, d=0: float(cv(x) if d == 0 else dv(x))
        return self

    def integrate(self, th0, om0, times, rtol=1e-12, atol=1e-12):
        """The reduced equation integrated with the interpolants of `fit` (call it first)."""
        def rhs(t, y):
            return [y[1], (-self._v(y[0], 1) - 0.5 * self._m(y[0], 1) * y[1] ** 2) / self._m(y[0])]
        sol = solve_ivp(rhs, (times[0], times[-1]), [th0, om0], method="DOP853", t_eval=times,
                        rtol=rtol, atol=atol)
        return sol.y[0], sol.y[1]
