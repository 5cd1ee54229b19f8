"""FMI units of `lsdc export-fmu` checked with FMPy (tools/fmi-tests runs this).

1. Each unit validates (FMPy's validation: the model description against the standard's
   schema, and its consistency) in FMI 3.0 and 2.0.
2. FMPy's simulations of the pendulum, the four-bar and the Delta (examples/) agree with
   `lsdc simulate` at every output time.
3. Model exchange: FMPy's CVode integrates the units of two trees (the pendulum and the double
   pendulum, FMI 3.0 and 2.0) at a tight relative tolerance, and agrees with `lsdc simulate`;
   the derivatives a unit returns at chosen states, an input set, are `lsdc eval`'s forward
   dynamics (ABA) to round-off; a mechanism with loops is refused for model exchange with a
   message that suggests co-simulation, and its unit says it is co-simulation only.
4. A PD controller written here drives the pendulum's unit through its input, sampled at each
   communication step h and held over it; the final angle approaches the same PD law written
   in LSD (tools/fmi/pd_pendulum.lsd) at the order of a zero-order hold, h¹; and at h = 0.01
   it is the discrete PD of examples/control/discrete_pd_pendulum.lsd (sampled in LSD at the
   same instants) to round-off.
5. A value input (`input voltage = 12;`, examples/control/dc_motor.lsd): the unit lists
   `voltage` as an input with its start value (and not among its outputs) in FMI 3.0 and 2.0
   and validates; a speed loop written here sets the voltage at each communication step h and
   holds it, and the final speed approaches the same law written in LSD at order h¹; at
   h = 0.01 it is the law sampled in LSD (`sample`, `update`) to round-off.

Usage: python check_units.py LSDC_BINARY WORK_DIRECTORY
"""

import csv
import io
import json
import math
import os
import shutil
import subprocess
import sys
from ctypes import POINTER, c_double

import numpy as np
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Model
from fmpy.fmi3 import FMU3Model, FMU3Slave
from fmpy.validation import validate_fmu

LSDC, WORK = sys.argv[1], sys.argv[2]
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
failures = []


def check(condition, message):
    print(("ok      " if condition else "FAILED  ") + message)
    if not condition:
        failures.append(message)


def lsdc(*arguments):
    done = subprocess.run([LSDC, *arguments], cwd=ROOT, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"lsdc {' '.join(arguments)} failed:\n{done.stderr}")
    return done.stdout


def export(program, name, *options):
    path = os.path.join(WORK, name)
    lsdc("export-fmu", program, "-o", path, *options)
    return path


def simulated(program, duration):
    """`lsdc simulate`'s CSV as a dict of columns."""
    text = lsdc("simulate", program, "--duration", str(duration))
    rows = list(csv.reader(io.StringIO(text)))
    header, rows = rows[0], [r for r in rows[1:] if r and not r[0].startswith("#")]
    return {name: np.array([float(r[k]) if r[k] else math.nan for r in rows])
            for k, name in enumerate(header)}


# 1-2: validation, and FMPy's simulations against `lsdc simulate`.
cases = [
    ("examples/pendulum.lsd", 5.0, 1e-8),
    ("examples/four_bar.lsd", 2.0, 1e-8),
    ("examples/delta_isir88.lsd", 1.0, 1e-7),
]
for program, duration, tolerance in cases:
    stem = os.path.splitext(os.path.basename(program))[0]
    reference = simulated(program, duration)
    coordinates = [n for n in reference if n not in ("time", "kinetic_energy", "potential_energy")]
    for version in ("3", "2"):
        unit = export(program, f"{stem}-fmi{version}.fmu", "--fmi", version)
        problems = validate_fmu(unit)
        check(not problems, f"{stem} (FMI {version}.0) validates: {problems or 'no problem'}")
        description = read_model_description(unit, validate=True)
        names = [v.name for v in description.modelVariables]
        check(all(n in names for n in coordinates),
              f"{stem} (FMI {version}.0) has the outputs {', '.join(coordinates[:4])}…")
        result = simulate_fmu(unit, stop_time=duration, output_interval=0.05,
                              output=coordinates + ["kinetic_energy"])
        times = reference["time"]
        check(len(result) == len(times) and np.allclose(result["time"], times, atol=1e-12, rtol=0),
              f"{stem} (FMI {version}.0): FMPy's {len(result)} output times are lsdc's {len(times)}")
        worst = max(np.max(np.abs(result[n] - reference[n])) for n in coordinates)
        check(worst <= tolerance,
              f"{stem} (FMI {version}.0): coordinates and rates within {tolerance:g} of `lsdc simulate` "
              f"over {duration} s (largest difference {worst:.2e})")

