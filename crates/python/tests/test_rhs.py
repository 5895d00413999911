"""model.rhs() and model.jac(): the compiled right-hand side and its
Jacobian inside scipy's solve_ivp (one state or many, arrays in and out)."""

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
    assert isinstance(dy, np.ndarray) and dy.shape == (2,)
    assert dy == pytest.approx([0.7, -g_over_l * np.sin(0.3)], rel=1e-14)
    with pytest.raises(ValueError, match="give \\[q, q'\\] of length 2"):
        f(0.0, [1.0, 2.0, 3.0])


def test_rhs_reads_every_kind_of_y_alike():
    # A float64 array is read from its bytes; anything else element by element.
    f = lagrange.load(EXAMPLES / "double_pendulum.toml").rhs()
    y = np.array([0.3, 0.5, 0.7, -0.2])
    expected = f(0.0, y.tolist())
    strided = np.array([0.3, 9.0, 0.5, 9.0, 0.7, 9.0, -0.2, 9.0])[::2]
    for same in (y, tuple(y), strided, y.astype(">f8"), np.frombuffer(y.tobytes())):
        assert np.array_equal(f(0.0, same), expected)
    assert np.array_equal(f(0.0, np.array([1, 2, 3, 4])), f(0.0, [1.0, 2.0, 3.0, 4.0]))
    for wrong in (np.zeros((2, 2)), "abcd", None):
        with pytest.raises(ValueError):
            f(0.0, wrong)


def test_rhs_takes_many_states_at_once_as_vectorized_solve_ivp_passes_them():
    model = lagrange.load(EXAMPLES / "double_pendulum.toml")
    f = model.rhs()
    ys = np.array([[0.3, 0.5, 0.7, -0.2], [1.0, -2.0, 0.1, 0.4], [2.0, 2.5, 0.0, 0.0]]).T
    many = f(0.0, ys)
    assert many.shape == (4, 3)
    for k in range(3):
        assert np.array_equal(many[:, k], f(0.0, ys[:, k]))
    init = model.initial
    y0 = [init["a"], init["b"], init["a'"], init["b'"]]
    sol = scipy_integrate.solve_ivp(f, (0, 5), y0, method="DOP853", rtol=1e-12, atol=1e-12, vectorized=True)
    run = model.simulate(until=5, rtol=1e-12)
    np.testing.assert_allclose(sol.y[:, -1], run.y[-1], rtol=1e-7, atol=1e-7)


def test_jac_is_the_derivative_and_radau_needs_no_differences():
    model = lagrange.load(EXAMPLES / "kepler.toml")
    f, jac = model.rhs(), model.jac()
    y = np.array([1.2, 0.3, 0.1, 0.8])
    h = 1e-6
    numeric = np.column_stack([(f(0.0, y + h * e) - f(0.0, y - h * e)) / (2 * h) for e in np.eye(4)])
    assert jac(0.0, y).shape == (4, 4)
    np.testing.assert_allclose(jac(0.0, y), numeric, rtol=1e-6, atol=1e-7)
    y0 = [1.0, 0.0, 0.0, 1.2]
    calls = {"jac": 0, "differences": 0}

    def counted(key):
        def g(t, y):
            calls[key] += 1
            return f(t, y)
        return g

    with_jac = scipy_integrate.solve_ivp(counted("jac"), (0, 5), y0, method="Radau", jac=jac, rtol=1e-10, atol=1e-12)
    differenced = scipy_integrate.solve_ivp(counted("differences"), (0, 5), y0, method="Radau", rtol=1e-10, atol=1e-12)
    assert with_jac.status == 0 and with_jac.njev > 0
    np.testing.assert_allclose(with_jac.y[:, -1], differenced.y[:, -1], rtol=1e-6, atol=1e-8)
    # Differencing a Jacobian costs n calls of f; the compiled one none.
    assert calls["jac"] == with_jac.nfev
    assert calls["differences"] > differenced.nfev
    with pytest.raises(lagrange.ModelError, match="without constraints"):
        lagrange.load(EXAMPLES / "constraints" / "pendulum_cartesian.toml").jac()
