#!/usr/bin/env python3
"""CPU time per target move of `lsdc drag` (BENCHMARKS.md, "Drag"): each method on a path of
N targets and on a path of 1 target, the difference divided by N - 1 (so that compiling and
assembling the program do not count); best and median over repeats of the children's CPU time.

Usage: bench/drag_speed.py [LSDC] (default target/release/lsdc), from the repository's root.
"""
import math
import os
import resource
import statistics
import subprocess
import sys
import tempfile

LSDC = sys.argv[1] if len(sys.argv) > 1 else "target/release/lsdc"
REPEATS = 7
MOVES = 2000


def coupler_point(t):
    """The four-bar's coupler point at crank angle t, in closed form (tests/suite/drag.rs)."""
    b = (math.cos(t), math.sin(t))
    bd = (4.0 - b[0], -b[1])
    d = math.hypot(*bd)
    along = (3.5**2 - 3.0**2 + d * d) / (2 * d)
    height = math.sqrt(3.5**2 - along * along)
    e = (bd[0] / d, bd[1] / d)
    c = (b[0] + along * e[0] - height * e[1], b[1] + along * e[1] + height * e[0])
    u = ((c[0] - b[0]) / 3.5, (c[1] - b[1]) / 3.5)
    return (b[0] + 1.75 * u[0] - u[1], b[1] + 1.75 * u[1] + u[0])


def cpu_of(args):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(args, check=False, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def per_move(program, point, targets, extra):
    with tempfile.TemporaryDirectory() as folder:
        many, one = os.path.join(folder, "many.csv"), os.path.join(folder, "one.csv")
        with open(many, "w") as f:
            f.writelines(f"{x},{y},{z}\n" for x, y, z in targets)
        with open(one, "w") as f:
            f.write("%s,%s,%s\n" % targets[0])
        base = [LSDC, "drag", program, "--point", point] + extra + ["--path"]
        times = []
        for _ in range(REPEATS):
            times.append((cpu_of(base + [many]) - cpu_of(base + [one])) / (len(targets) - 1))
        return min(times), statistics.median(times)


def main():
    four_bar = [coupler_point(1.0 + 0.001 * k) + (0.0,) for k in range(MOVES + 1)]
    # The Delta's nacelle along a line of 2 cm from its assembled position (0, 0, -0.3263...),
    # read from a one-target run of the exact method.
    out = subprocess.run([LSDC, "drag", "examples/delta_isir88.lsd", "--point", "nacelle",
                          "--path", "/dev/stdin"], input="0,0\n", capture_output=True, text=True).stdout
    header, row = out.splitlines()[:2]
    cells = dict(zip(header.split(","), row.split(",")))
    z = float(cells["point.z"])
    delta = [(0.01 * k / MOVES, 0.005 * k / MOVES, z) for k in range(MOVES + 1)]
    cases = [
        ("four-bar", "examples/four_bar.lsd", "coupler_point", four_bar, ["--method", "exact"]),
        ("four-bar", "examples/four_bar.lsd", "coupler_point", four_bar, ["--method", "penalty"]),
        ("Delta", "examples/delta_isir88.lsd", "nacelle", delta, ["--method", "exact"]),
    ]
    for name, program, point, targets, extra in cases:
        best, median = per_move(program, point, targets, extra)
        print(f"| {name} | {extra[1]} | {best * 1e6:.1f} | {median * 1e6:.1f} |")


main()