# 3: model exchange.
me_cases = [
    ("examples/pendulum.lsd", 5.0, 1e-8),
    ("examples/double_pendulum.lsd", 2.0, 1e-8),
]
for program, duration, tolerance in me_cases:
    stem = os.path.splitext(os.path.basename(program))[0]
    reference = simulated(program, duration)
    coordinates = [n for n in reference if n not in ("time", "kinetic_energy", "potential_energy")]
    for version in ("3", "2"):
        unit = export(program, f"{stem}-me-fmi{version}.fmu", "--fmi", version,
                      "--kind", "model-exchange")
        problems = validate_fmu(unit)
        check(not problems, f"{stem} (FMI {version}.0 model exchange) validates: {problems or 'no problem'}")
        description = read_model_description(unit, validate=True)
        check(description.modelExchange is not None and description.coSimulation is None,
              f"{stem} (FMI {version}.0): the unit is for model exchange only, as asked")
        interval = reference["time"][1] - reference["time"][0]
        result = simulate_fmu(unit, fmi_type="ModelExchange", solver="CVode",
                              relative_tolerance=1e-12, stop_time=duration, output_interval=interval,
                              output=coordinates + ["kinetic_energy"])
        times = reference["time"]
        check(len(result) == len(times) and np.allclose(result["time"], times, atol=1e-12, rtol=0),
              f"{stem} (FMI {version}.0 ME): FMPy's {len(result)} output times are lsdc's {len(times)}")
        worst = max(np.max(np.abs(result[n] - reference[n])) for n in coordinates)
        check(worst <= tolerance,
              f"{stem} (FMI {version}.0 ME): CVode at rtol 1e-12 within {tolerance:g} of `lsdc simulate` "
              f"over {duration} s (largest difference {worst:.2e})")

# The derivatives at chosen states, an effort along the first coordinate set, against `lsdc eval`.
program = "examples/double_pendulum.lsd"
states = [([0.3, -1.2], [0.7, 2.5], 1.5), ([2.0, 0.1], [-3.0, 0.4], -0.8)]
states_file = os.path.join(WORK, "states.json")
with open(states_file, "w") as f:
    json.dump([{"q": q, "v": v, "tau": [u, 0.0]} for q, v, u in states], f)
evaluated = json.loads(lsdc("eval", program, "--states", states_file))
for version in ("3", "2"):
    unit = export(program, f"double_pendulum-input-fmi{version}.fmu", "--fmi", version,
                  "--input", "shoulder.q")
    description = read_model_description(unit, validate=True)
    reference_of = {v.name: v.valueReference for v in description.modelVariables}
    unzipped = extract(unit)
    if version == "3":
        model = FMU3Model(guid=description.instantiationToken, unzipDirectory=unzipped,
                          modelIdentifier=description.modelExchange.modelIdentifier)
        model.instantiate()
        model.enterInitializationMode()
        model.exitInitializationMode()
        model.enterContinuousTimeMode()
        set_inputs, get_values = model.setFloat64, model.getFloat64
    else:
        model = FMU2Model(guid=description.guid, unzipDirectory=unzipped,
                          modelIdentifier=description.modelExchange.modelIdentifier)
        model.instantiate()
        model.setupExperiment(startTime=0.0)
        model.enterInitializationMode()
        model.exitInitializationMode()
        model.enterContinuousTimeMode()
        set_inputs, get_values = model.setReal, model.getReal
    names = evaluated["positions"]
    order = [["shoulder.q", "elbow.q"].index(n) for n in names]
    worst = 0.0
    for (q, v, u), output in zip(states, evaluated["states"]):
        model.setTime(0.0)
        set_inputs([reference_of["shoulder.q.effort"]], [u])
        state, derivatives = np.array(q + v, dtype=float), np.zeros(4)
        model.setContinuousStates(state.ctypes.data_as(POINTER(c_double)), 4)
        pointer = derivatives.ctypes.data_as(POINTER(c_double))
        if version == "2":
            model.getDerivatives(pointer, 4)
        else:
            model.getContinuousStateDerivatives(pointer, 4)
        accelerations = [derivatives[2 + order[k]] for k in range(2)]
        worst = max(worst, np.max(np.abs(derivatives[:2] - np.array(v))),
                    np.max(np.abs(np.array(accelerations) - np.array(output["aba"]))))
        read = get_values([reference_of["shoulder.q''"], reference_of["elbow.q''"]])
        worst = max(worst, np.max(np.abs(np.array(read) - derivatives[2:])))
    model.terminate()
    model.freeInstance()
    shutil.rmtree(unzipped, ignore_errors=True)
    check(worst <= 1e-13,
          f"double pendulum (FMI {version}.0 ME): the unit's derivatives are `lsdc eval`'s ABA "
          f"with the input's effort (largest difference {worst:.1e})")

