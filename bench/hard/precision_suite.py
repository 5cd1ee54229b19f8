#!/usr/bin/env python3
"""Speed against error on the hard cases: `lsdc precision` on each, its table in BENCHMARKS.md.

The cases are published benchmarks of multibody dynamics: the IFToMM library of computational
benchmarks, group A (A01 simple pendulum, A02 N-four-bar mechanism, A03 Andrews' squeezing
mechanism, A04 Bricard's mechanism, A05 flyball governor; https://www.iftomm-multibody.org/benchmark),
the squeezer as the Test Set for IVP Solvers gives it (problem `andrews`), and two more spatial and
planar loops of the hard set (Bennett 4R, Watt six-bar). Each case names its reference:

- `analytic`: a closed-form solution, written here as a CSV at the outputs (pendulum: Jacobi
  elliptic functions, sin(theta/2) = k cd(w t, k));
- `reduced`: the one-coordinate equation of motion derived for the mechanism, integrated by
  scipy's DOP853 at rtol = atol = 1e-13 (the rows of parallelograms, `four_bar_row.py`);
- `published`: the test set's reference solution at t = 0.03 (PSIDE, rtol = atol = 1e-14);
- `lsdc`: lsdc's own DOP853 at a tolerance 1000 times tighter than the tightest measured, written
  to a CSV and checked here by the case's independent script (closed forms, the reduced equation,
  an independent closure product: `bennett.py`, `bricard.py`, `watt.py`); the table records the
  script's verdict and its largest trajectory error.

Usage: bench/hard/precision_suite.py [--lsdc PATH] [--repeats N] [--no-write]
Writes bench/hard/references/*.csv, bench/hard/precision/NAME.json, docs/precision/NAME.svg and
the section between the markers in BENCHMARKS.md (with --no-write, that section is only printed;
the other files are still written, as the runs read them); prints the time it took. PATH
defaults to target/debug/lsdc: build it first, or pass target/release/lsdc.
"""

import argparse
import json
import math
import os
import subprocess
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp
from scipy.special import ellipj, ellipk

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
import bennett  # noqa: E402
import bricard  # noqa: E402
import four_bar_row  # noqa: E402
import watt  # noqa: E402

BEGIN, END = "<!-- precision-suite: begin -->", "<!-- precision-suite: end -->"


def outputs(duration, every):
    return np.round(np.arange(0.0, duration + every / 2, every), 12)


def write_csv(path, columns, times, values):
    with open(path, "w") as f:
        f.write(",".join(["time"] + columns) + "\n")
        for i, t in enumerate(times):
            f.write(",".join([repr(float(t))] + [repr(float(v[i])) for v in values]) + "\n")


def pendulum_reference(path):
    """examples/pendulum.lsd: a rod, I = 0.1 + 1.2 * 0.5^2 about the pivot, released at 60 deg."""
    w = math.sqrt(1.2 * 9.81 * 0.5 / (0.1 + 1.2 * 0.25))
    k = math.sin(math.pi / 6)
    m = k * k
    t = outputs(5.0, 0.05)
    sn, cn, dn, _ = ellipj(w * t, m)
    s = k * cn / dn
    theta = 2 * np.arcsin(s)
    rate = -2 * w * k * (1 - m) * sn / dn ** 2 / np.sqrt(1 - s * s)
    write_csv(path, ["swing.q", "swing.q'"], t, [theta, rate])
    return "analytic (elliptic functions; period %.12g s)" % (4 * ellipk(m) / w)


def four_bar_row_reference(n, path):
    j, k = four_bar_row.constants(n)
    t = outputs(2.0, 0.01)
    sol = solve_ivp(lambda _, y: [y[1], -k * math.cos(y[0]) / j], (0, 2), [four_bar_row.PHI0, four_bar_row.OMEGA0],
                    method="DOP853", t_eval=t, rtol=1e-13, atol=1e-13)
    phi, rate = sol.y
    columns, values = [], []
    for i in range(n + 1):
        columns += [f"c{i}.q", f"c{i}.q'"]
        values += [phi, rate]
    for i in range(1, n + 1):
        columns += [f"p{i}.q", f"p{i}.q'"]
        values += [-phi, -rate]
    write_csv(path, columns, t, values)
    return "reduced equation phi'' = -K cos(phi) / J (scipy DOP853, 1e-13)"


