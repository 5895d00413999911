"""modes(), orbit(), top(), linearize(), report(), inertia() and extremal()
from Python: the CLI's JSON, pages and the notes' numbers."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import lagrange
from conftest import EXAMPLES, cli, cli_json


def test_coupled_oscillators_frequencies():
    # The notes' Fig. 3.3: Ω1 = 1, Ω2 = 1.5.
    modes = lagrange.load(EXAMPLES / "coupled_oscillators.toml").modes()
    np.testing.assert_allclose(modes.frequencies, [1.0, 1.5], rtol=1e-12)
    assert modes.stable is True
    assert modes.json == cli_json("modes", EXAMPLES / "coupled_oscillators.toml", "--format", "json")
    assert "1.5" in str(modes)


def test_modes_at_and_unstable():
    model = lagrange.load(EXAMPLES / "pendulum.toml")
    with pytest.raises(lagrange.ModelError, match="unstable"):
        model.modes(at={"ph": 3.14159})
    report = model.modes(at={"ph": 3.14159}, allow_unstable=True)
    assert report.stable is False


def test_kepler_orbit():
    path = EXAMPLES / "kepler.toml"
    orbit = lagrange.load(path).orbit()
    assert orbit.json == cli_json("orbit", path, "--format", "json")
    assert orbit.kind == "ellipse"
    assert 0 < orbit.eccentricity < 1


def test_heavy_top():
    path = EXAMPLES / "tops" / "heavy_top.toml"
    top = lagrange.load(path).top()
    assert top.json == cli_json("top", path, "--format", "json")
    assert top.kind == "heavy"


def test_cube_inertia():
    path = EXAMPLES / "bodies" / "cube.toml"
    report = lagrange.inertia(path)
    assert report.json == cli_json("inertia", path, "--format", "json")
    assert report.tensor.shape == (3, 3)
    text = path.read_text()
    assert lagrange.inertia(text=text).json == report.json


def test_brachistochrone():
    path = EXAMPLES / "extremal" / "brachistochrone.toml"
    report = lagrange.extremal(path)
    assert report.json == cli_json("extremal", path, "--format", "json")
    assert report.value < report.straight_line_value
    assert report.path.shape == (201, 2)


def test_linearize_gives_the_cli_s_matrices_as_arrays():
    model = EXAMPLES / "cart_pendulum.toml"
    report = lagrange.load(model).linearize()
    cli_report = cli_json("linearize", model, "--format", "json")
    assert report.format == "lagrange.linearize/1"
    assert isinstance(report.A, np.ndarray) and report.A.shape == (4, 4)
    assert isinstance(report.B, np.ndarray) and report.B.shape == (4, 2)
    assert np.array_equal(report.A, np.array(cli_report["A"]))
    assert np.array_equal(report.B, np.array(cli_report["B"]))
    assert str(report).startswith("cart and pendulum — linearization about an equilibrium")
    top = EXAMPLES / "tops" / "heavy_top.toml"
    steady = lagrange.load(top).linearize(about="steady")
    assert np.array_equal(steady.A, np.array(cli_json("linearize", top, "--about", "steady", "--format", "json")["A"]))
    with pytest.raises(lagrange.ModelError, match='about must be "equilibrium" or "steady"'):
        lagrange.load(model).linearize(about="rest")
    with pytest.raises(lagrange.ModelError, match="a rate applies to a steady motion"):
        lagrange.load(model).linearize(rates={"x": 1.0})


def test_report_is_the_cli_s_page_for_a_notebook_or_a_file(tmp_path):
    model = lagrange.load(EXAMPLES / "double_pendulum.toml")
    page = model.report(until=2, path=tmp_path / "page.html")
    assert page.failure is None
    assert page._repr_html_() == page.html == (tmp_path / "page.html").read_text(encoding="utf-8")
    assert page.html.startswith("<!DOCTYPE html>") and "planar double pendulum" in page.html
    cli("report", EXAMPLES / "double_pendulum.toml", "--until", 2, "-o", tmp_path / "cli.html")
    assert len(page.html) == pytest.approx(len((tmp_path / "cli.html").read_text(encoding="utf-8")), rel=0.05)
    blow_up = lagrange.load(Path(__file__).resolve().parents[2] / "cli" / "tests" / "bad_simulate" / "blow_up.toml")
    with pytest.warns(RuntimeWarning, match="the run failed"):
        failed = blow_up.report(until=5)
    assert failed.failure is not None and "<!DOCTYPE html>" in failed.html[:100]
