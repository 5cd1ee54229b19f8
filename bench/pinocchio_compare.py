#!/usr/bin/env python3
"""Cross-checks lsdc's dynamics against Pinocchio on every URDF robot of example-robot-data.

For each URDF file shipped in the example-robot-data package, twice (fixed base, then floating
base), the script

* builds the robot with Pinocchio (`buildModelFromUrdf`; for the floating base with a
  `JointModelFreeFlyer` root joint), gravity 9.80665 m/s^2 along -z like lsdc's URDF import;
* gives the same robot to lsdc: the URDF file itself for the fixed base (`lsdc eval ROBOT.urdf`),
  the program written by `lsdc import-urdf --floating-base` for the floating base;
* draws a few random states (q, v, a, tau) in lsdc's layout, converts them to Pinocchio's, and
  compares, state by state,
    rnea    the generalised forces that give the accelerations a (gravity included),
    crba    the joint-space mass matrix (Pinocchio fills the upper triangle: symmetrised here),
    aba     the accelerations under the generalised forces tau,
    frames  the world pose (translation and rotation matrix) of every link's body frame.

Disagreement measure (the same in tests/suite/pinocchio_fixtures.rs): for one quantity at one state,

    d = max_i |lsdc_i - pinocchio_i| / max(1, max_i |pinocchio_i|)

over all the entries i of that quantity (every generalised force, every entry of the mass
matrix, every translation and rotation entry of every frame). It is an absolute difference for
values of order 1 or less and a relative one for larger values. A robot's figure for a quantity
is the largest d over its states.

Layouts. lsdc orders its joints breadth-first, Pinocchio depth-first: everything is matched by
name. lsdc renames URDF links and joints whose names are not LSD identifiers; the names are
matched through the program `lsdc import-urdf` writes (its links and joints come in the URDF's
order). A continuous joint is one angle in lsdc and (cos, sin) in Pinocchio. A free joint is
(px, py, pz, qw, qx, qy, qz) and velocities (omega, v) in lsdc, (x, y, z, qx, qy, qz, qw) and
(v, omega) in Pinocchio, both in the body's own axes; efforts and accelerations follow the
velocities' order.

States: every 1-dof coordinate uniform within its URDF limits when they are finite and ordered,
else in [-pi, pi]; the free joint's position uniform in [-1, 1]^3 and its orientation a uniform
random unit quaternion; v, a and tau uniform in [-1, 1]. The seed is fixed (per robot).

Usage:
    python3 bench/pinocchio_compare.py [--lsdc PATH] [--states N] [--robots DIR] [--only SUBSTRING]
                                       [--no-floating] [--tolerance T] [--json OUT.json]

--lsdc defaults to target/release/lsdc, else target/debug/lsdc, in this repository. The script
exits with status 1 when a compared robot disagrees by more than --tolerance (default 1e-9).
Needs `pip install pin example-robot-data` (Pinocchio's Python bindings and the robots).
"""

import argparse
import hashlib
import json
import math
import os
import pathlib
import random
import re
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

REPO = pathlib.Path(__file__).resolve().parent.parent
GRAVITY = 9.80665
QUANTITIES = ("rnea", "crba", "aba", "frames")


def require_pinocchio():
    """Pinocchio's Python module, or exits with a message saying how to install it."""
    try:
        import numpy  # noqa: F401
        import pinocchio
    except ImportError as e:
        sys.exit(f"error: Pinocchio's Python bindings are not installed ({e}).\n"
                 "help: pip install pin example-robot-data")
    return pinocchio


def robots_directory(given=None):
    """The directory of example-robot-data's robots (it holds one folder per robot)."""
    if given:
        return pathlib.Path(given)
    candidates = []
    try:
        import cmeel  # installed with pin's wheels
        candidates.append(pathlib.Path(cmeel.__file__).resolve().parent.parent / "cmeel.prefix")
    except ImportError:
        pass
    candidates += [pathlib.Path(p) / "cmeel.prefix" for p in sys.path if p]
    candidates += [pathlib.Path(sys.prefix), pathlib.Path("/opt/openrobots"), pathlib.Path("/usr")]
    for prefix in candidates:
        robots = prefix / "share" / "example-robot-data" / "robots"
        if robots.is_dir():
            return robots
    sys.exit("error: example-robot-data's robots were not found.\n"
             "help: pip install example-robot-data, or give their directory with --robots")