def squeezer_reference(path):
    with open(os.path.join(ROOT, "tests", "fixtures", "hard", "squeezer_reference.json")) as f:
        data = json.load(f)
    published = data["published"]
    columns = [f"{n}.q" for n in data["coordinates"]] + [f"{n}.q'" for n in data["coordinates"]]
    values = [[v] for v in published["positions"] + published["velocities"]]
    write_csv(path, columns, [data["t"]], values)
    return "published (IVP test set, PSIDE 1e-14, at t = 0.03)"


# name: (program, lsdc precision options, reference kind, independent check of an lsdc reference)
CASES = {
    "pendulum": ("examples/pendulum.lsd", ["--integrators", "rk4,dopri5,dop853",
                 "--tolerances", "1e-4,1e-6,1e-8,1e-10,1e-12"], "analytic", None),
    "four_bar_row_1": ("examples/hard/four_bar_row_1.lsd", ["--integrators", "rk4,dopri5,dop853",
                       "--tolerances", "1e-4,1e-6,1e-8,1e-10"], "reduced", None),
    "four_bar_row_10": ("examples/hard/four_bar_row_10.lsd", ["--integrators", "dopri5,dop853",
                        "--tolerances", "1e-6,1e-8,1e-10"], "reduced", None),
    "squeezer": ("examples/hard/squeezer.lsd", ["--integrators", "rk4,dopri5,dop853",
                 "--tolerances", "1e-6,1e-8,1e-10,1e-12", "--steps", "1e-4,3e-5,1e-5"], "published", None),
    "bricard": ("examples/hard/bricard.lsd", ["--integrators", "dopri5,dop853",
                "--tolerances", "1e-6,1e-8,1e-10"], "lsdc", bricard.check),
    "governor": ("examples/governor.lsd", ["--integrators", "dopri5,dop853,implicit", "--duration", "0.2",
                 "--tolerances", "1e-4,1e-6,1e-8"], "lsdc", None),
    "bennett": ("examples/hard/bennett.lsd", ["--integrators", "dopri5,dop853",
                "--tolerances", "1e-6,1e-8,1e-10"], "lsdc", bennett.check),
    "watt_six_bar": ("examples/hard/watt_six_bar.lsd", ["--integrators", "dopri5,dop853",
                     "--tolerances", "1e-6,1e-8,1e-10"], "lsdc", watt.check),
}


def reference_for(name, lsdc, program, options, kind, check):
    """The --reference option and a description of the reference."""
    # Relative to the repository (the runs' working directory), so that the tables the runs
    # record name the reference as the repository does.
    path = os.path.relpath(os.path.join(HERE, "references", f"{name}.csv"), ROOT)
    if kind == "analytic":
        return ["--reference", path], pendulum_reference(path)
    if kind == "reduced":
        return ["--reference", path], four_bar_row_reference(int(name.rsplit("_", 1)[1]), path)
    if kind == "published":
        return ["--reference", path], squeezer_reference(path)
    tolerances = [float(t) for t in options[options.index("--tolerances") + 1].split(",")]
    tolerance = max(min(tolerances) / 1000, 1e-14)
    if check is None:
        return [], "lsdc dop853 at %g (no independent script)" % tolerance
    csv = os.path.join("/tmp", f"lsdc-precision-{name}.csv")
    subprocess.run([lsdc, "simulate", program, "--integrator", "dop853", "--tolerance", str(tolerance), "-o", csv],
                   check=True, capture_output=True)
    verdict = check(csv)
    error = verdict.get("theta1_vs_reduced_ode", verdict.get("crank_vs_reduced_ode"))
    if error is None:
        error = max(v for k, v in verdict.items() if isinstance(v, float) and k != "t_end")
    return [], "lsdc dop853 at %g; independent script: %s, largest error %s" % (
        tolerance, "ok" if verdict.get("ok") else "FAIL", sci(error))


