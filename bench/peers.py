#!/usr/bin/env python3
"""lsdc beside its peers, timed the same way on a shared machine: Pinocchio (RNEA, CRBA, ABA and
the analytical derivatives of RNEA and ABA on URDF robots) and MuJoCo (whole RK4 steps of the same robots; one evaluation of rows of N
parallelogram four-bars, loops closed).

Three probes answer one protocol: each loads its cases, prints `ready CASE...`, then answers a
line `CASE CALLS` with the CPU seconds its timing thread spent on CALLS calls (the thread's CPU
clock, CLOCK_THREAD_CPUTIME_ID: time the machine gave to other programs is left out):

  lsdc       `cargo bench --bench peers` (benches/peers.rs), the library called in-process;
  Pinocchio  bench/peers/pinocchio_probe.cpp, compiled here with g++ -O3 -DNDEBUG against the
             pip package's headers and libraries (`pip install pin`), no -march=native (lsdc is
             built by cargo without target-cpu: both sides are portable x86-64 code);
  MuJoCo     bench/peers/mujoco_probe.c, compiled against the pip package's libmujoco
             (`pip install mujoco`), on models this script writes (target/peers/models/).

Each pair of cases is timed round by round: in each round one batch of about --batch seconds on
each side, the side that goes first alternating, so that a change of the machine's speed falls
on both. Per side and case: the best and the median over the rounds of the time per call; the
ratios lsdc / peer of the bests and of the medians. Where the derivatives are timed, a second
table sets each side's derivatives against its own algorithms: per robot and side, RNEA, its
derivatives (lsdc's `RneaDerivatives`, Pinocchio's `computeRNEADerivatives`: dtau/dq, dtau/dv)
and their ratio; ABA, its derivatives (`AbaDerivatives`, `computeABADerivatives`: ddq/dq, ddq/dv,
Minv) and their ratio; and lsdc / Pinocchio of the derivatives (`--only derivatives` times these
with the algorithms they are set against).

Cases: UR5, Panda and Talos (reduced) from example-robot-data (the URDF files
bench/pinocchio_fixtures.py copies into tests/fixtures/urdf/), fixed base, gravity 9.80665 along
-z, 256 random states cycled (Pinocchio: coordinates within the joint limits; lsdc: in [-pi, pi]);
steps of RK4 at 1 ms from rest at q = 0, started again every 1,000 steps outside the timing
(MuJoCo: the URDF without visual or collision geometry, joint limits off, so there are no
contacts nor limit rows; lsdc: the stiffness check off and the joints' limits off, so no
stops); the rows of N = 10, 20, 40, 70, 100 four-bars of
benches/common/rows.rs at their initial state (cranks hanging, turning at 12 rad/s): MuJoCo's
`mj_forward` with each closing revolute as a `connect` equality (the three rows of a point
joint; the hinges' axes are all z), lsdc's right-hand side (`MechanicalSystem::derivative`);
and lsdc's same bodies without the closing joins (a tree), for the loops' share.

Usage:
    python3 bench/peers.py [--rounds R] [--batch SECONDS] [--only SUBSTRING] [--json OUT.json]
                           [--lsdc-probe EXECUTABLE]

Needs a Python with `pip install pin example-robot-data mujoco cmeel-eigen cmeel-urdfdom-headers`
(Pinocchio's headers need Eigen's and urdfdom's), g++ and gcc; the rows alone (`--only row`)
need only `pip install mujoco` and gcc; the algorithms and their derivatives alone (`--only
derivatives`, `--only RNEA`...) need no MuJoCo. The Pinocchio probe takes a few
minutes to compile; it is kept in target/peers/ and compiled again when its source or the
flags change.
"""

import argparse
import datetime
import json
import math
import os
import pathlib
import platform
import statistics
import subprocess
import sys
import xml.etree.ElementTree as ET

REPO = pathlib.Path(__file__).resolve().parent.parent
OUT = REPO / "target" / "peers"
ROBOTS = {"ur5": "ur5", "panda": "panda", "talos": "talos_reduced"}
ALGORITHMS = ("rnea", "crba", "aba", "rnea_derivatives", "aba_derivatives")
STEPPED = ("ur5", "panda")
ROWS = (10, 20, 40, 70, 100)
GRAVITY = 9.80665


def algorithm_label(algorithm, robot):
    """`RNEA ur5`, `RNEA derivatives ur5`..."""
    return f"{algorithm.upper().replace('_', ' ').replace('DERIVATIVES', 'derivatives')} {robot}"


