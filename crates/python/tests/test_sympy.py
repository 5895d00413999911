"""SymPy in and out: expressions convert with to_sympy(), and models can be
written with SymPy expressions (dynamicsymbols for coordinates)."""

from __future__ import annotations

import numpy as np
import pytest

import lagrange
from conftest import EXAMPLES

sympy = pytest.importorskip("sympy")
from sympy.physics.mechanics import dynamicsymbols  # noqa: E402


def test_hamiltonian_to_sympy():
    d = lagrange.load(EXAMPLES / "pendulum.toml").derive()
    m, l, g, p = sympy.symbols("m l g p_ph")
    ph = dynamicsymbols("ph")
    expected = p**2 / (2 * m * l**2) - m * g * l * sympy.cos(ph)
    assert sympy.simplify(d.hamiltonian.to_sympy() - expected) == 0


def test_velocities_become_time_derivatives():
    d = lagrange.load(EXAMPLES / "pendulum.toml").derive()
    ph = dynamicsymbols("ph")
    m, l = sympy.symbols("m l")
    assert d.momenta["ph"].to_sympy() == m * l**2 * ph.diff()
    plain = d.momenta["ph"].to_sympy(dynamic=False)
    assert plain == m * l**2 * sympy.Symbol("ph'")


def test_rationals_stay_exact():
    m, v, k = sympy.symbols("m v k")
    assert lagrange.expression("m*v^2/2 + k/4").to_sympy() == m * v**2 / 2 + k / 4
    # A decimal is a float in the expression language, and stays one.
    c = lagrange.expression("0.1*k").to_sympy().coeff(k)
    assert isinstance(c, sympy.Float) and float(c) == 0.1
    assert lagrange.sympy_bridge.from_sympy(sympy.Rational(1, 3) * k) == "((1/3)*k)"


def test_model_from_sympy_matches_the_file():
    # The double pendulum written as a SymPy user would, against the example file.
    a, b = dynamicsymbols("a b")
    mA, mB, lA, lB, g = sympy.symbols("mA mB lA lB g")
    xA, yA = lA * sympy.sin(a), -lA * sympy.cos(a)
    xB, yB = xA + lB * sympy.sin(b), yA - lB * sympy.cos(b)
    model = lagrange.Model(
        name="planar double pendulum",
        coordinates=[a, b],
        parameters={mA: 1.0, mB: 1.0, lA: 1.0, lB: 1.0, g: 9.81},
        particles=[{"mass": mA, "position": [xA, yA]}, {"mass": mB, "position": [xB, yB]}],
        gravity=g,
        initial={"a": 2.0, "a'": 0.0, "b": 2.5, "b'": 0.0},
    )
    ours = model.derive()
    theirs = lagrange.load(EXAMPLES / "double_pendulum.toml").derive()
    for field in ("lagrangian", "hamiltonian", "equations", "momenta", "forcing", "mass_matrix", "cyclic"):
        assert ours.json[field] == theirs.json[field], field


def test_lagrangian_given_as_sympy_with_derivatives():
    x = dynamicsymbols("x")
    m, k = sympy.symbols("m k")
    L = m * x.diff() ** 2 / 2 - k * x**2 / 2
    model = lagrange.Model(coordinates=[x], parameters={m: 2.0, k: 8.0}, lagrangian=L, initial={"x": 1, "x'": 0})
    eq = model.derive().equations["x"].to_sympy()
    assert sympy.simplify(eq - (m * x.diff(sympy.Symbol("t"), 2) + k * x)) == 0
    # ω = √(k/m) = 2: x(t) = cos(2t).
    run = model.simulate(until=1.0)
    assert run.q[-1, 0] == pytest.approx(np.cos(2.0), rel=1e-8)


def test_round_trip_through_sympy():
    d = lagrange.load(EXAMPLES / "double_pendulum.toml").derive()
    for eq in list(d.equations.values()) + [d.hamiltonian, d.lagrangian]:
        back = lagrange.expression(lagrange.sympy_bridge.from_sympy(eq.to_sympy()))
        # The same expression; its printed order of factors may differ (a fresh
        # pool orders names as it meets them).
        assert sympy.expand(back.to_sympy(dynamic=False) - eq.to_sympy(dynamic=False)) == 0


def test_latex_has_dots_for_velocities():
    d = lagrange.load(EXAMPLES / "pendulum.toml").derive()
    assert d.momenta["ph"]._repr_latex_() == r"$l^{2} m \dot{\phi}$"
    assert r"\ddot{\phi}" in d.equations["ph"].latex()
    whole = d._repr_latex_()
    assert whole.startswith("$$\\begin{aligned}") and whole.endswith("\\end{aligned}$$") and "%" not in whole
    assert whole.count("$$") == 2 * whole.count(r"\begin{aligned}")


def test_evaluation_broadcasts():
    d = lagrange.load(EXAMPLES / "pendulum.toml").derive()
    H = d.hamiltonian
    assert H(ph=0.0, p_ph=0.0) == pytest.approx(-9.81)
    values = H(ph=np.array([0.0, np.pi]), p_ph=[[0.0], [1.0]])
    assert values.shape == (2, 2)
    np.testing.assert_allclose(values, [[-9.81, 9.81], [0.5 - 9.81, 0.5 + 9.81]])
    T = d.kinetic
    assert T(ph_dot=2.0) == pytest.approx(2.0)
    assert T({"ph'": 2.0, "m": 3.0}) == pytest.approx(6.0)
    with pytest.raises(ValueError, match="p_ph"):
        H(ph=0.0)
