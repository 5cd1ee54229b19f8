"""RNEA, CRBA, ABA and Jacobians on NumPy arrays: against `lsdc eval` (the acceptance: to
1e-15), against the double pendulum's closed-form equations (Lagrange's, written out by hand),
and against each other (ABA inverts RNEA; RNEA is linear in a with the mass matrix)."""

import json
import math

import numpy as np
import pytest

import lsdc

# examples/double_pendulum.lsd: two uniform rods about x; masses, lengths, centres, inertias.
M1, M2, L1, L2, G = 1.0, 0.8, 1.0, 0.8, 9.81
C1, C2 = L1 / 2, L2 / 2
I1, I2 = M1 * L1**2 / 12, M2 * L2**2 / 12


def closed_form(q, v, a):
    """Mass matrix, Coriolis and gravity of the double pendulum (q2 relative to the upper
    rod, angles from hanging down about +x): τ = M a + c − g."""
    q1, q2 = q
    m11 = I1 + M1 * C1**2 + I2 + M2 * (L1**2 + C2**2 + 2 * L1 * C2 * math.cos(q2))
    m12 = I2 + M2 * (C2**2 + L1 * C2 * math.cos(q2))
    m22 = I2 + M2 * C2**2
    mass = np.array([[m11, m12], [m12, m22]])
    h = M2 * L1 * C2 * math.sin(q2)
    coriolis = np.array([-h * (2 * v[0] * v[1] + v[1] ** 2), h * v[0] ** 2])
    gravity = -G * np.array(
        [M1 * C1 * math.sin(q1) + M2 * (L1 * math.sin(q1) + C2 * math.sin(q1 + q2)),
         M2 * C2 * math.sin(q1 + q2)]
    )
    return mass, mass @ a + coriolis - gravity


@pytest.fixture(scope="module")
def arm(example):
    return lsdc.load(example("double_pendulum.lsd")).prepare()


@pytest.fixture(scope="module")
def states():
    generator = np.random.default_rng(52)
    count = 64
    return (generator.uniform(-math.pi, math.pi, (count, 2)),
            generator.uniform(-3, 3, (count, 2)),
            generator.uniform(-5, 5, (count, 2)),
            generator.uniform(-10, 10, (count, 2)))


def test_names_and_shapes(arm, states):
    q, v, a, tau = states
    assert arm.position_names == ["shoulder.q", "elbow.q"]
    assert arm.velocity_names == ["shoulder.q", "elbow.q"]
    assert (arm.nq, arm.nv) == (2, 2)
    assert arm.rnea(q, v, a).shape == (64, 2)
    assert arm.aba(q, v, tau).shape == (64, 2)
    assert arm.crba(q).shape == (64, 2, 2)
    assert arm.jacobian(q, "lower").shape == (64, 6, 2)
    # One state as 1-D arrays gives 1-D results, equal to the batch's row.
    assert np.array_equal(arm.aba(q[3], v[3], tau[3]), arm.aba(q, v, tau)[3])
    assert arm.crba(q[3]).shape == (2, 2)


def test_equal_to_lsdc_eval(arm, states, example, run_cli, tmp_path):
    # The states as Python writes them (shortest round-trip form): `lsdc eval` reads them back
    # to the bit (serde_json with `float_roundtrip`).
    q, v, a, tau = states
    rows = [{"q": list(q[k]), "v": list(v[k]), "a": list(a[k]), "tau": list(tau[k])}
            for k in range(len(q))]
    path = tmp_path / "states.json"
    path.write_text(json.dumps({"states": rows}))
    evaluated = json.loads(run_cli("eval", example("double_pendulum.lsd"), "--states", path))
    expected = {key: np.array([s[key] for s in evaluated["states"]]) for key in ("rnea", "crba", "aba")}
    found = {"rnea": arm.rnea(q, v, a), "crba": arm.crba(q), "aba": arm.aba(q, v, tau)}
    # Issue #52's criterion: to 1e-15. Measured: identical, bit for bit.
    for key in found:
        worst = np.max(np.abs(found[key] - expected[key]))
        assert worst <= 1e-15, f"{key}: {worst}"


def test_closed_form(arm, states):
    q, v, a, _ = states
    tau, mass = arm.rnea(q, v, a), arm.crba(q)
    for k in range(len(q)):
        expected_mass, expected_tau = closed_form(q[k], v[k], a[k])
        np.testing.assert_allclose(mass[k], expected_mass, rtol=0, atol=1e-12)
        np.testing.assert_allclose(tau[k], expected_tau, rtol=0, atol=1e-11)


def test_algorithms_agree(arm, states):
    q, v, a, _ = states
    tau = arm.rnea(q, v, a)
    # ABA inverts RNEA, and RNEA(q, v, a) − RNEA(q, v, 0) = M(q) a.
    np.testing.assert_allclose(arm.aba(q, v, tau), a, rtol=0, atol=1e-11)
    bias = arm.rnea(q, v, np.zeros_like(a))
    np.testing.assert_allclose(tau - bias, np.einsum("nij,nj->ni", arm.crba(q), a), atol=1e-12)


def test_jacobian_closed_form(arm, states):
    q = states[0]
    upper, lower = arm.jacobian(q, "upper"), arm.jacobian(q, "lower")
    for k in range(len(q)):
        q2 = q[k][1]
        # The upper rod's origin is on the shoulder's axis; the lower's, the elbow, moves
        # with the shoulder at l1 (cos q2, −sin q2) in the lower rod's (y, z) axes.
        expected_upper = np.zeros((6, 2))
        expected_upper[0, 0] = 1
        expected_lower = np.zeros((6, 2))
        expected_lower[0] = [1, 1]
        expected_lower[4, 0] = L1 * math.cos(q2)
        expected_lower[5, 0] = -L1 * math.sin(q2)
        np.testing.assert_allclose(upper[k], expected_upper, atol=1e-14)
        np.testing.assert_allclose(lower[k], expected_lower, atol=1e-14)


def test_bad_arrays(arm, states):
    q, v, _, tau = states
    with pytest.raises(ValueError, match="`q` has 3 columns, the mechanism has 2"):
        arm.aba(np.zeros((4, 3)))
    with pytest.raises(ValueError, match="`tau` has 5 states, `q` has 64"):
        arm.aba(q, v, tau[:5])
    bad = q.copy()
    bad[7, 1] = np.nan
    with pytest.raises(ValueError, match=r"state 7: `q\[1\]` is not a finite number"):
        arm.crba(bad)
    with pytest.raises(ValueError, match="no body `elbow`"):
        arm.jacobian(q, "elbow")
