"""Whole runs against `lsdc simulate`'s CSV (bit for bit), runs stepped from Python against
the balance of a sampled PD law (solved by Newton's method), and the columns in pandas."""

import csv
import io
import math

import numpy as np
import pytest

import lsdc


def read_csv(text):
    """The CSV of `lsdc simulate` as columns of floats (an empty field is NaN)."""
    rows = [row for row in csv.reader(io.StringIO(text)) if row and not row[0].startswith("#")]
    header, body = rows[0], rows[1:]
    return {name: np.array([float(row[k]) if row[k] else math.nan for row in body])
            for k, name in enumerate(header)}


@pytest.mark.parametrize("name", ["pendulum.lsd", "four_bar.lsd", "double_pendulum.lsd"])
def test_equal_to_the_csv(name, example, run_cli):
    expected = read_csv(run_cli("simulate", example(name), "--duration", 2, "--every", 0.5))
    found = lsdc.load(example(name)).simulate(duration=2.0, every=0.5)
    assert list(found) == list(expected)
    for column, values in expected.items():
        assert found[column].dtype == np.float64
        # The same numbers, bit for bit: equal, NaN where the CSV is empty, signs of zeros too.
        assert np.array_equal(found[column], values, equal_nan=True), column
        assert np.array_equal(np.signbit(found[column]), np.signbit(values)), column
    assert found.report["failure"] is None
    assert found["time"][-1] == 2.0 and len(found["time"]) == 5


def test_values_and_initial(example):
    # Initial values by name: the run starts from them.
    program = lsdc.load(example("pendulum.lsd"))
    found = program.simulate(initial={"swing.q": 0.3, "swing.q'": 1.0}, duration=1.0, every=0.25)
    assert found["swing.q"][0] == 0.3 and found["swing.q'"][0] == 1.0
    with pytest.raises(lsdc.LsdcError, match="did you mean `swing.q`"):
        program.prepare(initial={"swing.p": 0.3})


def test_to_pandas(example):
    pandas = pytest.importorskip("pandas")
    columns = lsdc.load(example("pendulum.lsd")).simulate(duration=1.0, every=0.5)
    frame = columns.to_pandas()
    assert isinstance(frame, pandas.DataFrame)
    assert list(frame.columns) == list(columns)
    assert np.array_equal(frame["swing.q"].to_numpy(), columns["swing.q"])


KP, KD, TARGET, PERIOD = 20.0, 3.0, 0.5, 0.01
GRAVITY_MOMENT = 1.2 * 9.81 * 0.5  # examples/pendulum.lsd: m g l


def balanced_angle():
    """Where kp (target − q) = m g l sin q, by Newton's method from the target."""
    q = TARGET
    for _ in range(50):
        q += (KP * (TARGET - q) - GRAVITY_MOMENT * math.sin(q)) / (KP + GRAVITY_MOMENT * math.cos(q))
    return q


def test_sampled_pd_settles_at_the_balance(example):
    prepared = lsdc.load(example("pendulum.lsd")).prepare(duration=10.0)
    simulation = prepared.simulation(["swing.q"])
    assert simulation.input_names == ["swing.q"]
    for k in range(1, 1001):
        (q,), (v,) = simulation.coordinates()
        simulation.set_inputs([-KP * (q - TARGET) - KD * v])
        simulation.advance_to(k * PERIOD)
    (q,), (v,) = simulation.coordinates()
    assert simulation.time == 10.0
    assert abs(q - balanced_angle()) < 1e-9 and abs(v) < 1e-9
    samples = simulation.take_samples()
    assert samples["time"][0] == 0.0 and len(samples["time"]) > 100
    # Back to the start with the held torque kept: the same loop, the same motion.
    simulation.reset()
    assert simulation.time == 0.0
    for k in range(1, 1001):
        (q2,), (v2,) = simulation.coordinates()
        simulation.set_inputs([-KP * (q2 - TARGET) - KD * v2])
        simulation.advance_to(k * PERIOD)
    assert simulation.coordinates()[0][0] == q
    final = simulation.finish()
    assert final.report["failure"] is None
    with pytest.raises(lsdc.LsdcError, match="finished"):
        simulation.step()


def test_stepping_errors(example):
    simulation = lsdc.load(example("pendulum.lsd")).prepare(duration=0.1).simulation(["swing.q"])
    with pytest.raises(lsdc.RunError, match="2 input efforts given for 1 inputs"):
        simulation.set_inputs([1.0, 2.0])
    with pytest.raises(lsdc.RunError):
        lsdc.load(example("pendulum.lsd")).prepare().simulation(["swing.x"])
    simulation.advance_to(0.1)
    with pytest.raises(lsdc.RunError, match="end of its duration"):
        simulation.step()


def test_value_input_set_between_steps(example):
    # examples/control/dc_motor.lsd: `input voltage = 12;`, read by its current's rate.
    program = lsdc.load(example("control/dc_motor.lsd"))
    settings = dict(duration=0.2, integrator="rk4", step=1e-4)
    simulation = program.prepare(**settings).simulation()
    assert simulation.value_input_names == ["voltage"]
    assert simulation.input_names == []
    # Held at its start value, 12 V, until set: the run equals the whole run at 12 V.
    simulation.advance_to(0.1)
    whole = program.prepare(**settings).simulation()
    whole.advance_to(0.1)
    assert simulation.coordinates()[1][0] == whole.coordinates()[1][0]
    # Set to 0 V at 0.1 s: held from there on, and the motor brakes.
    (_,), (v,) = simulation.coordinates()
    simulation.set_input("voltage", 0.0)
    simulation.advance_to(0.2)
    samples = simulation.take_samples()
    assert np.all(samples["voltage"][samples["time"] > 0.1] == 0.0)
    assert simulation.coordinates()[1][0] < v
    with pytest.raises(lsdc.RunError, match="no input `volts`: the run.s inputs are voltage"):
        simulation.set_input("volts", 1.0)


def test_value_input_equals_its_start_value_given(example):
    # Set at the start, or given as a value (`--set voltage=6`): the same run.
    program = lsdc.load(example("control/dc_motor.lsd"))
    settings = dict(duration=0.05, integrator="rk4", step=1e-4)
    stepped = program.prepare(**settings).simulation()
    stepped.set_input("voltage", 6.0)
    stepped.advance_to(0.05)
    given = program.prepare({"voltage": 6.0}, **settings).simulation()
    given.advance_to(0.05)
    assert stepped.coordinates()[1][0] == given.coordinates()[1][0]
