#!/usr/bin/env python3
"""The gain table of gain_scheduled_delta.lsd, from `lsdc linearize` of that program.

The Delta seed's gain scheduling (notes on the Delta seed, §6 and R13): at operating points
E_0 = (X_0, U_0) taken along the reference, state feedback with integral action whose gains
K = [K_x K_s] place the poles of the 12-state augmented system A_e - B_e K. For each operating
time t_k of TIMES:

1. the reference's angles, rates and accelerations r, r', r'' at t_k (the quintics of
   gain_scheduled_delta.lsd, written again here: `reference`);
2. `lsdc linearize PROGRAM --set law=0` (the plant alone: the law's voltage switched off, the
   voltages the constant states leg[i]:voltage_input held as inputs) with the arms at r and
   r' and no current, with the arms' torques as inputs too: the accelerations a there and the
   torques' columns of B (exact) give the current I_0 that makes r'', the accelerations being
   affine in the torque 12 K_i I (the seed's X3_0 = N^-1 (12 r'' - M));
3. the same at X_0 = (r, r', I_0), the voltages the only inputs: A and B are the seed's A_e and
   B_e themselves, the program's integral states (Z' = alpha - r) being their last three rows
   (the accelerations there are checked to be r'' within 1e-9 rad/s^2);
4. the gains by pole placement (scipy.signal.place_poles: Kautz, Nichols & Van Dooren,
   "Robust pole assignment in linear state feedback", Int. J. Control 41(5), 1985, with
   Tits & Yang's update, IEEE TAC 41(10), 1996), each pole of POLES once per arm (a
   multiplicity of 3, the rank of B_e), the eigenvalues of A_e - B_e K checked against them.

It then writes the table between the lines "(* The gain table" and "(* End of the gain
table. *)" of PROGRAM: the interpolation's weights (hat functions of time: the gains linear in
time between operating points, held before the first and after the last) and, for each point,
its time, X_0, and the four 3 x 3 blocks of K (angles, rates, currents, integrals), the
numbers written to read back exactly. It prints how far the eigenvalues are from the poles at
the points and between them: at the middle of each interval of the moves, with the gains
interpolated as the law interpolates them, and with the first point's gains frozen (what the
schedule is for). Needs numpy and scipy; takes a minute (84 linearisations).

Usage: python3 examples/control/gain_schedule_delta.py [--lsdc PATH]   (from the repository root)
"""

import argparse
import json
import math
import subprocess
import warnings

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.signal import place_poles

PROGRAM = "examples/control/gain_scheduled_delta.lsd"
# The poles (1/s): three of the arms' motion and the winding's, each once per arm.
POLES = [-100.0, -120.0, -140.0, -2250.0]
# The operating points: every 0.05 s along the move out (0.2 to 0.7 s) and back (1.0 to
# 1.5 s); the reference rests between them, where the gains are those of its ends.
TIMES = ([round(0.2 + 0.05 * k, 2) for k in range(11)]
         + [round(1.0 + 0.05 * k, 2) for k in range(11)])
# The reference of gain_scheduled_delta.lsd: from 40 degrees, each arm out by its move in
# 0.2 to 0.7 s and back in 1.0 to 1.5 s, on quintics.
START = 40 * math.pi / 180
MOVES = [0.3, -0.1, 0.2]
# The motor's torque constant and the reduction (the arm's torque is N K_i I).
K_I, N = 0.119, 12
ARMS = ["leg[1]", "leg[2]", "leg[3]"]
BEGIN, END = "(* The gain table", "(* End of the gain table. *)"


def quintic(t, t0, t1, d):
    """The quintic from 0 at t0 to d at t1 at rest at both ends, and its two derivatives."""
    span = t1 - t0
    s = min(max((t - t0) / span, 0.0), 1.0)
    return (d * (10 * s**3 - 15 * s**4 + 6 * s**5),
            d * (30 * s**2 - 60 * s**3 + 30 * s**4) / span,
            d * (60 * s - 180 * s**2 + 120 * s**3) / span**2)


