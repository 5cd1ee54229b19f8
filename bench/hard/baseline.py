#!/usr/bin/env python3
"""Run lsdc on the hard set (examples/hard/) and check its output against the references.

For every program: `lsdc check`, `lsdc tree --format json` (the mobility it reports),
`lsdc assemble`, then `lsdc simulate` with each integrator (rk4, dopri5, implicit, symplectic)
at two settings, "A" (--tolerance 1e-8 --step 1e-3) and "B" (--tolerance 1e-11 --step 1e-4),
each run limited to TIMEOUT seconds of wall time. It records the exit code, whether lsdc
panicked (exit 101 or "panicked" on standard error), the energy drift (or energy balance) and the
loop residuals of the run report (--report json), the wall time, and the verdict of the
program's reference script on the CSV samples. Writes bench/hard/baseline.json and prints a
Markdown table.

Usage: bench/hard/baseline.py [--lsdc PATH] [--timeout S] [--out FILE.json] [PROGRAM...]
       bench/hard/baseline.py --table [baseline.json]   (the Markdown table of a previous run)
"""

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)

import bennett  # noqa: E402
import bricard  # noqa: E402
import four_bar_row  # noqa: E402
import rigid  # noqa: E402
import squeezer  # noqa: E402
import watt  # noqa: E402

PROGRAMS = {
    "bennett": (bennett.check, 3, 1, 1),
    "bricard": (bricard.check, 5, 1, 1),
    "four_bar_row_1": (lambda p: four_bar_row.check(1, p), 3, 1, 1),
    "four_bar_row_2": (lambda p: four_bar_row.check(2, p), 5, 2, 1),
    "four_bar_row_10": (lambda p: four_bar_row.check(10, p), 21, 10, 1),
    "four_bar_row_40": (lambda p: four_bar_row.check(40, p), 81, 40, 1),
    "squeezer": (squeezer.check, 7, 3, 1),
    "watt_six_bar": (watt.check, 5, 2, 1),
    "truss": (lambda p: rigid.check("truss", p), 3, 2, 0),
    "double_revolute": (lambda p: rigid.check("double_revolute", p), 1, 1, 0),
}
SETTINGS = {"A": ["--tolerance", "1e-8", "--step", "1e-3"], "B": ["--tolerance", "1e-11", "--step", "1e-4"]}
INTEGRATORS = ["rk4", "dopri5", "implicit", "symplectic"]


def run(cmd, timeout):
    t0 = time.time()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        return p.returncode, p.stdout, p.stderr, time.time() - t0
    except subprocess.TimeoutExpired as e:
        err = e.stderr.decode() if isinstance(e.stderr, bytes) else (e.stderr or "")
        return None, "", err, time.time() - t0


