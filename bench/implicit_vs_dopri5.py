#!/usr/bin/env python3
"""The implicit integrator against dopri5 at equal error, on the command line's runs.

For each case, a reference run (dopri5 at a tolerance far below the compared ones) gives the
samples; each compared run is repeated and its process CPU time (user + system, best and
median) taken with its steps and right-hand sides (from the JSON report), and its error: the
largest difference over the samples of a coordinate or rate from the reference's, relative to
that column's largest magnitude. The ratio at equal error interpolates dopri5's CPU time
log-linearly in log error at the implicit run's error (within dopri5's sweep; "-" outside it).

    python3 bench/implicit_vs_dopri5.py [--repeats N] [--only NAME] [--binary PATH]

Needs numpy and a release build (`cargo build --release`).
"""
import argparse
import json
import os
import resource
import subprocess
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# name, file, extra options, tolerances compared, reference tolerance
CASES = [
    ("governor (stiff)", "examples/governor.lsd", ["--duration", "1"], [1e-4, 1e-5, 1e-6, 1e-7, 1e-8], 1e-12),
    ("maille1", "examples/maille1.lsd", [], [1e-10], 1e-13),
    ("delta_isir88_reduced", "examples/delta_isir88_reduced.lsd", [], [1e-10], 1e-13),
    ("four_bar_row_40, step 1e-3", "examples/hard/four_bar_row_40.lsd", ["--step", "1e-3"], [1e-8], 1e-12),
    ("four_bar_row_40, step 1e-4", "examples/hard/four_bar_row_40.lsd", ["--step", "1e-4"], [1e-11], 1e-12),
]
OWN = [  # every example the implicit integrator runs, at its own tolerance
    ("pendulum", 1e-10), ("double_pendulum", 1e-12), ("elastic_pendulum", 1e-8),
    ("elliptic_pendulum", 1e-12), ("four_bar", 1e-12), ("free_body", 1e-12),
    ("heavy_top", 1e-12), ("homocinetic", 1e-10), ("maille2", 1e-10), ("runaway", 1e-9),
    ("saliere", 1e-10), ("satellite_fixed", 1e-8), ("satellite_numeric", 1e-8),
    ("satellite_springs", 1e-12), ("slider_crank", 1e-12), ("delta_isir88", 1e-10),
]


def run(binary, path, options, integrator, tolerance):
    """(samples as columns, report, CPU seconds) of one run."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    result = subprocess.run(
        [binary, "simulate", path, "--integrator", integrator, "--tolerance", str(tolerance),
         "--report", "json"] + options,
        cwd=ROOT, capture_output=True, text=True, timeout=120)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    report = None
    text, decoder, at = result.stderr, json.JSONDecoder(), 0
    while (at := text.find("{", at)) >= 0:
        try:
            value, end = decoder.raw_decode(text, at)
        except json.JSONDecodeError:
            at += 1
            continue
        if isinstance(value, dict) and "steps" in value:
            report = value
        at = end
    lines = result.stdout.splitlines()
    lines = lines[next(i for i, l in enumerate(lines) if l.startswith("time,")):]
    lines = [lines[0]] + [l for l in lines[1:] if l[:1].isdigit() or l[:1] == "-"]
    header = lines[0].split(",")
    number = lambda x: float(x) if x else float("nan")
    rows = np.array([[number(x) for x in l.split(",")] for l in lines[1:]]).reshape(-1, len(header))
    wanted = [i for i, name in enumerate(header)
              if name != "time" and not name.startswith(("kinetic", "potential", "work", "momentum"))]
    return rows[:, wanted], report, cpu


def error_against(samples, reference):
    n = min(len(samples), len(reference))
    if n == 0:
        return float("nan")
    scale = np.maximum(np.abs(reference[:n]).max(axis=0), 1e-300)
    return float((np.abs(samples[:n] - reference[:n]) / scale).max())


def measure(binary, path, options, integrator, tolerance, reference, repeats):
    times = []
    for _ in range(repeats):
        samples, report, cpu = run(binary, path, options, integrator, tolerance)
        times.append(cpu)
    failed = report is None or report.get("failure") is not None
    return {
        "integrator": integrator, "tolerance": tolerance, "best": min(times),
        "median": float(np.median(times)), "steps": report["steps"] if report else 0,
        "evaluations": report["function_evaluations"] if report else 0,
        "stiff": report.get("stiff_steps") if report else None,
        "error": float("nan") if failed else error_against(samples, reference),
        "failed": failed,
    }


def at_error(points, error):
    """dopri5's best CPU time at `error`, log-linearly between its runs (None outside)."""
    points = sorted((p["error"], p["best"]) for p in points if not p["failed"] and p["error"] > 0)
    for (e0, c0), (e1, c1) in zip(points, points[1:]):
        if e0 <= error <= e1:
            w = (np.log(error) - np.log(e0)) / (np.log(e1) - np.log(e0))
            return float(np.exp((1 - w) * np.log(c0) + w * np.log(c1)))
    return None


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--only")
    parser.add_argument("--binary", default=os.path.join(ROOT, "target/release/lsdc"))
    args = parser.parse_args()
    cases = CASES + [(name, f"examples/{name}.lsd", [], [tol], min(tol * 1e-2, 1e-13)) for name, tol in OWN]
    print("| case | tolerance | integrator | CPU s best / median | steps (stiff) | evaluations | error | implicit / dopri5 CPU |")
    print("|---|---:|---|---:|---:|---:|---:|---:|")
    for name, path, options, tolerances, reference_tolerance in cases:
        if args.only and args.only not in name:
            continue
        reference, _, _ = run(args.binary, path, options, "dopri5", reference_tolerance)
        sweep = sorted(set(tolerances + [t * f for t in tolerances for f in (0.1, 0.01)]))
        explicit = [measure(args.binary, path, options, "dopri5", t, reference, args.repeats) for t in sweep]
        for tolerance in tolerances:
            implicit = measure(args.binary, path, options, "implicit", tolerance, reference, args.repeats)
            same = next(p for p in explicit if p["tolerance"] == tolerance)
            equal = at_error(explicit, implicit["error"])
            for p in (same, implicit):
                stiff = f" ({p['stiff']})" if p["stiff"] is not None else ""
                ratio = ""
                if p is implicit:
                    ratio = f"{p['best'] / same['best']:.2f} at equal tolerance"
                    ratio += f", {p['best'] / equal:.2f} at equal error" if equal else ", equal error outside dopri5's sweep"
                status = "FAILED " if p["failed"] else ""
                print(f"| {name} | {tolerance:.0e} | {p['integrator']} | {status}{p['best']:.3f} / {p['median']:.3f} | "
                      f"{p['steps']}{stiff} | {p['evaluations']} | {p['error']:.1e} | {ratio} |")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
