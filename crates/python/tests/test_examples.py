"""Every example model loads, derives and simulates from Python with the same
numbers as the CLI."""

from __future__ import annotations

import csv
import io

import numpy as np
import pytest

import lagrange
from conftest import EXAMPLES, cli_json, models

# Fields that time the process rather than describe the model.
TIMINGS = {"derive_seconds", "equations_seconds"}


@pytest.mark.parametrize("path", models(), ids=lambda p: str(p.relative_to(EXAMPLES)))
def test_derive_matches_cli(path):
    model = lagrange.load(path)
    ours = {k: v for k, v in model.derive().json.items() if k not in TIMINGS}
    theirs = {k: v for k, v in cli_json("derive", path, "--format", "json").items() if k not in TIMINGS}
    assert ours == theirs


@pytest.mark.parametrize("path", models(), ids=lambda p: str(p.relative_to(EXAMPLES)))
def test_simulate_matches_cli(path, tmp_path):
    model = lagrange.load(path)
    out = tmp_path / "run.csv"
    summary = cli_json("simulate", path, "--until", "1", "--samples", "11", "--out", out, "--summary", "json")
    run = model.simulate(until=1, samples=11)
    with open(out) as f:
        rows = list(csv.reader(f))
    assert rows[0] == run.columns
    table = np.array([[float(v) for v in r] for r in rows[1:]])
    assert table.shape == run.data.shape
    np.testing.assert_allclose(run.data, table, rtol=1e-12, atol=1e-12)
    assert run.summary["method"] == summary["method"]
    assert run.summary["steps"] == summary["steps"]
    for key, value in summary["final"].items():
        assert run.final[key] == pytest.approx(value, rel=1e-12, abs=1e-12), key
    for name, audit in summary["invariants"].items():
        assert run.summary["invariants"][name]["max_abs_drift"] == pytest.approx(audit["max_abs_drift"], rel=1e-6, abs=1e-15)


def test_arrays_are_views_of_the_table():
    run = lagrange.load(EXAMPLES / "double_pendulum.toml").simulate(until=2, samples=201)
    assert run.t.shape == (201,)
    assert run.q.shape == (201, 2) and run.qd.shape == (201, 2)
    assert run.t[-1] == 2.0
    np.testing.assert_array_equal(run.q[:, 0], run["a"])
    np.testing.assert_array_equal(run.qd[:, 1], run["b'"])
    assert set(run.invariants) == {"H"}
    assert run.invariants["H"].shape == (201,)
    assert str(run).splitlines()[0] == "planar double pendulum"


def test_pendulum_period_from_python():
    # The notes' small-oscillation period 2π√(l/g): one period brings it back.
    model = lagrange.Model(
        coordinates=["ph"],
        parameters={"m": 1.0, "l": 1.0, "g": 9.81},
        particles=[{"mass": "m", "position": ["l*sin(ph)", "-l*cos(ph)"]}],
        gravity="g",
        initial={"ph": 0.001, "ph'": 0.0},
    )
    period = 2 * np.pi / np.sqrt(9.81)
    run = model.simulate(until=period)
    assert run.t[-1] == pytest.approx(period, rel=1e-15)
    assert run.q[-1, 0] == pytest.approx(0.001, rel=1e-6)
    assert model.derive().equations["ph"] == "l^2*m*ph'' + g*l*m*sin(ph)"


def test_constraint_multipliers_and_forces():
    run = lagrange.load(EXAMPLES / "constraints" / "pendulum_cartesian.toml").simulate(until=1, samples=11)
    assert list(run.multipliers) == ["rod"]
    assert list(run.constraint_forces) == ["rod"]
    assert run.multipliers["rod"].shape == (11,)
    assert np.all(np.isfinite(run.multipliers["rod"]))


def test_crossings_and_pandas():
    pd = pytest.importorskip("pandas")
    run = lagrange.load(EXAMPLES / "pendulum.toml").simulate(until=5, crossing="ph")
    assert run.events, "the pendulum crosses ph = 0"
    frame = run.to_pandas()
    assert isinstance(frame, pd.DataFrame)
    assert list(frame.columns) == run.columns + ["event"]
    for i, condition in run.events:
        assert frame["event"][i] == condition
        assert abs(frame["ph"][i]) < 1e-9


def test_svg_plot_of_a_run():
    run = lagrange.load(EXAMPLES / "double_pendulum.toml").simulate(until=2)
    svg = run._repr_svg_()
    assert svg.lstrip().startswith("<svg") and svg.rstrip().endswith("</svg>")
    assert "planar double pendulum" in svg


def test_initial_values_replaced_for_one_run():
    model = lagrange.load(EXAMPLES / "pendulum.toml")
    run = model.simulate(until=1, samples=3, initial={"ph": 0.2, "ph_dot": 0.1})
    assert run.q[0, 0] == 0.2 and run.qd[0, 0] == 0.1
    assert model.initial["ph"] == 1.0
    with pytest.raises(lagrange.ModelError, match=r'initial\["x"\]: .x. is not a coordinate'):
        model.simulate(until=1, initial={"x": 1.0})