def run_case(name, lsdc, repeats):
    program, options, kind, check = CASES[name]
    reference_options, description = reference_for(name, lsdc, program, options, kind, check)
    json_path = os.path.join(HERE, "precision", f"{name}.json")
    svg = os.path.join(ROOT, "docs", "precision", f"{name}.svg")
    common = [lsdc, "precision", program, *options, *reference_options, "--repeats", str(repeats)]
    started = time.time()
    subprocess.run(common + ["--format", "json", "-o", json_path, "--plot", svg, "--accuracy", "1e-6"],
                   check=True, capture_output=True)
    with open(json_path) as f:
        table = json.load(f)
    return table, description, time.time() - started


def sci(value, digits=1):
    """Scientific notation as lsdc writes it: 4.3e-9, 1e-4."""
    return ("%.*e" % (digits, value)).replace("e-0", "e-").replace("e+00", "e0").replace("e+0", "e")


def markdown(name, table, description, seconds):
    rows = ["| method | setting | position error | velocity error | closure | energy drift | steps | "
            "rejected | evaluations | CPU min (ms) | CPU median (ms) | outcome |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    optional = lambda v: "–" if v is None else sci(v)  # noqa: E731
    for m in table["measurements"]:
        setting = m["setting"]
        kind, value = next(iter(setting.items()))
        value = sci(value, 0)
        rows.append("| %s | %s %s | %s | %s | %s | %s | %d | %d | %d | %.3f | %.3f | %s |" % (
            m["integrator"], "tol" if kind == "tolerance" else "step", value, sci(m["errors"]["position"] or 0.0),
            sci(m["errors"]["velocity"] or 0.0), optional(m["closure_residual"]), optional(m["energy_drift"]),
            m["steps"], m["rejected_steps"], m["function_evaluations"], m["cpu_seconds_min"] * 1e3,
            m["cpu_seconds_median"] * 1e3, m["failure"] or "ok"))
    recommendation = table.get("recommendation") or {}
    return "\n".join([f"#### {name}", "",
                      f"`{CASES[name][0]}`, {table['duration']} s, outputs every {table['output_interval']} s; "
                      f"reference: {description}. Plot: `docs/precision/{name}.svg`. "
                      f"({seconds:.1f} s for the case.)", "", *rows, "",
                      f"Recommended {recommendation.get('message', '')}", ""])


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--lsdc", default=os.path.join(ROOT, "target", "debug", "lsdc"))
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--no-write", action="store_true")
    args = parser.parse_args()
    # The cases name their programs and references relative to the repository.
    args.lsdc = os.path.abspath(args.lsdc)
    os.chdir(ROOT)
    started = time.time()
    sections = []
    for name in CASES:
        table, description, seconds = run_case(name, args.lsdc, args.repeats)
        sections.append(markdown(name, table, description, seconds))
        print(f"{name}: {seconds:.1f} s", file=sys.stderr)
    total = time.time() - started
    text = "\n".join([BEGIN, "", "Generated by `bench/hard/precision_suite.py` "
                      f"in {total:.0f} s of wall time ({args.repeats} repeats per method).", "", *sections, END])
    print(text)
    if not args.no_write:
        path = os.path.join(ROOT, "BENCHMARKS.md")
        with open(path) as f:
            old = f.read()
        if BEGIN in old:
            new = old[:old.index(BEGIN)] + text + old[old.index(END) + len(END):]
        else:
            new = old.rstrip("\n") + "\n\n" + text + "\n"
        with open(path, "w") as f:
            f.write(new)
    print(f"total: {total:.1f} s", file=sys.stderr)


if __name__ == "__main__":
    main()
