"""modes(), orbit(), top(), inertia() and extremal() from Python: the CLI's
JSON and the notes' numbers."""

from __future__ import annotations

import numpy as np
import pytest

import lagrange
from conftest import EXAMPLES, cli_json


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