def package_version(name):
    try:
        from importlib.metadata import version
        return version(name)
    except Exception:
        return "unknown"


def default_lsdc():
    for profile in ("release", "debug"):
        path = REPO / "target" / profile / "lsdc"
        if path.exists():
            return str(path)
    return str(REPO / "target" / "release" / "lsdc")


# ---------------------------------------------------------------------------------------------
# lsdc


class LsdcError(Exception):
    """lsdc refused the robot; the message is its first error line."""


def first_error(stderr, stdout=""):
    lines = [l.strip() for l in (stderr + "\n" + stdout).splitlines() if l.strip()]
    for line in lines:
        if line.startswith("error"):
            return line
    return lines[0] if lines else "no message"


def run_lsdc(lsdc, args, timeout=600):
    try:
        done = subprocess.run([lsdc] + args, capture_output=True, text=True, timeout=timeout)
    except FileNotFoundError:
        sys.exit(f"error: no lsdc binary at `{lsdc}`: build it (cargo build --release) or pass --lsdc")
    except subprocess.TimeoutExpired:
        raise LsdcError(f"`lsdc {args[0]}` took more than {timeout} s")
    if done.returncode != 0:
        raise LsdcError(first_error(done.stderr, done.stdout))
    return done.stdout


def import_program(lsdc, urdf, floating):
    """The LSD program `lsdc import-urdf` writes for the robot."""
    return run_lsdc(lsdc, ["import-urdf", str(urdf)] + (["--floating-base"] if floating else []))


def evaluate(lsdc, program, states, workdir):
    """`lsdc eval PROGRAM --states ...`: the parsed JSON output."""
    states_path = os.path.join(workdir, "states.json")
    with open(states_path, "w") as f:
        json.dump({"states": states}, f)
    return json.loads(run_lsdc(lsdc, ["eval", str(program), "--states", states_path]))


LET = re.compile(r"^let\s+(\S+)\s*=\s*body\b")
JOIN = re.compile(r"^join\s+(.*?)\s+with\s+.*\s+as\s+(\S+)\s*;")


def urdf_names(urdf):
    """The names of the URDF's links and joints, in the order of the file."""
    robot = ET.parse(urdf).getroot()
    return [l.get("name") for l in robot.findall("link")], [j.get("name") for j in robot.findall("joint")]


def name_map(program, urdf):
    """LSD name -> URDF name for every link and joint, and the LSD name of the base joint.

    The importer writes one `let NAME = body ...` per link and one `join ... as NAME` per joint
    in the order of the URDF file, after the base joint `join earth and ROOT ...`."""
    links, joints = urdf_names(urdf)
    bodies, joins, base = [], [], None
    for line in program.splitlines():
        line = line.strip()
        if m := LET.match(line):
            bodies.append(m.group(1))
        elif m := JOIN.match(line):
            if m.group(1).startswith("earth and ") and base is None:
                base = m.group(2)
            else:
                joins.append(m.group(2))
    if len(bodies) != len(links) or len(joins) != len(joints):
        raise LsdcError(f"cannot match the imported program's names: {len(bodies)} bodies and "
                        f"{len(joins)} joins for {len(links)} links and {len(joints)} joints")
    mapping = dict(zip(bodies, links))
    mapping.update(zip(joins, joints))
    return mapping, base


# ---------------------------------------------------------------------------------------------
# Layouts