def reference(t):
    """The arms' reference angles, rates and accelerations at t."""
    laws = [[a + b for a, b in zip(quintic(t, 0.2, 0.7, d), quintic(t, 1.0, 1.5, -d))]
            for d in MOVES]
    angles, rates, accelerations = (np.array(values) for values in zip(*laws))
    return angles + START, rates, accelerations


def linearize(lsdc, angles, rates, currents, inputs):
    """`lsdc linearize` of the plant (the law off) at the arms' angles, rates and currents."""
    command = [lsdc, "linearize", PROGRAM, "--set", "law=0", "--format", "json"]
    for arm, angle, rate, current in zip(ARMS, angles, rates, currents):
        command += ["--coordinate", f"{arm}:A.q",
                    "--set", f"{arm}:alpha0={float(angle)!r}",
                    "--set", f"{arm}:rate0={float(rate)!r}",
                    "--set", f"{arm}:current0={float(current)!r}"]
    for name in inputs:
        command += ["--input", name]
    return json.loads(subprocess.run(command, check=True, capture_output=True, text=True).stdout)


def operating_point(lsdc, t):
    """The operating point at t: (angles, rates, currents) and the linear model there."""
    angles, rates, accelerations = reference(t)
    voltages = [f"{arm}:voltage_input" for arm in ARMS]
    torques = [f"{arm}:A.q" for arm in ARMS]
    unpowered = linearize(lsdc, angles, rates, [0.0] * 3, voltages + torques)
    response = np.array(unpowered["B"])[3:6, 3:6]  # the accelerations per unit torque
    currents = np.linalg.solve(N * K_I * response,
                               accelerations - np.array(unpowered["accelerations"]))
    model = linearize(lsdc, angles, rates, currents, voltages)
    expected = ([f"{arm}:A.q" for arm in ARMS] + [f"{arm}:A.q'" for arm in ARMS]
                + [f"{arm}:current" for arm in ARMS] + [f"{arm}:integral" for arm in ARMS])
    # The plant's states; the observer's (held with the law off, and which the plant then does
    # not read: its rows of A are zero on their columns) left out.
    if not set(expected) <= set(model["states"]) or model["inputs"] != voltages:
        raise SystemExit(f"unexpected states {model['states']} or inputs {model['inputs']}")
    plant = [model["states"].index(name) for name in expected]
    others = [k for k in range(len(model["states"])) if k not in plant]
    a_full = np.array(model["A"])
    if np.abs(a_full[np.ix_(plant, others)]).max(initial=0.0) != 0.0:
        raise SystemExit(f"t = {t}: the plant reads the observer with the law off")
    missed = np.abs(np.array(model["accelerations"]) - accelerations).max()
    if missed > 1e-9:
        raise SystemExit(f"t = {t}: the accelerations miss the reference's by {missed:e}")
    return angles, rates, currents, a_full[np.ix_(plant, plant)], np.array(model["B"])[plant]


def eigenvalue_gap(a, b, gain):
    """How far the eigenvalues of A_e - B_e K are from POLES: the largest distance of one from
    the pole it is matched to (the matching of least total distance), relative to the pole,
    and the slowest eigenvalue's real part."""
    poles = np.repeat(POLES, 3)
    eigenvalues = np.linalg.eigvals(a - b @ gain)
    distance = np.abs(eigenvalues[:, None] - poles[None, :]) / np.abs(poles)[None, :]
    rows, columns = linear_sum_assignment(distance)
    return distance[rows, columns].max(), eigenvalues.real.max()


def gains(a, b):
    """The gain K placing POLES (each once per arm) on A_e - B_e K, checked."""
    with warnings.catch_warnings():
        # Tits and Yang's iteration, which improves the eigenvectors' conditioning, reports no
        # convergence when poles repeat; the placement itself is checked below.
        warnings.simplefilter("ignore", UserWarning)
        gain = place_poles(a, b, np.repeat(POLES, 3), method="YT").gain_matrix
    gap, _ = eigenvalue_gap(a, b, gain)
    if gap > 1e-9:
        raise SystemExit(f"the poles were not placed: {np.linalg.eigvals(a - b @ gain)}")
    return gain, gap


