#!/usr/bin/env python3
"""Writes the Pinocchio reference fixtures of tests/suite/pinocchio_fixtures.rs.

The Rust test suite cannot run Python, so this script stores Pinocchio's answers once:

* it copies a few URDF files of example-robot-data into tests/fixtures/urdf/ (byte for byte; a
  file over 300 KB would go to bench/urdf/ instead and get no test fixture);
* for each, it draws 4 random states and writes tests/fixtures/pinocchio/<robot>.json with
  Pinocchio's RNEA, CRBA (symmetrised), ABA and body-frame poses at those states.

Every array of a fixture is in lsdc's layout, so the test reads it without conversions:
`positions` and `velocities` name the entries of q and v (and of a, tau, rnea, aba and the rows
and columns of crba); `frames` maps each lsdc body name to its world pose (`translation` and
`rotation`, the rotation matrix by rows). Conventions, gravity, how states are drawn and the
layout conversions are those of bench/pinocchio_compare.py (read its docstring): joints are
matched by name, a continuous joint's angle becomes Pinocchio's (cos, sin), a free joint's
(px, py, pz, qw, qx, qy, qz) / (omega, v) becomes Pinocchio's (x, y, z, qx, qy, qz, qw) / (v, omega).

The names and their order are lsdc's: the script runs `lsdc import-urdf` (which links and joints
got which LSD names) and `lsdc eval` with an empty list of states (the order of q and v and, with
the states, the list of bodies). lsdc's own numbers are not written: the script only prints how
far they are from Pinocchio's, as a check. If lsdc's joint order changes, the test says that the
names no longer agree: run this script again.

Numbers are written with Python's repr, the shortest text that reads back as the same double:
no digit is lost.

Usage:  python3 bench/pinocchio_fixtures.py [--lsdc PATH] [--robots DIR]
Needs `pip install pin example-robot-data`, and a built lsdc (default target/release/lsdc, else
target/debug/lsdc).
"""

import argparse
import datetime
import hashlib
import json
import os
import pathlib
import random
import shutil
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pinocchio_compare import (  # noqa: E402  (the shared conventions)
    GRAVITY, QUANTITIES, Layout, default_lsdc, disagreement, evaluate, flatten, import_program,
    lsdc_in_common_form, name_map, package_version, pinocchio_model, pinocchio_results,
    require_pinocchio, robots_directory, seed_of,
)

REPO = pathlib.Path(__file__).resolve().parent.parent
SIZE_LIMIT = 300_000  # bytes: larger URDF files stay out of tests/

# (fixture name, path under example-robot-data's robots directory, floating base, why)
ROBOTS = [
    ("ur5", "ur_description/urdf/ur5_robot.urdf", False, "6-dof arm, revolute joints, fixed joints"),
    ("panda", "panda_description/urdf/panda.urdf", False, "7-dof arm with two prismatic finger joints"),
    ("kinova", "kinova_description/robots/kinova.urdf", False, "arm with continuous joints (Pinocchio's cos/sin)"),
    ("double_pendulum", "double_pendulum_description/urdf/double_pendulum.urdf", False, "the double pendulum"),
    ("talos_reduced", "talos_data/robots/talos_reduced.urdf", True, "humanoid, floating base"),
    ("solo12", "solo_description/robots/solo12.urdf", True, "quadruped, floating base"),
]
STATES = 4


def format_json(value, indent=0):
    """JSON with one line per list of numbers (and per matrix row); floats as repr."""
    pad, inner = " " * indent, " " * (indent + 2)
    if isinstance(value, dict):
        if not value:
            return "{}"
        items = [f"{inner}{json.dumps(k)}: {format_json(v, indent + 2)}" for k, v in value.items()]
        return "{\n" + ",\n".join(items) + "\n" + pad + "}"
    if isinstance(value, list):
        if all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in value):
            return "[" + ", ".join(number(x) for x in value) + "]"
        if all(isinstance(x, str) for x in value):
            return "[" + ", ".join(json.dumps(x, ensure_ascii=False) for x in value) + "]"
        items = [inner + format_json(x, indent + 2) for x in value]
        return "[\n" + ",\n".join(items) + "\n" + pad + "]"
    if isinstance(value, float):
        return number(value)
    return json.dumps(value, ensure_ascii=False)


def number(x):
    x = float(x)
    if x != x or x in (float("inf"), float("-inf")):
        raise ValueError("a fixture value is not finite")
    return repr(x)


def sha256(path):
    return hashlib.sha256(pathlib.Path(path).read_bytes()).hexdigest()


