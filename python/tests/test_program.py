"""Loading, checking and preparing: diagnostics as objects with their place, errors raised
with them; the linear model against the pendulum's closed form."""

import math

import numpy as np
import pytest

import lsdc


def test_diagnostics_have_their_place():
    program = lsdc.load_text("let b = body mass = 1 end;\njoin earth and c with 1;", name="typo.lsd")
    assert program.has_errors
    errors = [d for d in program.diagnostics if d.is_error]
    assert errors, program.render()
    first = errors[0]
    assert (first.file, first.line) == ("typo.lsd", 2)
    assert first.column == 16 and "unknown name `c`" in first.message
    assert first.code.startswith("E") and first.severity == "error"
    assert str(first).startswith("typo.lsd:2:16: error[")
    with pytest.raises(lsdc.ProgramError) as raised:
        program.prepare()
    message, diagnostics = raised.value.args
    assert "typo.lsd:2:16" in message and diagnostics[0].line == 2
    with pytest.raises(lsdc.ProgramError):
        program.check()


def test_check_and_missing_values(example, tmp_path):
    assert [d for d in lsdc.check(example("pendulum.lsd")) if d.is_error] == []
    text = ("import joints; let k = ?s; let b = body mass = 1, iframe = 0, inertia = [1, 1, 1] end;\n"
            "join earth and b with prismatic([1, 0, 0]) as slide;\n"
            "apply force value = [-k * slide.q, 0, 0], body = earth end on b;\n"
            "initial slide.q = 0.1;")
    program = lsdc.load_text(text, name="spring.lsd")
    with pytest.raises(lsdc.ProgramError, match="no value for `k`"):
        program.prepare()
    # A spring of stiffness k on a unit mass: x = 0.1 cos(√k t).
    columns = program.simulate({"k": 4.0}, duration=1.0, every=0.5, tolerance=1e-12)
    np.testing.assert_allclose(columns["slide.q"], 0.1 * np.cos(2 * columns["time"]), atol=1e-9)
    with pytest.raises(lsdc.LsdcError, match="cannot read"):
        lsdc.load(tmp_path / "nowhere.lsd")


def test_urdf(root):
    prepared = lsdc.load(root / "tests" / "fixtures" / "urdf" / "double_pendulum.urdf").prepare()
    q = np.zeros((3, prepared.nq))
    assert prepared.crba(q).shape == (3, prepared.nv, prepared.nv)


def test_linearize_closed_form(example):
    # The pendulum about its initial angle (60°): θ'' = −m g c sin θ / J + τ / J, with J the
    # moment about the axis, J = Ixx + m c².
    model = lsdc.load(example("pendulum.lsd")).linearize(inputs=["swing.q"])
    inertia = 0.1 + 1.2 * 0.5**2
    assert model["states"] == ["swing.q", "swing.q'"]
    expected_a = np.array([[0, 1], [-1.2 * 9.81 * 0.5 * math.cos(math.pi / 3) / inertia, 0]])
    np.testing.assert_allclose(model["A"], expected_a, atol=1e-7)
    np.testing.assert_allclose(model["B"], [[0], [1 / inertia]], atol=1e-12)
    assert model["eigenvalues"].dtype == np.complex128
    with pytest.raises(lsdc.LsdcError):
        lsdc.load(example("pendulum.lsd")).linearize(inputs=["swing.x"])