def derivative_rows(pairs, best_median, lsdc, pin):
    """Per robot whose derivatives and algorithms were timed on both sides: each side's times
    (ns, best and median) of RNEA, ABA and their derivatives, its ratios derivatives /
    algorithm, and lsdc / Pinocchio of the derivatives."""
    timed = {ours for _, ours, _, _ in pairs}
    rows = []
    for name in ROBOTS:
        cases = [f"{name}/{algorithm}" for algorithm in
                 ("rnea", "rnea_derivatives", "aba", "aba_derivatives")]
        if pin is None or not all(case in timed for case in cases):
            continue
        row = {"robot": name}
        for side, probe in (("lsdc", lsdc), ("Pinocchio", pin)):
            t = {case.split("/")[1]: [x * 1e9 for x in best_median(probe, case)] for case in cases}
            for algorithm in ("rnea", "aba"):
                t[f"{algorithm}_ratio"] = [d / a for d, a in
                                           zip(t[f"{algorithm}_derivatives"], t[algorithm])]
            row[side] = t
        for algorithm in ("rnea_derivatives", "aba_derivatives"):
            row[f"{algorithm}_ratio"] = [o / p for o, p in
                                         zip(row["lsdc"][algorithm], row["Pinocchio"][algorithm])]
        rows.append(row)
    return rows


def fail(message):
    sys.exit(f"error: {message}")


def require(module, package):
    try:
        return __import__(module)
    except ImportError as e:
        fail(f"{module} is not installed for {sys.executable} ({e})\n"
             f"help: pip install {package}")


def urdf_path(stem):
    for directory in ("tests/fixtures/urdf", "bench/urdf"):
        path = REPO / directory / f"{stem}.urdf"
        if path.is_file():
            return path
    fail(f"no {stem}.urdf in tests/fixtures/urdf or bench/urdf: run python3 bench/pinocchio_fixtures.py")


def compile_if_needed(command, source, binary):
    """Runs `command` (which writes `binary`) unless `binary` is newer than `source` and was
    made by the same command."""
    stamp = binary.with_suffix(".command")
    wanted = " ".join(command)
    if binary.exists() and binary.stat().st_mtime >= source.stat().st_mtime \
            and stamp.exists() and stamp.read_text() == wanted:
        return
    print(f"compiling {source.relative_to(REPO)}...", file=sys.stderr)
    result = subprocess.run(command, cwd=REPO)
    if result.returncode != 0:
        fail(f"{source.relative_to(REPO)} does not compile")
    stamp.write_text(wanted)


def pinocchio_probe():
    import cmeel
    prefix = pathlib.Path(cmeel.__file__).resolve().parent.parent / "cmeel.prefix"
    include = prefix / "include"
    for needed, package in ((include / "pinocchio/algorithm/crba.hpp", "pin"),
                            (include / "eigen3/Eigen/Core", "cmeel-eigen"),
                            (include / "urdfdom_headers/urdf_model/model.h", "cmeel-urdfdom-headers")):
        if not needed.exists():
            fail(f"{needed} is missing: pip install {package}")
    source = REPO / "bench/peers/pinocchio_probe.cpp"
    binary = OUT / "pinocchio_probe"
    # The definitions Pinocchio's CMake targets give their users (pinocchio::pinocchio_parsers).
    defines = ["-DNDEBUG", "-DPINOCCHIO_WITH_URDFDOM",
               "-DPINOCCHIO_URDFDOM_HEADERS_MAJOR_VERSION=3",
               "-DPINOCCHIO_URDFDOM_HEADERS_MINOR_VERSION=0",
               "-DPINOCCHIO_URDFDOM_HEADERS_PATCH_VERSION=0",
               "-DBOOST_MPL_LIMIT_LIST_SIZE=30", "-DBOOST_MPL_LIMIT_VECTOR_SIZE=30",
               "-DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS", "-DBOOST_FUSION_INVOKE_MAX_ARITY=12"]
    command = [os.environ.get("CXX", "g++"), "-std=c++17", "-O3", *defines,
               f"-I{include}", f"-I{include / 'eigen3'}", f"-I{include / 'urdfdom_headers'}",
               str(source), "-o", str(binary), f"-L{prefix / 'lib'}",
               f"-Wl,-rpath,{prefix / 'lib'}", "-lpinocchio_parsers", "-lpinocchio_default",
               "-lurdfdom_model"]
    compile_if_needed(command, source, binary)
    return binary


