#!/usr/bin/env python3
"""SymPy's simplified forms of lsdc's equations of motion: their sizes, the fixture
tests/fixtures/sympy_simplified_sizes.json that `tests/suite/symbolic_simplify.rs` compares
`lsdc compile --simplify` with (so that `cargo test` needs no Python).

For each mechanism (the planar n-link pendulums n = 1 ... 5 of `benches/symbolic.rs`, the same
program as `bench/sympy_pendulum.py`, and `examples/satellite.lsd`), the unsimplified equations
are written by `lsdc compile FILE --emit equations --format sympy`; the entries measured are
M[i, j] for i <= j (M is symmetric) and S[i] + F[i] (SymPy's "forcing"). Each entry is passed
to `sympy.simplify` (which tries `trigsimp`, `cancel`, `factor`, ... and keeps the shortest by
`count_ops`). Each mechanism runs in a child process with a time limit (`--limit`, seconds
of wall clock): where `simplify` does not finish in it, `sympy.trigsimp` (the
trigonometric part alone) is measured instead, under the same limit, and the fixture says which
method each count comes from. Two measures of the simplified entries are recorded:

  tree_ops  the sum over the entries of `sympy.count_ops(entry)`: every operation as the
            expression is written, a shared subexpression once per use;
  cse_ops   `count_ops` of the entries after `sympy.cse` of them all together (the common
            subexpressions' definitions plus the reduced entries): each shared subexpression
            counted once, as lsdc's distinct operations of the graph are.

Usage: python3 bench/sympy_simplified_sizes.py [--lsdc PATH] [--out PATH] [--limit S] [--only NAME]
(`--only pendulum4` measures that mechanism again and updates its entry of an existing fixture.)
Needs sympy (pip install sympy).
"""

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import sympy as sp

ROOT = Path(__file__).resolve().parent.parent
PENDULUMS = [1, 2, 3, 4, 5]


def pendulum_program(n):
    lines = ["let g = 9.81 ;"]
    for i in range(1, n + 1):
        lines.append(
            f"let l{i} = body mass = 1, iframe = [0, 0, -0.5] ++ 1, "
            f"inertia = [0.08, 0.08, 0.01] end ;"
        )
        parent = "earth" if i == 1 else f"[0, 0, -1] ++ 1 @ l{i - 1}"
        lines.append(f"join {parent} and l{i}.frame with link(q) dof = q || [0, 1, 0] end as j{i} ;")
        lines.append(
            f"apply force value = [0, 0, -g * l{i}.mass], body = earth end on l{i}.iframe ;"
        )
    return "\n".join(lines) + "\n"


def equations(lsdc, path):
    """The module lsdc writes for the program at `path`, executed."""
    text = subprocess.run(
        [lsdc, "compile", str(path), "--emit", "equations", "--format", "sympy"],
        check=True, capture_output=True, text=True,
    ).stdout
    namespace = {}
    exec(compile(text, str(path), "exec"), namespace)
    return namespace


def entries(module):
    mass, s, f = module["M"], module["S"], module["F"]
    n = mass.shape[0]
    upper = [mass[i, j] for i in range(n) for j in range(i, n)]
    return upper + [s[i] + f[i] for i in range(n)]


def measure(lsdc, path, method):
    exprs = entries(equations(lsdc, path))
    start = time.process_time()
    simplified = [getattr(sp, method)(e) for e in exprs]
    seconds = time.process_time() - start
    tree = sum(sp.count_ops(e) for e in simplified)
    replacements, reduced = sp.cse(simplified)
    cse = sum(sp.count_ops(v) for _, v in replacements) + sum(sp.count_ops(e) for e in reduced)
    unsimplified = sum(sp.count_ops(e) for e in exprs)
    return {
        "method": f"sympy.{method}",
        "entries": len(exprs),
        "tree_ops": int(tree),
        "cse_ops": int(cse),
        "unsimplified_tree_ops": int(unsimplified),
        "simplify_cpu_seconds": round(seconds, 2),
    }


def measured_in_child(args, name, path):
    """`measure` in a child process, `simplify` then `trigsimp`, each under the time limit."""
    for method in ["simplify", "trigsimp"]:
        command = [sys.executable, __file__, "--lsdc", args.lsdc, "--one", str(path), "--method", method]
        try:
            done = subprocess.run(command, capture_output=True, text=True, timeout=args.limit, check=True)
            return {**json.loads(done.stdout), "limit_seconds": args.limit}
        except subprocess.TimeoutExpired:
            print(f"{name}: sympy.{method} did not finish in {args.limit} s", file=sys.stderr)
    return {"method": f"neither sympy.simplify nor sympy.trigsimp finished in {args.limit} s"}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--lsdc", default=str(ROOT / "target" / "debug" / "lsdc"))
    parser.add_argument("--out", default=str(ROOT / "tests" / "fixtures" / "sympy_simplified_sizes.json"))
    parser.add_argument("--limit", type=float, default=300.0)
    parser.add_argument("--only", help="measure this mechanism again, updating the fixture")
    parser.add_argument("--one", help=argparse.SUPPRESS)
    parser.add_argument("--method", default="simplify", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(measure(args.lsdc, Path(args.one), args.method)))
        return
    results = {}
    if args.only:
        results = json.loads(Path(args.out).read_text())["mechanisms"]
    fixture = {
        "provenance": "bench/sympy_simplified_sizes.py: sympy.simplify (or sympy.trigsimp where "
        "simplify did not finish in the limit) of each entry of lsdc's unsimplified equations "
        "(M[i, j] for i <= j, S[i] + F[i]), then sympy.count_ops",
        "sympy_version": sp.__version__,
        "python_version": sys.version.split()[0],
        "limit_seconds": args.limit,
        "mechanisms": results,
    }
    with tempfile.TemporaryDirectory() as directory:
        mechanisms = []
        for n in PENDULUMS:
            path = Path(directory) / f"pendulum{n}.lsd"
            path.write_text(pendulum_program(n))
            mechanisms.append((f"pendulum{n}", path))
        mechanisms.append(("satellite", ROOT / "examples" / "satellite.lsd"))
        for name, path in mechanisms:
            if args.only and name != args.only:
                continue
            results[name] = measured_in_child(args, name, path)
            print(name, results[name], file=sys.stderr)
            Path(args.out).write_text(json.dumps(fixture, indent=2) + "\n")


if __name__ == "__main__":
    main()
