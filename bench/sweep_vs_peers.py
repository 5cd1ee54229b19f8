#!/usr/bin/env python3
"""1,000 runs of the double pendulum (examples/double_pendulum.lsd, 5 s each), the shoulder's
initial angle on a grid from 1 to 2 rad, by four means, at equal error, CPU time side by side:

  lsdc sweep             one process, the equations evaluated by the simulator (`-j 1`);
  lsdc sweep --compiled  the same with the generated C forward dynamics (`-j 1`);
  generated C + driver   lsdc's generated C (`lsdc compile --emit c`) under a hand-written
                         Dormand–Prince 5(4) driver (bench/peers/dopri5_driver.c, cc -O2), no
                         samples, no dense output: the floor of what native code can do;
  MuJoCo                 the same two rods (mass, centre of mass, inertia) as an MJCF model, its
                         RK4 integrator at the largest step (from 32 ms, by factors 2^(1/4)) whose median
                         error is at most lsdc's, `mj_step(nstep=...)` per run from Python.

The driver runs at the largest tolerance (from lsdc's, by factors 2^(1/4)) whose median error is at most
lsdc's, so that all four are compared at equal median error.

Error of a run: the largest difference of its end state (angles and rates) from a reference
(lsdc sweep with DOP853 at 1e-14); per means the median and the largest over the runs. CPU:
lsdc's from its summary (`cpu_seconds`, the process's CPU over the runs, one worker thread);
the driver's and MuJoCo's by their thread's CPU clock around the runs. Rounds alternate the
means' order; best and median of the rounds.

Usage: python3 bench/sweep_vs_peers.py [--lsdc target/release/lsdc] [--rounds 3] [--tolerance 1e-8]
Needs `pip install mujoco numpy` and a C compiler.
"""

import argparse
import json
import pathlib
import statistics
import subprocess
import sys
import time

REPO = pathlib.Path(__file__).resolve().parent.parent
OUT = REPO / "target" / "sweep_vs_peers"
PROGRAM = REPO / "examples" / "double_pendulum.lsd"
RUNS, FROM, TO, DURATION = 1000, 1.0, 2.0, 5.0
# The program's other initial values: elbow.q, shoulder.q', elbow.q'.
REST = (-1.0, 0.5, 1.0)