def mujoco_probe(mujoco):
    package = pathlib.Path(mujoco.__file__).resolve().parent
    libraries = sorted(package.glob("libmujoco.so*"))
    if not libraries or not (package / "include/mujoco/mujoco.h").exists():
        fail(f"MuJoCo's library or headers are missing under {package}: pip install mujoco")
    source = REPO / "bench/peers/mujoco_probe.c"
    binary = OUT / "mujoco_probe"
    command = [os.environ.get("CC", "gcc"), "-O2", "-std=c11", "-D_POSIX_C_SOURCE=200809L",
               f"-I{package / 'include'}", str(source), "-o", str(binary), str(libraries[0]),
               f"-Wl,-rpath,{package}"]
    compile_if_needed(command, source, binary)
    return binary


def mujoco_robot(mujoco, urdf, out):
    """The URDF robot as MJCF: no visual or collision geometry (so no meshes and no contacts),
    joint limits off, RK4 at 1 ms, gravity as lsdc's URDF import has it."""
    tree = ET.parse(urdf)
    for link in tree.getroot().iter("link"):
        for geometry in link.findall("visual") + link.findall("collision"):
            link.remove(geometry)
    spec = mujoco.MjSpec.from_string(ET.tostring(tree.getroot(), encoding="unicode"))
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_RK4
    spec.option.timestep = 1e-3
    spec.option.gravity = [0.0, 0.0, -GRAVITY]
    for joint in spec.joints:
        joint.limited = mujoco.mjtLimited.mjLIMITED_FALSE
    spec.compile()
    out.write_text(spec.to_xml())


def mujoco_row(n, out):
    """The row of `n` parallelogram four-bars of benches/common/rows.rs as MJCF: crank k pivoted
    on the ground at x = k L, coupler k on crank k-1's tip, its far end joined to crank k's tip
    by a `connect` equality; bars of 1 kg/m with lsdc's inertias, gravity 9.81 along -y. The
    bodies' frames are placed so that qpos = 0 is lsdc's initial configuration (cranks at -pi/2,
    couplers at +pi/2 on them); the keyframe gives lsdc's initial rates (cranks 12 rad/s,
    couplers translating)."""
    crank, rod = 0.5, 1.0

    def inertial(length):
        return (f'<inertial pos="{length / 2} 0 0" mass="{length}" '
                f'diaginertia="{1e-4 * length} {length ** 3 / 12} {length ** 3 / 12}"/>')

    def crank_body(k, inner):
        return (f'<body name="crank{k}" pos="{k * rod} 0 0" euler="0 0 -90">'
                f'<joint name="c{k}" type="hinge" axis="0 0 1"/>{inertial(crank)}{inner}</body>')

    bodies = []
    for k in range(n + 1):
        inner = ""
        if k < n:
            inner = (f'<body name="rod{k + 1}" pos="{crank} 0 0" euler="0 0 90">'
                     f'<joint name="p{k + 1}" type="hinge" axis="0 0 1"/>{inertial(rod)}</body>')
        bodies.append(crank_body(k, inner))
    connects = "".join(f'<connect body1="rod{k}" body2="crank{k}" anchor="{rod} 0 0"/>'
                       for k in range(1, n + 1))
    rates = " ".join(["12 -12"] * n + ["12"])
    out.write_text(f'<mujoco model="row{n}"><compiler angle="degree"/>'
                   f'<option gravity="0 -9.81 0" timestep="0.001"/>'
                   f'<worldbody>{"".join(bodies)}</worldbody><equality>{connects}</equality>'
                   f'<keyframe><key qvel="{rates}"/></keyframe></mujoco>\n')


class Probe:
    """One side: a process that answers `CASE CALLS` with CPU seconds."""

    def __init__(self, name, command):
        self.name = name
        self.process = subprocess.Popen(command, cwd=REPO, stdin=subprocess.PIPE,
                                        stdout=subprocess.PIPE, text=True, bufsize=1)
        line = self.process.stdout.readline().split()
        if not line or line[0] != "ready":
            fail(f"the {name} probe did not start ({' '.join(command)})")
        self.cases = set(line[1:])

    def seconds(self, case, calls):
        self.process.stdin.write(f"{case} {calls}\n")
        answer = self.process.stdout.readline().strip()
        try:
            return float(answer)
        except ValueError:
            fail(f"the {self.name} probe answered `{answer}` to `{case} {calls}`")

    def close(self):
        self.process.stdin.close()
        self.process.wait()


