"""Impacts from Python: the pendulum against a wall against SciPy's
event-driven ``solve_ivp`` (stop at the wall, reverse the velocity times e,
start again), ``Model(impacts=...)``, the event rows, the Zeno end as a
``RunError`` with its rows, and bad impacts as ``ModelError``."""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy

import lagrange
from conftest import EXAMPLES

WALL = EXAMPLES / "impacts" / "pendulum_wall.toml"


def scipy_wall_run(until: float, th0: float, g: float, l: float, th_w: float, e: float):
    """θ'' = −(g/l) sin θ with θ ≤ θ_w: the impact times and a dense solution."""
    integrate = pytest.importorskip("scipy.integrate")

    def rhs(_t, y):
        return [y[1], -g / l * math.sin(y[0])]

    def wall(_t, y):
        return th_w - y[0]

    wall.terminal = True
    wall.direction = -1
    t, y = 0.0, [th0, 0.0]
    impacts, parts = [], []
    while t < until:
        sol = integrate.solve_ivp(rhs, (t, until), y, rtol=1e-12, atol=1e-12, events=wall, dense_output=True,
                                  method="DOP853")
        parts.append((t, sol.t[-1], sol.sol))
        if sol.status != 1:
            break
        t = sol.t_events[0][0]
        th, thd = sol.y_events[0][0]
        impacts.append((t, thd))
        y = [th, -e * thd]

    def at(time: float) -> np.ndarray:
        for a, b, f in parts:
            if a <= time <= b:
                return f(time)
        raise ValueError(time)

    return impacts, at


def test_the_pendulum_against_a_wall_matches_scipys_event_driven_run() -> None:
    model = lagrange.load(WALL)
    run = model.simulate(until=10, rtol=1e-12)
    impacts, at = scipy_wall_run(10.0, -1.0, 9.81, 1.0, 0.3, 0.8)
    labels = [(i, label) for i, label in run.events]
    befores = [i for i, label in labels if label == "impact wall before"]
    afters = [i for i, label in labels if label == "impact wall after"]
    assert len(befores) == len(afters) == len(impacts) >= 5
    for i, j, (t, thd) in zip(befores, afters, impacts):
        assert abs(run.t[i] - t) < 1e-8 and run.t[j] == run.t[i]
        assert abs(run["th'"][i] - thd) < 1e-8
        assert abs(run["th'"][j] + 0.8 * run["th'"][i]) < 1e-12
    # Between impacts the samples agree with SciPy's dense solution.
    samples = [k for k in range(len(run)) if k not in set(befores) | set(afters)]
    for k in samples[::50]:
        want = at(float(run.t[k]))
        assert abs(run["th"][k] - want[0]) < 1e-7 and abs(run["th'"][k] - want[1]) < 1e-7
    assert run.summary["impacts"][0]["count"] == len(impacts)
    assert run.summary["energy_lost_at_impacts"] > 0


def test_a_model_built_in_python_bounces() -> None:
    y, g, e = sympy.symbols("y g e")
    model = lagrange.Model(
        [y],
        name="ball",
        parameters={g: 9.81, e: 0.5},
        particles=[{"mass": 1, "position": [0, y]}],
        gravity=g,
        impacts=[{"name": "floor", "surface": y, "restitution": e}],
        initial={"y": 2.0, "y'": 0.0},
    )
    assert "floor: y ≥ 0,  restitution e" in str(model.derive())
    run = model.simulate(until=1.0)
    (i, before), (j, after) = run.events[:2]
    assert (before, after) == ("impact floor before", "impact floor after")
    assert abs(run.t[i] - math.sqrt(2 * 2.0 / 9.81)) < 1e-9
    assert abs(run["y'"][j] + 0.5 * run["y'"][i]) < 1e-12


def test_bounces_that_die_out_raise_a_run_error_with_the_rows() -> None:
    model = lagrange.load(EXAMPLES / "impacts" / "bouncing_ball.toml", set={"e": 0.5})
    with pytest.raises(lagrange.RunError) as caught:
        model.simulate(until=10)
    assert "accumulate (Zeno)" in caught.value.message
    t_inf = math.sqrt(2 / 9.81) * 1.5 / 0.5
    assert caught.value.t is not None and 0 < t_inf - caught.value.t < 1e-3
    assert caught.value.run is not None and len(caught.value.run) > 100


def test_bad_impacts_raise_model_errors() -> None:
    with pytest.raises(lagrange.ModelError, match="must be between 0 and 1, not 1.5"):
        lagrange.load(EXAMPLES / "impacts" / "bouncing_ball.toml", set={"e": 1.5})
    y = sympy.Symbol("y")
    with pytest.raises(lagrange.ModelError, match="the impact has no `surface`"):
        lagrange.Model([y], kinetic="y'^2/2", impacts=[{"restitution": 1}], initial={"y": 1, "y'": 0})
    with pytest.raises(lagrange.ModelError, match="a sweep does not run models with"):
        lagrange.load(EXAMPLES / "impacts" / "bouncing_ball.toml").sweep(until=1, grid={"h0": [1.0, 2.0]})
