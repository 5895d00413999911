"""model.rhs(): the compiled right-hand side inside scipy's solve_ivp."""

from __future__ import annotations

import numpy as np
import pytest

import lagrange
from conftest import EXAMPLES

scipy_integrate = pytest.importorskip("scipy.integrate")


def test_rhs_in_solve_ivp_matches_simulate():
    model = lagrange.load(EXAMPLES / "double_pendulum.toml")
    f = model.rhs()
    assert f.dim == 4
    init = model.initial
    y0 = [init["a"], init["b"], init["a'"], init["b'"]]
    sol = scipy_integrate.solve_ivp(f, (0, 5), y0, method="DOP853", rtol=1e-12, atol=1e-12)
    run = model.simulate(until=5, rtol=1e-12)
    np.testing.assert_allclose(sol.y[:, -1], run.y[-1], rtol=1e-7, atol=1e-7)


def test_rhs_is_the_equation_of_motion():
    # Pendulum: th'' = -(g/l) sin(th).
    model = lagrange.load(EXAMPLES / "pendulum.toml")
    f = model.rhs()
    g_over_l = model.parameters["g"] / model.parameters["l"]
    dy = f(0.0, np.array([0.3, 0.7]))
    assert dy == pytest.approx([0.7, -g_over_l * np.sin(0.3)], rel=1e-14)
    with pytest.raises(ValueError, match="components"):
        f(0.0, [1.0, 2.0, 3.0])


def test_rhs_reads_every_kind_of_y_alike():
    # A float64 array is read from its bytes; anything else element by element.
    f = lagrange.load(EXAMPLES / "double_pendulum.toml").rhs()
    y = np.array([0.3, 0.5, 0.7, -0.2])
    expected = f(0.0, y.tolist())
    strided = np.array([0.3, 9.0, 0.5, 9.0, 0.7, 9.0, -0.2, 9.0])[::2]
    for same in (y, tuple(y), strided, y.astype(">f8"), np.frombuffer(y.tobytes())):
        assert f(0.0, same) == expected
    assert f(0.0, np.array([1, 2, 3, 4])) == f(0.0, [1.0, 2.0, 3.0, 4.0])
    for wrong in (np.zeros((2, 2)), "abcd", None):
        with pytest.raises(TypeError, match="sequence of floats"):
            f(0.0, wrong)