class Layout:
    """Where each entry of lsdc's q and v is in Pinocchio's, and how to draw a state.

    positions: per lsdc q entry, (kind, pin_index, limits) with kind `angle` (nq = 1 joint
    coordinate), `cos_sin` (continuous joint: pin q[i], q[i+1] = cos, sin), or `copy` (a free
    joint's coordinates, pin_index the target). velocities: per lsdc v entry, the Pinocchio
    index (the efforts and accelerations use the same)."""

    def __init__(self, model, evaluation, names, base, floating):
        self.nq_pin, self.nv_pin = model.nq, model.nv
        self.positions, self.velocities = [], []
        self.free_quaternions = []  # lsdc q index of each free joint's qw
        pos_names, vel_names = evaluation["positions"], evaluation["velocities"]

        def joint_of(lsd_join):
            if lsd_join == base:
                if not floating:
                    raise LsdcError(f"the base joint `{base}` has coordinates on a fixed base")
                return model.getJointId("root_joint")
            urdf_name = names.get(lsd_join)
            if urdf_name is None or not model.existJointName(urdf_name):
                raise LsdcError(f"lsdc's joint `{lsd_join}` (URDF `{urdf_name}`) is not a Pinocchio joint")
            return model.getJointId(urdf_name)

        free_q = {"px": 0, "py": 1, "pz": 2, "qx": 3, "qy": 4, "qz": 5, "qw": 6}
        free_v = {"v_x": 0, "v_y": 1, "v_z": 2, "ω_x": 3, "ω_y": 4, "ω_z": 5}
        for name in pos_names:
            join, _, coord = name.rpartition(".")
            j = joint_of(join)
            iq, nq, nv = model.idx_qs[j], model.nqs[j], model.nvs[j]
            if nq == 1 and nv == 1 and coord == "q":
                limits = (model.lowerPositionLimit[iq], model.upperPositionLimit[iq])
                self.positions.append(("angle", iq, limits))
            elif nq == 2 and nv == 1 and coord == "q":
                self.positions.append(("cos_sin", iq, None))
            elif nq == 7 and nv == 6 and coord in free_q:
                self.positions.append(("copy", iq + free_q[coord], None))
                if coord == "qw":
                    self.free_quaternions.append(len(self.positions) - 1)
            else:
                raise LsdcError(f"no layout conversion for `{name}` (Pinocchio joint "
                                f"{model.names[j]} of type {model.joints[j].shortname()})")
        for name in vel_names:
            join, _, coord = name.rpartition(".")
            j = joint_of(join)
            iv, nv = model.idx_vs[j], model.nvs[j]
            if nv == 1 and coord == "q":
                self.velocities.append(iv)
            elif nv == 6 and coord in free_v:
                self.velocities.append(iv + free_v[coord])
            else:
                raise LsdcError(f"no layout conversion for velocity `{name}`")
        if len(self.velocities) != model.nv or sorted(self.velocities) != list(range(model.nv)):
            raise LsdcError(f"lsdc has {len(self.velocities)} velocities, Pinocchio {model.nv}: "
                            "the joints do not correspond")

    def random_state(self, rng):
        q = []
        for kind, _, limits in self.positions:
            if kind == "angle":
                q.append(draw_coordinate(rng, *limits))
            elif kind == "cos_sin":
                q.append(rng.uniform(-math.pi, math.pi))
            else:
                q.append(rng.uniform(-1.0, 1.0))
        for i in self.free_quaternions:
            # qw, then the joint's qx, qy, qz follow it in lsdc's order.
            quat = unit_quaternion(rng)
            q[i:i + 4] = quat
        n = len(self.velocities)
        return {
            "q": q,
            "v": [rng.uniform(-1.0, 1.0) for _ in range(n)],
            "a": [rng.uniform(-1.0, 1.0) for _ in range(n)],
            "tau": [rng.uniform(-1.0, 1.0) for _ in range(n)],
        }

    def q_to_pin(self, q):
        import numpy as np
        out = np.zeros(self.nq_pin)
        for value, (kind, i, _) in zip(q, self.positions):
            if kind == "cos_sin":
                out[i], out[i + 1] = math.cos(value), math.sin(value)
            else:
                out[i] = value
        return out

    def v_to_pin(self, v):
        import numpy as np
        out = np.zeros(self.nv_pin)
        for value, i in zip(v, self.velocities):
            out[i] = value
        return out

    def v_from_pin(self, x):
        return [float(x[i]) for i in self.velocities]

    def matrix_from_pin(self, m):
        return [[float(m[i, j]) for j in self.velocities] for i in self.velocities]