# A mechanism with loops: co-simulation only, and model exchange refused with the reason.
refused = subprocess.run([LSDC, "export-fmu", "examples/four_bar.lsd", "--kind", "model-exchange",
                          "-o", os.path.join(WORK, "refused.fmu")],
                         cwd=ROOT, capture_output=True, text=True)
check(refused.returncode == 2 and "closed loops" in refused.stderr
      and "--kind co-simulation" in refused.stderr,
      f"the four-bar is refused for model exchange: {refused.stderr.strip()}")
description = read_model_description(os.path.join(WORK, "four_bar-fmi3.fmu"), validate=True)
check(description.modelExchange is None and "co-simulation only" in description.description,
      "the four-bar's default unit is for co-simulation only, and says why")

# 4: the PD loop closed in Python through the unit's input.
K_P, K_D, Q_REF, T = 20.0, 2.0, 0.5, 2.0
plant = export("examples/pendulum.lsd", "pendulum_plant.fmu", "--input", "swing.q")
description = read_model_description(plant, validate=True)
reference_of = {v.name: v.valueReference for v in description.modelVariables}
q, rate, effort = reference_of["swing.q"], reference_of["swing.q'"], reference_of["swing.q.effort"]
unzipped = extract(plant)


def pd_loop(h, first_instant=0):
    """The angle at T with the PD law sampled every h and held over the step, from step
    `first_instant` on (0 before it)."""
    unit = FMU3Slave(guid=description.instantiationToken, unzipDirectory=unzipped,
                     modelIdentifier=description.coSimulation.modelIdentifier)
    unit.instantiate()
    unit.enterInitializationMode(startTime=0.0, stopTime=T)
    unit.exitInitializationMode()
    steps = round(T / h)
    for k in range(steps):
        angle, angle_rate = unit.getFloat64([q, rate])
        if k >= first_instant:
            unit.setFloat64([effort], [K_P * (Q_REF - angle) - K_D * angle_rate])
        unit.doStep(currentCommunicationPoint=k * h, communicationStepSize=h)
    (angle,) = unit.getFloat64([q])
    unit.terminate()
    unit.freeInstance()
    return angle


continuous = simulated("tools/fmi/pd_pendulum.lsd", T)["swing.q"][-1]
steps = [0.02, 0.01, 0.005, 0.0025]
errors = [abs(pd_loop(h) - continuous) for h in steps]
for h, e in zip(steps, errors):
    print(f"        h = {h:<7g} |q(T) - q_LSD(T)| = {e:.3e}")
ratios = [a / b for a, b in zip(errors, errors[1:])]
orders = [math.log2(r) for r in ratios]
check(all(0.85 <= p <= 1.15 for p in orders),
      f"the sampled PD approaches the continuous law at order 1 in h (observed {', '.join(f'{p:.3f}' for p in orders)})")
discrete = simulated("examples/control/discrete_pd_pendulum.lsd", T)
# `sample(h, u0)` holds u0 = 0 until its first instant, t = h: the loop's first command too.
sampled = pd_loop(0.01, first_instant=1)
check(abs(sampled - discrete["swing.q"][-1]) <= 1e-12,
      f"at h = 0.01 the loop is the discrete PD written in LSD to {abs(sampled - discrete['swing.q'][-1]):.1e}")

shutil.rmtree(unzipped, ignore_errors=True)

# 5: a value input, the DC motor's voltage, set by a speed loop written here.
with open(os.path.join(ROOT, "examples/control/dc_motor.lsd")) as f:
    MOTOR = f.read()
