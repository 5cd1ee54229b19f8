#!/usr/bin/env python3
"""Checks the SymPy form of the equations of motion against the numeric back end.

For each example, `lsdc compile FILE --emit equations --format sympy` writes a Python module;
this script imports it, substitutes pseudo-random states and compares

  - M with the mass matrix of `lsdc eval` (CRBA), and
  - S + F with -RNEA(q, v, 0), which `lsdc eval` gives with the links' own efforts already
    taken off: both are the generalised forces that are not inertial.

The numeric back end works on the spanning tree: for a mechanism with loops only the tree's
coordinates are compared. Examples whose numeric coordinates are not the program's (quaternions
of spherical and free joints), and examples with parameters that have no given value, are
skipped with a note.

Usage: python3 bench/check_sympy.py [--lsdc PATH] [--states N] [EXAMPLE.lsd ...]
Needs sympy (pip install sympy). Exit status 1 when an entry disagrees beyond the tolerance.
"""

import argparse
import importlib.util
import json
import random
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import sympy as sp

ROOT = Path(__file__).resolve().parent.parent
DEFAULT_EXAMPLES = [
    "pendulum", "double_pendulum", "satellite_fixed", "satellite_numeric", "satellite_springs",
    "elliptic_pendulum", "runaway", "four_bar", "slider_crank", "homocinetic", "heavy_top",
]
TOLERANCE = 1e-10


def run(command):
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        raise RuntimeError(f"{' '.join(map(str, command))} failed:\n{result.stderr}")
    return result.stdout


def load_module(path):
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def relative_deviation(got, expected):
    """Largest |got - expected| relative to max(|expected|, the largest |expected| entry)."""
    scale = max((abs(x) for x in expected), default=0.0)
    worst = 0.0
    for g, e in zip(got, expected):
        worst = max(worst, abs(g - e) / max(abs(e), scale, 1e-300))
    return worst


def check(lsdc, example, states, workdir):
    module_path = workdir / f"{example.stem}_equations.py"
    run([lsdc, "compile", example, "--emit", "equations", "--format", "sympy", "-o", module_path])
    eq = load_module(module_path)
    missing = [p for p in eq.parameters if p not in eq.given]
    if missing:
        return f"skipped: parameters without a given value ({', '.join(map(str, missing))})"
    if eq.functions:
        return "skipped: unknown functions"
    names = [str(p) for p in eq.positions]

    # The numeric back end's coordinates, from one evaluation at zero (the tree's coordinates
    # only, and a quaternion for a free or spherical joint: its error says how many).
    numeric_names = None
    count = len(names)
    for _ in range(2):
        probe = workdir / "probe.json"
        probe.write_text(json.dumps({"states": [{"q": [0.0] * count}]}))
        try:
            numeric_names = json.loads(run([lsdc, "eval", example, "--states", probe]))["positions"]
            break
        except RuntimeError as error:
            found = re.search(r"the mechanism has (\d+)", str(error))
            if "quaternion" in str(error):
                return "skipped: the numeric coordinates include a quaternion (free or spherical joint)"
            if not found:
                return f"skipped: {str(error).splitlines()[-1]}"
            count = int(found.group(1))
    if not set(numeric_names) <= set(names):
        return f"skipped: the numeric coordinates are not the program's ({', '.join(numeric_names)})"

    generator = random.Random(7)
    inputs = []
    for _ in range(states):
        q = {name: generator.uniform(-1.5, 1.5) for name in names}
        v = {name: generator.uniform(-1.0, 1.0) for name in names}
        inputs.append((q, v))
    states_file = workdir / "states.json"
    states_file.write_text(json.dumps({"states": [
        {"q": [q[n] for n in numeric_names], "v": [v[n] for n in numeric_names], "a": [0.0] * len(numeric_names)}
        for q, v in inputs
    ]}))
    evaluation = json.loads(run([lsdc, "eval", example, "--states", states_file]))

    index = [names.index(n) for n in numeric_names]
    worst_m, worst_rhs = 0.0, 0.0
    for (q, v), numeric in zip(inputs, evaluation["states"]):
        values = {p: q[str(p)] for p in eq.positions}
        values.update({r: v[str(p)] for p, r in zip(eq.positions, eq.rates)})
        values.update(eq.given)
        values[eq.t] = 0.0
        mass = eq.M.subs(values).evalf()
        rhs = (eq.S + eq.F).subs(values).evalf()
        got_m = [float(mass[i, j]) for i in index for j in index]
        expected_m = [x for row in numeric["crba"] for x in row]
        got_rhs = [float(rhs[i]) for i in index]
        expected_rhs = [-x for x in numeric["rnea"]]
        worst_m = max(worst_m, relative_deviation(got_m, expected_m))
        worst_rhs = max(worst_rhs, relative_deviation(got_rhs, expected_rhs))
    verdict = "ok" if max(worst_m, worst_rhs) <= TOLERANCE else "DISAGREES"
    loops = f", {len(eq.constraint_names)} constraint rows not compared" if eq.constraint_names else ""
    return f"{verdict}: {states} states, M within {worst_m:.1e}, S + F within {worst_rhs:.1e}{loops}"


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--lsdc", default=str(ROOT / "target" / "release" / "lsdc"))
    parser.add_argument("--states", type=int, default=5)
    parser.add_argument("examples", nargs="*")
    args = parser.parse_args()
    examples = [Path(e) for e in args.examples] or [ROOT / "examples" / f"{name}.lsd" for name in DEFAULT_EXAMPLES]
    failed = False
    with tempfile.TemporaryDirectory() as scratch:
        for example in examples:
            try:
                outcome = check(args.lsdc, example, args.states, Path(scratch))
            except RuntimeError as error:
                outcome = f"error: {error}"
            failed |= outcome.startswith(("DISAGREES", "error"))
            print(f"{example.name:28} {outcome}")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