def draw_coordinate(rng, lo, hi):
    """Uniform within the limits when they are finite and ordered, else in [-pi, pi]."""
    if math.isfinite(lo) and math.isfinite(hi) and lo < hi and hi - lo < 1e6:
        return rng.uniform(lo, hi)
    return rng.uniform(-math.pi, math.pi)


def unit_quaternion(rng):
    """A uniform random unit quaternion (w, x, y, z) with w >= 0."""
    while True:
        quat = [rng.gauss(0.0, 1.0) for _ in range(4)]
        norm = math.sqrt(sum(x * x for x in quat))
        if norm > 1e-3:
            break
    quat = [x / norm for x in quat]
    return [-x for x in quat] if quat[0] < 0 else quat


# ---------------------------------------------------------------------------------------------
# Pinocchio


class CapturedStderr:
    """Collects what C++ code (urdfdom) writes to file descriptor 2, to keep the table tidy."""

    def __enter__(self):
        sys.stderr.flush()
        self.file = tempfile.TemporaryFile(mode="w+b")
        self.saved = os.dup(2)
        os.dup2(self.file.fileno(), 2)
        return self

    def __exit__(self, *exc):
        sys.stderr.flush()
        os.dup2(self.saved, 2)
        os.close(self.saved)
        self.file.seek(0)
        self.text = self.file.read().decode(errors="replace")
        self.file.close()
        return False


def pinocchio_model(pin, urdf, floating):
    """Pinocchio's model with lsdc's gravity; raises with urdfdom's own message on failure."""
    import numpy as np
    with CapturedStderr() as captured:
        try:
            if floating:
                model = pin.buildModelFromUrdf(str(urdf), pin.JointModelFreeFlyer())
            else:
                model = pin.buildModelFromUrdf(str(urdf))
            error = None
        except Exception as e:
            error = e
    if error is not None:
        detail = " ".join(captured.text.split())
        raise RuntimeError(" ".join(str(error).replace(str(urdf), urdf.name).split()) + (f" ({detail})" if detail else ""))
    model.gravity.linear = np.array([0.0, 0.0, -GRAVITY])
    return model


def pinocchio_results(pin, model, data, layout, state, bodies, names):
    """Pinocchio's RNEA, CRBA, ABA and frames at an lsdc-layout state, in lsdc's layout.
    `bodies` are lsdc's body names, `names` maps them to URDF link names."""
    import numpy as np
    q = layout.q_to_pin(state["q"])
    v = layout.v_to_pin(state["v"])
    a = layout.v_to_pin(state["a"])
    tau = layout.v_to_pin(state["tau"]) if "tau" in state else None
    rnea = pin.rnea(model, data, q, v, a).copy()
    mass = pin.crba(model, data, q).copy()
    mass = np.triu(mass) + np.triu(mass, 1).T
    aba = pin.aba(model, data, q, v, tau).copy() if "tau" in state else None
    pin.framesForwardKinematics(model, data, q)
    frames = {}
    for body in bodies:
        link = names.get(body)
        if link is None or not model.existFrame(link, pin.FrameType.BODY):
            raise LsdcError(f"lsdc's body `{body}` (URDF `{link}`) has no Pinocchio BODY frame")
        pose = data.oMf[model.getFrameId(link, pin.FrameType.BODY)]
        frames[body] = {
            "translation": [float(x) for x in pose.translation],
            "rotation": [[float(pose.rotation[r, c]) for c in range(3)] for r in range(3)],
        }
    return {
        "rnea": layout.v_from_pin(rnea),
        "crba": layout.matrix_from_pin(mass),
        "aba": layout.v_from_pin(aba) if aba is not None else None,
        "frames": frames,
    }


# ---------------------------------------------------------------------------------------------
# Comparison