MOTOR_SETTINGS = "simulate duration = 10, output = 0.01, integrator = implicit, tolerance = 1e-10 end ;"
K_S, W_REF, T_MOTOR = 1.0, 5.0, 1.0  # V s/rad, rad/s, s


def motor_variant(name, voltage):
    """The example with its voltage declared as `voltage` (after the join: a law may read its
    rate) and Dormand-Prince's settings."""
    text = MOTOR.replace("input voltage = 12 ; (* U, V *)\n", "").replace(
        "rate current =", voltage + "\nrate current =").replace(
        MOTOR_SETTINGS, "simulate duration = 1, output = 0.01, integrator = dopri5, tolerance = 1e-10 end ;")
    path = os.path.join(WORK, name)
    with open(path, "w") as f:
        f.write(text)
    return path


motor_plant = motor_variant("dc_motor_plant.lsd", "input voltage = 12 ; (* U, V *)")
for version in ("3", "2"):
    unit = export(motor_plant, f"dc_motor-fmi{version}.fmu", "--fmi", version)
    problems = validate_fmu(unit)
    check(not problems, f"dc_motor FMI {version}.0 validates" + (f": {problems}" if problems else ""))
    variables = read_model_description(unit).modelVariables
    voltage = [v for v in variables if v.name == "voltage"]
    check(len(voltage) == 1 and voltage[0].causality == "input" and float(voltage[0].start) == 12.0,
          f"dc_motor FMI {version}.0 lists `voltage` once, an input starting at 12")
motor_unit = os.path.join(WORK, "dc_motor-fmi3.fmu")
motor_description = read_model_description(motor_unit)
motor_reference = {v.name: v.valueReference for v in motor_description.modelVariables}
speed, volts = motor_reference["shoulder.q'"], motor_reference["voltage"]
motor_unzipped = extract(motor_unit)


def speed_loop(h, first_instant=0):
    """The arm's speed at T_MOTOR with the voltage K_S (W_REF - speed) set every h and held,
    from step `first_instant` on (the declared 12 V before it)."""
    unit = FMU3Slave(guid=motor_description.instantiationToken, unzipDirectory=motor_unzipped,
                     modelIdentifier=motor_description.coSimulation.modelIdentifier)
    unit.instantiate()
    unit.enterInitializationMode(startTime=0.0, stopTime=T_MOTOR)
    unit.exitInitializationMode()
    for k in range(round(T_MOTOR / h)):
        (arm_speed,) = unit.getFloat64([speed])
        if k >= first_instant:
            unit.setFloat64([volts], [K_S * (W_REF - arm_speed)])
        unit.doStep(currentCommunicationPoint=k * h, communicationStepSize=h)
    (arm_speed,) = unit.getFloat64([speed])
    unit.terminate()
    unit.freeInstance()
    return arm_speed


law = f"let voltage = {K_S} * ({W_REF} - shoulder.q') ;"
continuous = simulated(motor_variant("dc_motor_law.lsd", law), T_MOTOR)["shoulder.q'"][-1]
errors = [abs(speed_loop(h) - continuous) for h in steps]
for h, e in zip(steps, errors):
    print(f"        h = {h:<7g} |w(T) - w_LSD(T)| = {e:.3e}")
orders = [math.log2(a / b) for a, b in zip(errors, errors[1:])]
check(all(0.85 <= p <= 1.15 for p in orders),
      f"the voltage set every h approaches the law in LSD at order 1 in h (observed {', '.join(f'{p:.3f}' for p in orders)})")
sampled_law = ("let voltage = sample(0.01, 12) ; "
               f"update voltage = {K_S} * ({W_REF} - shoulder.q') ;")
discrete = simulated(motor_variant("dc_motor_sampled.lsd", sampled_law), T_MOTOR)["shoulder.q'"][-1]
difference = abs(speed_loop(0.01, first_instant=1) - discrete)
check(difference <= 1e-12 * max(1.0, abs(discrete)),
      f"at h = 0.01 the voltage set from Python is the law sampled in LSD to {difference:.1e}")
shutil.rmtree(motor_unzipped, ignore_errors=True)

if failures:
    sys.exit(f"{len(failures)} check(s) failed")
print("all FMI checks passed")