def between_points(lsdc, points):
    """The schedule between operating points: at the middle of each interval of the moves, the
    eigenvalues with the gains interpolated as the law interpolates them, and with the first
    point's gains frozen (no scheduling): each the largest relative gap and the slowest real
    part."""
    interpolated, frozen = [], []
    spacing = points[1][0] - points[0][0]
    for (t0, *_, k0), (t1, *_, k1) in zip(points, points[1:]):
        if t1 - t0 > spacing + 1e-9:
            continue  # the reference rests: the two points are one
        *_, a, b = operating_point(lsdc, (t0 + t1) / 2)
        interpolated.append(eigenvalue_gap(a, b, (k0 + k1) / 2))
        frozen.append(eigenvalue_gap(a, b, points[0][-1]))
    return ([max(g for g, _ in gaps) for gaps in (interpolated, frozen)],
            [max(s for _, s in gaps) for gaps in (interpolated, frozen)])


def numbers(values):
    return "[" + ", ".join(repr(float(v)) for v in values) + "]"


def matrix(block):
    return "[" + ",\n    ".join(numbers(row) for row in block) + "]"


def table(points):
    """The text of the gain table."""
    times = [t for t, *_ in points]
    last = len(points) - 1
    weights = [f"(1 - linear(time, {times[0]}, 0, {times[1]}, 1))"]
    weights += [f"hat({times[k - 1]}, {times[k]}, {times[k + 1]})" for k in range(1, last)]
    weights += [f"linear(time, {times[last - 1]}, 0, {times[last]}, 1)"]
    parameters = ", ".join(f"f{k}" for k in range(len(points)))
    terms = "\n  + ".join(f"{w} * f{k}" for k, w in enumerate(weights))
    poles = ", ".join(f"{p:g}" for p in POLES)
    lines = [
        f"{BEGIN}, written by `python3 examples/control/gain_schedule_delta.py` from",
        "   `lsdc linearize` of this program with `--set law=0` (do not edit it by hand): the",
        f"   poles {poles} (1/s), each once per arm. For each operating point its time",
        "   (s), the reference's angles (rad) and rates (rad/s) and the current I_0 (A), then",
        "   feedback(K_angle, K_rate, K_current, K_integral), the blocks of K by rows. *)",
        "let hat(t0, t1, t2) = linear(time, t0, 0, t1, 1) - linear(time, t1, 0, t2, 1) ;",
        f"let schedule({parameters}) =\n  {terms} ;",
    ]
    for k, (t, angles, rates, currents, gain) in enumerate(points):
        lines.append(f"(* {k}: t = {t}, angles {numbers(angles)},")
        lines.append(f"   rates {numbers(rates)},")
        lines.append(f"   currents {numbers(currents)} *)")
        blocks = ",\n  ".join(matrix(gain[:, 3 * j:3 * j + 3]) for j in range(4))
        lines.append(f"let feedback{k} = feedback(\n  {blocks}) ;")
    arguments = ", ".join(f"feedback{k}" for k in range(len(points)))
    lines.append(f"let scheduled_feedback = schedule({arguments}) ;")
    lines.append(END)
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--lsdc", default="target/debug/lsdc")
    arguments = parser.parse_args()
    points = []
    largest_gap = 0.0
    for t in TIMES:
        angles, rates, currents, a, b = operating_point(arguments.lsdc, t)
        gain, gap = gains(a, b)
        largest_gap = max(largest_gap, gap)
        points.append((t, angles, rates, currents, gain))
    (interpolated, frozen), (interpolated_slowest, frozen_slowest) = between_points(
        arguments.lsdc, points)
    with open(PROGRAM, encoding="utf-8") as f:
        text = f.read()
    begin, end = text.index(BEGIN), text.index(END) + len(END)
    with open(PROGRAM, "w", encoding="utf-8") as f:
        f.write(text[:begin] + table(points) + text[end:])
    print(f"{len(points)} operating points; the eigenvalues of A_e - B_e K within "
          f"{largest_gap:.1e} of the poles (relative)")
    print(f"between points, the gains interpolated: within {interpolated:.1e} of the poles, "
          f"the slowest at {interpolated_slowest:.4g} /s; the first point's frozen: within "
          f"{frozen:.1e}, the slowest at {frozen_slowest:.4g} /s")


if __name__ == "__main__":
    main()