def flatten(quantity, value, velocity_names):
    """(label, number) pairs of a quantity in lsdc's layout."""
    if quantity in ("rnea", "aba"):
        return [(velocity_names[i], x) for i, x in enumerate(value)]
    if quantity == "crba":
        return [(f"[{velocity_names[i]}, {velocity_names[j]}]", x)
                for i, row in enumerate(value) for j, x in enumerate(row)]
    out = []
    for body, pose in value.items():
        out += [(f"{body}.translation[{k}]", x) for k, x in enumerate(pose["translation"])]
        out += [(f"{body}.rotation[{r}][{c}]", x) for r, row in enumerate(pose["rotation"]) for c, x in enumerate(row)]
    return out


def disagreement(mine, reference):
    """(d, label, mine, reference) of the worst entry: d = max|diff| / max(1, max|reference|)."""
    scale = max([1.0] + [abs(x) for _, x in reference])
    worst = (0.0, None, None, None)
    for (label, x), (_, y) in zip(mine, reference):
        d = abs(x - y) / scale if math.isfinite(x) and math.isfinite(y) else math.inf
        if d > worst[0] or worst[1] is None:
            worst = (d, label, x, y)
    return worst


def lsdc_in_common_form(output):
    """One state of `lsdc eval`'s output with frames as {body: pose}."""
    return {
        "rnea": output.get("rnea"),
        "crba": output["crba"],
        "aba": output.get("aba"),
        "frames": {f["body"]: {"translation": f["translation"], "rotation": f["rotation"]} for f in output["frames"]},
    }


def seed_of(text):
    return int(hashlib.sha256(text.encode()).hexdigest()[:12], 16)


def compare_robot(pin, lsdc, urdf, label, floating, nstates, workdir):
    """A result row: status, sizes and the worst disagreement of each quantity."""
    row = {"robot": label, "base": "floating" if floating else "fixed", "nq": None, "nv": None,
           "status": "compared", "worst": {}}
    try:
        model = pinocchio_model(pin, urdf, floating)
    except Exception as e:
        row["status"] = "pinocchio could not read it: " + " ".join(str(e).split())[:200]
        return row
    row["nq"], row["nv"] = model.nq, model.nv
    data = model.createData()
    try:
        program_text = import_program(lsdc, urdf, floating)
        names, base = name_map(program_text, urdf)
        if floating:
            program = os.path.join(workdir, "robot.lsd")
            with open(program, "w") as f:
                f.write(program_text)
        else:
            program = str(urdf)
        layout_eval = evaluate(lsdc, program, [], workdir)
        layout = Layout(model, layout_eval, names, base, floating)
        rng = random.Random(seed_of(label + ("/floating" if floating else "/fixed")))
        states = [layout.random_state(rng) for _ in range(nstates)]
        try:
            evaluation = evaluate(lsdc, program, states, workdir)
        except LsdcError as e:
            if "singular" not in str(e):
                raise
            # A massless link at the end of a moving joint: no forward dynamics (Pinocchio's
            # ABA gives NaN there). The other quantities are still compared.
            row["note"] = f"aba not compared: {str(e)[:120]}"
            states = [{k: x for k, x in state.items() if k != "tau"} for state in states]
            evaluation = evaluate(lsdc, program, states, workdir)
    except LsdcError as e:
        row["status"] = "lsdc could not read it: " + str(e)[:160]
        return row
    row["lsdc_nq"], row["lsdc_nv"] = len(layout_eval["positions"]), len(layout_eval["velocities"])
    vnames = evaluation["velocities"]
    bodies = [f["body"] for f in evaluation["states"][0]["frames"]] if evaluation["states"] else []
    for s, (state, output) in enumerate(zip(states, evaluation["states"])):
        try:
            reference = pinocchio_results(pin, model, data, layout, state, bodies, names)
        except LsdcError as e:
            row["status"] = "not comparable: " + str(e)[:160]
            return row
        mine = lsdc_in_common_form(output)
        for quantity in QUANTITIES:
            if mine[quantity] is None:
                continue
            d, entry, x, y = disagreement(flatten(quantity, mine[quantity], vnames),
                                          flatten(quantity, reference[quantity], vnames))
            if quantity not in row["worst"] or d > row["worst"][quantity]["d"]:
                row["worst"][quantity] = {"d": d, "state": s, "entry": entry, "lsdc": x, "pinocchio": y}
    return row