def last_json(text):
    i = text.rfind("\n{")
    i = 0 if text.startswith("{") and i < 0 else i
    for start in [m.start() for m in re.finditer(r"(^|\n)\{", text)][::-1]:
        try:
            return json.loads(text[start:].strip())
        except ValueError:
            continue
    return None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--lsdc", default=os.environ.get("LSDC", "lsdc"))
    ap.add_argument("--timeout", type=float, default=30)
    ap.add_argument("--out", default=os.path.join(HERE, "baseline.json"), help="where the results go")
    ap.add_argument("programs", nargs="*")
    a = ap.parse_args()
    names = a.programs or list(PROGRAMS)
    out_path = a.out
    # programs not run this time keep their previous results
    results = [r for r in (json.load(open(out_path)) if os.path.exists(out_path) else []) if r["program"] not in names]
    for name in names:
        ref, bodies, loops, expected = PROGRAMS[name]
        f = os.path.join(ROOT, "examples", "hard", name + ".lsd")
        rec = {"program": name, "bodies": bodies, "loops": loops, "expected_mobility": expected}
        rc, _, _, _ = run([a.lsdc, "check", f], a.timeout)
        rec["check_rc"] = rc
        rc, out, err, _ = run([a.lsdc, "tree", "--format", "json", f], a.timeout)
        rec["tree_rc"] = rc
        try:
            mob = json.loads(out)["mobility"]
            rec["tree_mobility"] = mob["mobility"]
            rec["tree_first_order_mobility"] = mob["first_order_mobility"]
        except (ValueError, KeyError, TypeError):
            rec["tree_mobility"] = None
        rc, out, err, _ = run([a.lsdc, "assemble", f], a.timeout)
        rec["assemble_rc"] = rc
        rec["runs"] = []
        for setting, extra in SETTINGS.items():
            for integ in INTEGRATORS:
                with tempfile.NamedTemporaryFile(suffix=".csv", delete=False) as tmp:
                    csv_path = tmp.name
                cmd = [a.lsdc, "simulate", f, "--integrator", integ, "--report", "json", "-o", csv_path] + extra
                rc, out, err, wall = run(cmd, a.timeout)
                r = {"integrator": integ, "setting": setting, "rc": rc, "timeout": rc is None,
                     "panicked": rc == 101 or "panicked" in err, "wall_s": round(wall, 2),
                     "warnings": sorted(set(re.findall(r"W09\d\d", err)))}
                rep = last_json(err)
                if rep:
                    r["energy_drift"] = rep.get("energy_drift")
                    eb = rep.get("energy_balance")
                    r["energy_balance"] = eb if not isinstance(eb, dict) else eb.get("relative", eb)
                    c = rep.get("constraints") or {}
                    r["position_residual"] = c.get("position_residual")
                    r["position_residual_before_projection"] = c.get("position_residual_before_projection")
                    r["failure"] = rep.get("failure")
                elif r["panicked"]:
                    m = re.search(r"panicked at [^\n]*\n([^\n]*)", err)
                    r["failure"] = "panic: " + (m.group(1) if m else "?")
                try:
                    r["reference"] = ref(csv_path) if os.path.getsize(csv_path) > 0 else {"ok": False, "reason": "no output"}
                except Exception as exc:  # a partial or empty CSV
                    r["reference"] = {"ok": False, "reason": "reference failed: %s" % exc}
                os.unlink(csv_path)
                rec["runs"].append(r)
                print(name, setting, integ, r["rc"], r["wall_s"], r["reference"].get("ok"), flush=True, file=sys.stderr)
        results.append(rec)
        results.sort(key=lambda r: list(PROGRAMS).index(r["program"]))
        with open(out_path, "w") as fo:
            json.dump(results, fo, indent=1)
            fo.write("\n")




KEY = {"watt_six_bar": "crank_vs_reduced_ode", "bennett": "theta1_vs_reduced_ode", "bricard": "theta1_vs_reduced_ode", "squeezer": "positions_max_abs_error",
       "truss": "max_coordinate_change", "double_revolute": "max_coordinate_change"}


def duration(name):
    text = open(os.path.join(ROOT, "examples", "hard", name + ".lsd")).read()
    return float(re.search(r"simulate\s+duration\s*=\s*([0-9.eE+-]+)", text).group(1))


def cell(r, name):
    if r["timeout"]:
        return "timeout (%g s)" % r["wall_s"]
    parts = ["rc %s%s" % (r["rc"], " **panic**" if r["panicked"] else "")]
    d = r.get("energy_drift")
    if d is None and r.get("energy_balance") is not None:
        d = r["energy_balance"]
    if d is not None:
        parts.append("dE %.1e" % d)
    if r.get("position_residual") is not None:
        parts.append("res %.0e" % r["position_residual"])
    ref = r.get("reference") or {}
    key = KEY.get(name, "phi_vs_reference")
    v = ref.get(key)
    end = ref.get("t_end")
    complete = end is not None and end >= duration(name) - 1e-9
    mark = "ok" if ref.get("ok") and complete else "FAIL"
    parts.append("ref %s%s" % (mark, "" if v is None else " %.1e" % v))
    if r.get("warnings"):
        parts.append("/".join(r["warnings"]))
    elif mark == "FAIL" and r["rc"] == 0:
        parts.append("**silent**")
    if end is not None and not complete:
        parts.append("stopped at t=%.3g" % end)
    elif end is None:
        parts.append("no samples")
    parts.append("%.1f s" % r["wall_s"])
    return ", ".join(parts)


def table(path):
    res = json.load(open(path))
    lines = ["| mechanism | bodies | loops | expected mobility | `tree` mobility (first order) | setting | rk4 | dopri5 | implicit | symplectic |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for rec in res:
        for setting in SETTINGS:
            runs = {r["integrator"]: r for r in rec["runs"] if r["setting"] == setting}
            lines.append("| %s | %d | %d | %d | %s (%s) | %s | %s |" % (
                rec["program"], rec["bodies"], rec["loops"], rec["expected_mobility"], rec.get("tree_mobility"),
                rec.get("tree_first_order_mobility"), setting, " | ".join(cell(runs[i], rec["program"]) for i in INTEGRATORS)))
    return "\n".join(lines)


if __name__ == "__main__":
    if sys.argv[1:2] == ["--table"]:
        print(table(sys.argv[2] if len(sys.argv) > 2 else os.path.join(HERE, "baseline.json")))
    else:
        main()
