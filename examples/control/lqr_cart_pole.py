#!/usr/bin/env python3
"""A balancing gain for the cart-pole of cart_pole.lsd, from `lsdc linearize` output.

Runs `lsdc linearize examples/control/cart_pole.lsd --input rail.q --format json`, reads A and B
(the keys of its JSON, arrays of rows), and computes the linear-quadratic regulator's gain
K = R^-1 B^T P, with P the stabilising solution of the continuous algebraic Riccati equation

    A^T P + P A - P B R^-1 B^T P + Q = 0,

for Q = diag(Q_DIAGONAL) and R = R_INPUT. The Riccati equation is solved with the matrix sign
function of its Hamiltonian H = [[A, -B R^-1 B^T], [-Q, -A^T]] (J. D. Roberts, "Linear model
reduction and solution of the algebraic Riccati equation by use of the sign function",
Int. J. Control 32(4), 1980; scaled Newton iteration Z <- (Z / c + c Z^-1) / 2 with
c = |det Z|^(1/2n), J. D. Gardiner and A. J. Laub, Int. J. Control 44(3), 1986): with
W = sign(H), P solves [W12; W22 + I] P = -[W11 + I; W21] in the least-squares sense. Plain
Python, no package needed; with python-control installed, `control.lqr(A, B, Q, R)` gives
the same K (the JSON reads directly: `control.ss(m["A"], m["B"], m["C"], m["D"])`).

Prints a JSON object: the gain `K` (one row, along the states' names `states`), the Riccati
equation's largest residual, and the gains as `let` lines for cart_pole_lqr.lsd.

Usage: python3 examples/control/lqr_cart_pole.py [--lsdc PATH]   (from the repository root)
"""

import argparse
import json
import subprocess
import sys

# Weights: the cart's position and the pole's angle (m, rad) and their rates.
Q_DIAGONAL = [1.0, 10.0, 1.0, 1.0]
R_INPUT = 1.0
SIGN_ITERATIONS = 100


def identity(n):
    return [[1.0 if i == j else 0.0 for j in range(n)] for i in range(n)]


def multiply(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(len(b))) for j in range(len(b[0]))]
            for i in range(len(a))]


def transpose(a):
    return [list(row) for row in zip(*a)]


def add(a, b, scale=1.0):
    return [[x + scale * y for x, y in zip(ra, rb)] for ra, rb in zip(a, b)]


def inverse_and_determinant(a):
    """Gauss-Jordan elimination with partial pivoting."""
    n = len(a)
    m = [list(row) + e for row, e in zip(a, identity(n))]
    determinant = 1.0
    for c in range(n):
        pivot = max(range(c, n), key=lambda r: abs(m[r][c]))
        if m[pivot][c] == 0.0:
            raise ValueError("singular matrix")
        if pivot != c:
            m[c], m[pivot] = m[pivot], m[c]
            determinant = -determinant
        determinant *= m[c][c]
        scale = 1.0 / m[c][c]
        m[c] = [x * scale for x in m[c]]
        for r in range(n):
            if r != c and m[r][c] != 0.0:
                factor = m[r][c]
                m[r] = [x - factor * y for x, y in zip(m[r], m[c])]
    return [row[n:] for row in m], determinant


def riccati(a, b, q, r):
    """The stabilising solution P of A^T P + P A - P B R^-1 B^T P + Q = 0 (see the docstring)."""
    n = len(a)
    r_inverse, _ = inverse_and_determinant(r)
    s = multiply(multiply(b, r_inverse), transpose(b))
    hamiltonian = [a[i] + [-x for x in s[i]] for i in range(n)]
    hamiltonian += [[-x for x in q[i]] + [-a[j][i] for j in range(n)] for i in range(n)]
    z = hamiltonian
    for _ in range(SIGN_ITERATIONS):
        z_inverse, determinant = inverse_and_determinant(z)
        c = abs(determinant) ** (1.0 / (2 * n))
        following = [[0.5 * (x / c + c * y) for x, y in zip(rz, ri)] for rz, ri in zip(z, z_inverse)]
        change = max(abs(x - y) for rf, rz in zip(following, z) for x, y in zip(rf, rz))
        z = following
        if change < 1e-14 * max(abs(x) for row in z for x in row):
            break
    w11 = [row[:n] for row in z[:n]]
    w12 = [row[n:] for row in z[:n]]
    w21 = [row[:n] for row in z[n:]]
    w22 = [row[n:] for row in z[n:]]
    left = w12 + add(w22, identity(n))
    right = [[-x for x in row] for row in add(w11, identity(n)) + w21]
    normal, _ = inverse_and_determinant(multiply(transpose(left), left))
    p = multiply(normal, multiply(transpose(left), right))
    return [[0.5 * (p[i][j] + p[j][i]) for j in range(n)] for i in range(n)]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--lsdc", default="target/debug/lsdc")
    parser.add_argument("--program", default="examples/control/cart_pole.lsd")
    arguments = parser.parse_args()
    command = [arguments.lsdc, "linearize", arguments.program, "--input", "rail.q",
               "--format", "json"]
    model = json.loads(subprocess.run(command, check=True, capture_output=True, text=True).stdout)
    a, b = model["A"], model["B"]
    n = len(a)
    q = [[Q_DIAGONAL[i] if i == j else 0.0 for j in range(n)] for i in range(n)]
    r = [[R_INPUT]]
    p = riccati(a, b, q, r)
    r_inverse, _ = inverse_and_determinant(r)
    gain = multiply(r_inverse, multiply(transpose(b), p))
    pa = multiply(p, a)
    pb = multiply(p, b)
    residual = add(add(transpose(pa), pa), q)
    residual = add(residual, multiply(multiply(pb, r_inverse), transpose(pb)), -1.0)
    largest = max(abs(x) for row in residual for x in row)
    names = ["k_" + s.replace(".", "_").replace("'", "_rate") for s in model["states"]]
    lines = [f"let {name} = {k!r} ;" for name, k in zip(names, gain[0])]
    json.dump({"states": model["states"], "K": gain[0], "riccati_residual": largest,
               "lsd": lines}, sys.stdout, indent=2)
    print()


if __name__ == "__main__":
    main()