MJCF = """<mujoco>
  <option gravity="0 0 -9.81" integrator="RK4" timestep="{dt!r}"/>
  <worldbody>
    <body name="upper">
      <joint name="shoulder" type="hinge" axis="1 0 0"/>
      <inertial pos="0 0 -0.5" mass="1" diaginertia="{i1!r} {i1!r} 1e-12"/>
      <body name="lower" pos="0 0 -1">
        <joint name="elbow" type="hinge" axis="1 0 0"/>
        <inertial pos="0 0 -0.4" mass="0.8" diaginertia="{i2!r} {i2!r} 1e-12"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def sweep(lsdc, extra, tolerance, integrator="dopri5"):
    """The runs' end states and the sweep's CPU seconds."""
    command = [lsdc, "sweep", str(PROGRAM), "--grid", f"shoulder.q={FROM}:{TO}:{RUNS}",
               "--duration", str(DURATION), "--tolerance", repr(tolerance), "--integrator",
               integrator, "--every", str(DURATION), "-j", "1", "--report", "json", *extra]
    done = subprocess.run(command, capture_output=True, text=True, check=True)
    summary = json.loads(done.stderr[done.stderr.index("{"):])
    lines = done.stdout.splitlines()
    header = lines[0].split(",")
    columns = [header.index(f"end({n})") for n in
               ("shoulder.q", "elbow.q", "shoulder.q'", "elbow.q'")]
    ends = [[float(row.split(",")[c]) for c in columns] for row in lines[1:]]
    assert summary["ok"] == RUNS, summary
    return ends, summary["cpu_seconds"], summary.get("warnings")


def driver(binary, tolerance):
    done = subprocess.run([str(binary), str(RUNS), str(FROM), str(TO), str(DURATION),
                           repr(tolerance), *map(repr, REST)],
                          capture_output=True, text=True, check=True)
    ends = [[float(x) for x in line.split(",")] for line in done.stdout.splitlines()]
    return ends, float(done.stderr.split()[1])


def mujoco_runs(mujoco, dt):
    model = mujoco.MjModel.from_xml_string(MJCF.format(dt=dt, i1=1 / 12, i2=0.8 * 0.8 ** 2 / 12))
    data = mujoco.MjData(model)
    steps = round(DURATION / dt)
    ends = []
    started = time.thread_time()
    for r in range(RUNS):
        mujoco.mj_resetData(model, data)
        data.qpos[:] = (FROM + (TO - FROM) * r / (RUNS - 1) if r < RUNS - 1 else TO, REST[0])
        data.qvel[:] = REST[1:]
        mujoco.mj_step(model, data, nstep=steps)
        ends.append([*data.qpos, *data.qvel])
    return ends, time.thread_time() - started


def errors(ends, reference):
    per_run = [max(abs(a - b) for a, b in zip(e, r)) for e, r in zip(ends, reference)]
    return statistics.median(per_run), max(per_run)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--lsdc", default=str(REPO / "target" / "release" / "lsdc"))
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--tolerance", type=float, default=1e-8)
    args = parser.parse_args()
    import mujoco

    OUT.mkdir(parents=True, exist_ok=True)
    generated = OUT / "double_pendulum.c"
    generated.write_text(subprocess.run([args.lsdc, "compile", "--emit", "c", str(PROGRAM)],
                                        capture_output=True, text=True, check=True).stdout)
    binary = OUT / "dopri5_driver"
    subprocess.run(["cc", "-O2", f'-DMODEL="{generated}"',
                    str(REPO / "bench" / "peers" / "dopri5_driver.c"), "-o", str(binary), "-lm"],
                   check=True)

    reference, _, _ = sweep(args.lsdc, [], 1e-14, "dop853")
    ends, _, _ = sweep(args.lsdc, [], args.tolerance)
    target_median, target_max = errors(ends, reference)
    # The peers at the error lsdc reaches: MuJoCo's largest step (from 32 ms, divided by the
    # fourth root of 2 each time), the driver's largest tolerance (from lsdc's, likewise),
    # whose median error is at most lsdc's.
    dt = 0.032
    while True:
        median, largest = errors(mujoco_runs(mujoco, dt)[0], reference)
        if median <= target_median or dt < 1e-6:
            break
        dt /= 2 ** 0.25
    c_tolerance = args.tolerance
    while True:
        c_median, c_largest = errors(driver(binary, c_tolerance)[0], reference)
        if c_median <= target_median or c_tolerance < 1e-15:
            break
        c_tolerance /= 2 ** 0.25
    print(f"lsdc dopri5 at {args.tolerance:g}: median error {target_median:.2e}, largest "
          f"{target_max:.2e}; MuJoCo RK4 at dt = {dt:g} s: median {median:.2e}, largest "
          f"{largest:.2e}; the driver at {c_tolerance:g}: median {c_median:.2e}, largest "
          f"{c_largest:.2e}", flush=True)

    means = {
        "lsdc sweep": lambda: sweep(args.lsdc, [], args.tolerance)[:2],
        "lsdc sweep --compiled": lambda: sweep(args.lsdc, ["--compiled"], args.tolerance)[:2],
        f"generated C + driver {c_tolerance:.3g}": lambda: driver(binary, c_tolerance),
        f"MuJoCo RK4 {dt:.3g}": lambda: mujoco_runs(mujoco, dt),
    }
    times = {name: [] for name in means}
    errs = {}
    names = list(means)
    for round_ in range(args.rounds):
        order = names if round_ % 2 == 0 else names[::-1]
        for name in order:
            ends, cpu = means[name]()
            times[name].append(cpu)
            errs[name] = errors(ends, reference)
    mujoco_best = min(times[names[3]])
    mujoco_median = statistics.median(times[names[3]])
    c_best = min(times[names[2]])
    c_median = statistics.median(times[names[2]])
    print("| means | CPU s best | median | median error | largest error | / MuJoCo (best, median) | / C + driver (best, median) |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for name in names:
        best, median = min(times[name]), statistics.median(times[name])
        print(f"| {name} | {best:.3f} | {median:.3f} | {errs[name][0]:.1e} | {errs[name][1]:.1e} "
              f"| {best / mujoco_best:.3f}, {median / mujoco_median:.3f} "
              f"| {best / c_best:.2f}, {median / c_median:.2f} |")


if __name__ == "__main__":
    sys.exit(main())