def format_d(worst):
    return "-" if worst is None else f"{worst['d']:.1e}"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--lsdc", default=default_lsdc(), help="the lsdc binary (default: target/release/lsdc or target/debug/lsdc)")
    parser.add_argument("--states", type=int, default=5, help="random states per robot (default 5)")
    parser.add_argument("--robots", help="example-robot-data's robots directory (default: found with the pip package)")
    parser.add_argument("--only", action="append", default=[], help="only the URDF files whose path contains this (repeatable)")
    parser.add_argument("--no-floating", action="store_true", help="skip the floating-base runs")
    parser.add_argument("--tolerance", type=float, default=1e-9, help="exit with status 1 above this disagreement (default 1e-9)")
    parser.add_argument("--json", help="also write every row, with the worst entries, to this file")
    args = parser.parse_args()

    pin = require_pinocchio()
    robots = robots_directory(args.robots)
    urdfs = sorted(robots.rglob("*.urdf"))
    if args.only:
        urdfs = [u for u in urdfs if any(s in str(u.relative_to(robots)) for s in args.only)]
    print(f"Pinocchio {pin.__version__}, example-robot-data {package_version('example-robot-data')}, "
          f"lsdc {args.lsdc}; {len(urdfs)} URDF files under {robots}")
    print(f"disagreement d = max|lsdc - pinocchio| / max(1, max|pinocchio|) per quantity, worst of {args.states} states\n")

    rows = []
    header = f"{'robot':<66} {'base':<8} {'nq/nv':>7}  {'rnea':>8} {'crba':>8} {'aba':>8} {'frames':>8}  status"
    print(header)
    print("-" * len(header))
    with tempfile.TemporaryDirectory(prefix="pinocchio_compare_") as workdir:
        for urdf in urdfs:
            label = str(urdf.relative_to(robots))
            for floating in ([False] if args.no_floating else [False, True]):
                row = compare_robot(pin, args.lsdc, urdf, label, floating, args.states, workdir)
                rows.append(row)
                sizes = f"{row['nq']}/{row['nv']}" if row["nq"] is not None else "-"
                cells = " ".join(f"{format_d(row['worst'].get(q)):>8}" for q in QUANTITIES)
                status = row["status"] + (f"; {row['note']}" if row.get("note") else "")
                print(f"{label:<66} {row['base']:<8} {sizes:>7}  {cells}  {status}", flush=True)

    compared = [r for r in rows if r["status"] == "compared"]
    fixed = [r for r in compared if r["base"] == "fixed"]
    floating = [r for r in compared if r["base"] == "floating"]
    print()
    print(f"{len(urdfs)} URDF files found; compared {len(fixed)} with a fixed base and {len(floating)} with a floating base; "
          f"{sum(r['status'].startswith('lsdc') for r in rows)} runs lsdc could not read, "
          f"{sum(r['status'].startswith('pinocchio') for r in rows)} Pinocchio could not read, "
          f"{sum(r['status'].startswith('not comparable') for r in rows)} not comparable.")
    worst = None
    for r in compared:
        for q, w in r["worst"].items():
            if worst is None or w["d"] > worst[2]["d"]:
                worst = (r, q, w)
    if worst:
        r, q, w = worst
        print(f"worst disagreement: {w['d']:.3g} in {q} of {r['robot']} ({r['base']} base), state {w['state']}, "
              f"entry {w['entry']}: lsdc {w['lsdc']!r}, pinocchio {w['pinocchio']!r}")
        for quantity in QUANTITIES:
            best = max((rr for rr in compared if quantity in rr["worst"]), key=lambda rr: rr["worst"][quantity]["d"], default=None)
            if best:
                w = best["worst"][quantity]
                print(f"  worst {quantity:<6} {w['d']:.3g}  {best['robot']} ({best['base']}), state {w['state']}, {w['entry']}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)
    failing = [r for r in compared if any(w["d"] > args.tolerance for w in r["worst"].values())]
    if failing:
        print(f"{len(failing)} compared runs disagree by more than {args.tolerance:g}")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