def calibrate(probe, case, batch):
    """The number of calls that takes about `batch` seconds of CPU."""
    calls = 1
    while True:
        spent = probe.seconds(case, calls)
        if spent >= batch / 4:
            return max(1, math.ceil(calls * batch / spent))
        calls *= 10 if spent < batch / 40 else 4


def loads():
    try:
        return os.getloadavg()
    except OSError:
        return (float("nan"),) * 3


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=9)
    parser.add_argument("--batch", type=float, default=0.03, help="seconds of CPU per batch")
    parser.add_argument("--only", default="", help="only the pairs whose label contains this")
    parser.add_argument("--json", help="also write the measurements to this file")
    parser.add_argument("--lsdc-probe", help="lsdc's probe already built (the executable "
                        "`cargo bench --no-run --bench peers` names) instead of `cargo bench`")
    args = parser.parse_args()

    # The pairs first, by label: `--only` leaves out the sides (and the packages) they need.
    labels = [algorithm_label(algorithm, name) for algorithm in ALGORITHMS for name in ROBOTS]
    labels += [f"RK4 step {name}" for name in STEPPED]
    labels += [f"row of {n}" for n in ROWS] + [f"row of {n}: loops / tree" for n in ROWS]
    wanted = [label for label in labels if args.only in label]
    # A robot's derivatives are set against its algorithms: time those too.
    for name in ROBOTS:
        for algorithm in ("rnea", "aba"):
            if algorithm_label(f"{algorithm}_derivatives", name) in wanted \
                    and algorithm_label(algorithm, name) not in wanted:
                wanted.append(algorithm_label(algorithm, name))
    robots = any(not label.startswith("row") for label in wanted)
    stepped = [name for name in STEPPED if f"RK4 step {name}" in wanted]
    rows = [n for n in ROWS if any(label.startswith(f"row of {n}") for label in wanted)]

    OUT.mkdir(parents=True, exist_ok=True)
    models = OUT / "models"
    models.mkdir(exist_ok=True)
    urdfs = {name: urdf_path(stem) for name, stem in ROBOTS.items()} if robots else {}
    mujoco = require("mujoco", "mujoco") if stepped or rows else None
    mujoco_binary = mujoco_probe(mujoco) if mujoco else None
    for name in stepped:
        mujoco_robot(mujoco, urdfs[name], models / f"{name}.xml")
    for n in rows:
        mujoco_row(n, models / f"row{n}.xml")

    robot_arguments = [f"{name}={path}" for name, path in urdfs.items()]
    if args.lsdc_probe:
        print(f"starting lsdc's probe ({args.lsdc_probe})...", file=sys.stderr)
        lsdc_command = [args.lsdc_probe]
    else:
        print("building and starting lsdc's probe (cargo bench --bench peers)...",
              file=sys.stderr)
        lsdc_command = ["cargo", "bench", "--locked", "--bench", "peers", "--"]
    lsdc = Probe("lsdc", [*lsdc_command, *robot_arguments, *[f"row{n}" for n in rows]])
    pin = None
    if robots:
        require("pinocchio", "pin")
        require("cmeel", "pin")
        pin = Probe("Pinocchio", [str(pinocchio_probe()), *robot_arguments])
    muj = None
    if mujoco:
        muj = Probe("MuJoCo", [str(mujoco_binary),
                               *[f"{name}={models / f'{name}.xml'}" for name in stepped],
                               *[f"row{n}={models / f'row{n}.xml'}" for n in rows]])

    pairs = []  # (label, lsdc case, peer probe, peer case)
    for algorithm in ALGORITHMS:
        for name in ROBOTS:
            pairs.append((algorithm_label(algorithm, name), f"{name}/{algorithm}", pin,
                          f"{name}/{algorithm}"))
    for name in STEPPED:
        pairs.append((f"RK4 step {name}", f"{name}/step", muj, f"{name}/step"))
    for n in ROWS:
        pairs.append((f"row of {n}", f"row{n}/evaluation", muj, f"row{n}/forward"))
    for n in ROWS:
        pairs.append((f"row of {n}: loops / tree", f"row{n}/evaluation", lsdc, f"row{n}/tree"))
    pairs = [p for p in pairs if p[0] in wanted]

    started, load_before = datetime.datetime.now(datetime.timezone.utc), loads()
    calls = {}
    for _, ours, peer, theirs in pairs:
        for probe, case in ((lsdc, ours), (peer, theirs)):
            if (probe.name, case) not in calls:
                calls[(probe.name, case)] = calibrate(probe, case, args.batch)
    times = {key: [] for key in calls}
    for round_number in range(args.rounds):
        for _, ours, peer, theirs in pairs:
            sides = [(lsdc, ours), (peer, theirs)]
            if round_number % 2:
                sides.reverse()
            for probe, case in sides:
                n = calls[(probe.name, case)]
                times[(probe.name, case)].append(probe.seconds(case, n) / n)
    load_after = loads()
    for probe in (lsdc, pin, muj):
        if probe is not None:
            probe.close()

    def best_median(probe, case):
        values = times[(probe.name, case)]
        return min(values), statistics.median(values)

    rows = []
    for label, ours, peer, theirs in pairs:
        (ob, om), (pb, pm) = best_median(lsdc, ours), best_median(peer, theirs)
        rows.append({"pair": label, "peer": peer.name if peer is not lsdc else "lsdc (tree)",
                     "lsdc_best_ns": ob * 1e9, "lsdc_median_ns": om * 1e9,
                     "peer_best_ns": pb * 1e9, "peer_median_ns": pm * 1e9,
                     "ratio_best": ob / pb, "ratio_median": om / pm})

    versions = ", ".join(
        ([f"Pinocchio {sys.modules['pinocchio'].__version__}"] if pin is not None else [])
        + ([f"MuJoCo {mujoco.__version__}"] if mujoco else []))
    print(f"\n{started:%Y-%m-%d %H:%M} UTC, {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} CPUs; load average {load_before[0]:.1f} before, {load_after[0]:.1f} after; "
          f"{versions}; {args.rounds} rounds of "
          f"{args.batch * 1e3:.0f} ms batches per side; thread CPU time per call, ns\n")
    print("| work | peer | lsdc best | lsdc median | peer best | peer median | ratio of bests | ratio of medians |")
    print("|---|---|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {r['pair']} | {r['peer']} | {r['lsdc_best_ns']:,.0f} | {r['lsdc_median_ns']:,.0f} | "
              f"{r['peer_best_ns']:,.0f} | {r['peer_median_ns']:,.0f} | "
              f"**{r['ratio_best']:.2f}** | {r['ratio_median']:.2f} |")
    derivatives = derivative_rows(pairs, best_median, lsdc, pin)
    if derivatives:
        print("\nEach side's derivatives against its own algorithms (ns per call, best / median):\n")
        print("| robot | side | RNEA | ∂RNEA | ratio | ABA | ∂ABA | ratio |")
        print("|---|---|---:|---:|---:|---:|---:|---:|")
        for d in derivatives:
            for side in ("lsdc", "Pinocchio"):
                t = d[side]
                print(f"| {d['robot']} | {side} | {t['rnea'][0]:,.0f} / {t['rnea'][1]:,.0f} | "
                      f"{t['rnea_derivatives'][0]:,.0f} / {t['rnea_derivatives'][1]:,.0f} | "
                      f"**{t['rnea_ratio'][0]:.2f}** / {t['rnea_ratio'][1]:.2f} | "
                      f"{t['aba'][0]:,.0f} / {t['aba'][1]:,.0f} | "
                      f"{t['aba_derivatives'][0]:,.0f} / {t['aba_derivatives'][1]:,.0f} | "
                      f"**{t['aba_ratio'][0]:.2f}** / {t['aba_ratio'][1]:.2f} |")
        print("\n| robot | lsdc / Pinocchio, ∂RNEA | lsdc / Pinocchio, ∂ABA |")
        print("|---|---:|---:|")
        for d in derivatives:
            print(f"| {d['robot']} | {d['rnea_derivatives_ratio'][0]:.2f} / "
                  f"{d['rnea_derivatives_ratio'][1]:.2f} | {d['aba_derivatives_ratio'][0]:.2f} / "
                  f"{d['aba_derivatives_ratio'][1]:.2f} |")
    if args.json:
        pathlib.Path(args.json).write_text(json.dumps({
            "date": started.isoformat(), "load_before": load_before, "load_after": load_after,
            "pinocchio": pin and sys.modules['pinocchio'].__version__, "mujoco": mujoco and mujoco.__version__,
            "rounds": args.rounds, "batch": args.batch, "rows": rows,
            "derivatives": derivatives}, indent=1) + "\n")


if __name__ == "__main__":
    main()