def write_fixture(pin, lsdc, robots, name, source, floating, why, workdir):
    src = robots / source
    size = src.stat().st_size
    folder = REPO / "tests" / "fixtures" / "urdf" if size <= SIZE_LIMIT else REPO / "bench" / "urdf"
    folder.mkdir(parents=True, exist_ok=True)
    urdf = folder / f"{name}.urdf"
    shutil.copyfile(src, urdf)
    relative = urdf.relative_to(REPO).as_posix()
    if size > SIZE_LIMIT:
        print(f"{name}: {size} bytes, copied to {relative} for the speed comparison; no test fixture")
        return None

    model = pinocchio_model(pin, urdf, floating)
    data = model.createData()
    program_text = import_program(lsdc, urdf, floating)
    names, base = name_map(program_text, urdf)
    if floating:
        program = os.path.join(workdir, f"{name}.lsd")
        pathlib.Path(program).write_text(program_text)
    else:
        program = str(urdf)
    layout_eval = evaluate(lsdc, program, [], workdir)
    layout = Layout(model, layout_eval, names, base, floating)
    rng = random.Random(seed_of(f"fixture/{name}"))
    states = [layout.random_state(rng) for _ in range(STATES)]
    # lsdc at the same states: for the list of bodies, and to print how far it is from Pinocchio.
    evaluation = evaluate(lsdc, program, states, workdir)
    bodies = [f["body"] for f in evaluation["states"][0]["frames"]]

    fixture_states = []
    worst = {}
    for index, (state, output) in enumerate(zip(states, evaluation["states"])):
        reference = pinocchio_results(pin, model, data, layout, state, bodies, names)
        fixture_states.append({**state, **reference})
        mine = lsdc_in_common_form(output)
        for quantity in QUANTITIES:
            d = disagreement(flatten(quantity, mine[quantity], evaluation["velocities"]),
                             flatten(quantity, reference[quantity], evaluation["velocities"]))[0]
            worst[quantity] = max(worst.get(quantity, 0.0), d)

    fixture = {
        "provenance": {
            "description": f"Pinocchio's RNEA, CRBA, ABA and body-frame poses for {name} ({why}), in lsdc's layout",
            "script": "bench/pinocchio_fixtures.py",
            "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d"),
            "pinocchio": pin.__version__,
            "example_robot_data": package_version("example-robot-data"),
            "source": f"example-robot-data: robots/{source}",
            "sha256": sha256(urdf),
            "gravity": [0.0, 0.0, -GRAVITY],
            "base": "a JointModelFreeFlyer root joint" if floating else "fixed (the root link is the universe's)",
            "rnea": "pinocchio.rnea(q, v, a): generalised forces for the accelerations a, gravity included",
            "crba": "pinocchio.crba(q), upper triangle mirrored",
            "aba": "pinocchio.aba(q, v, tau)",
            "frames": "data.oMf of each link's BODY frame after framesForwardKinematics(q); rotation by rows",
            "layout": "joints matched by name with lsdc's; continuous joint angle -> (cos, sin); free joint "
                      "(px,py,pz,qw,qx,qy,qz)/(omega,v) <-> Pinocchio (x,y,z,qx,qy,qz,qw)/(v,omega), both local",
            "names": "positions, velocities and body names from `lsdc import-urdf` and `lsdc eval`",
            "measure": "d = max|lsdc - pinocchio| / max(1, max|pinocchio|) per quantity and state",
        },
        "robot": name,
        "urdf": relative,
        "floating_base": floating,
        "positions": layout_eval["positions"],
        "velocities": layout_eval["velocities"],
        "states": fixture_states,
    }
    out = REPO / "tests" / "fixtures" / "pinocchio" / f"{name}.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(format_json(fixture) + "\n")
    json.loads(out.read_text())  # reads back
    sizes = f"nq={model.nq} nv={model.nv}, lsdc nq={len(layout_eval['positions'])}"
    report = ", ".join(f"{q} {worst[q]:.1e}" for q in QUANTITIES)
    print(f"{name}: {relative} ({size} bytes, {sizes}) -> {out.relative_to(REPO)}; lsdc now: {report}")
    return max(worst.values())


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--lsdc", default=default_lsdc(), help="the lsdc binary (default: target/release/lsdc or target/debug/lsdc)")
    parser.add_argument("--robots", help="example-robot-data's robots directory (default: found with the pip package)")
    args = parser.parse_args()
    pin = require_pinocchio()
    robots = robots_directory(args.robots)
    print(f"Pinocchio {pin.__version__}, example-robot-data {package_version('example-robot-data')}, lsdc {args.lsdc}")
    with tempfile.TemporaryDirectory(prefix="pinocchio_fixtures_") as workdir:
        for name, source, floating, why in ROBOTS:
            write_fixture(pin, args.lsdc, robots, name, source, floating, why, workdir)
    return 0


if __name__ == "__main__":
    sys.exit(main())
