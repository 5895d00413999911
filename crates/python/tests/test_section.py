"""`Model.simulate(section=...)`: a Poincaré section from Python is the CLI's
(`simulate --section`), row for row and digit for digit; its points lie on
the surface and cross it the one way asked; `run.section` is the plane's
points; a section run pickles with its figure; bad sections raise naming
the argument."""

from __future__ import annotations

import csv
import pickle
from pathlib import Path

import numpy as np
import pytest

import lagrange
from conftest import EXAMPLES, cli

HH = EXAMPLES / "henon_heiles.toml"


def test_the_section_is_the_clis_digit_for_digit(tmp_path: Path) -> None:
    out = tmp_path / "section.csv"
    cli("simulate", HH, "--set", "E=0.125", "--until", "300", "--section", "x = 0", "--out", out)
    with open(out) as f:
        rows = list(csv.reader(f))
    model = lagrange.load(HH, set={"E": 0.125})
    run = model.simulate(until=300, section="x = 0")
    assert run.columns == rows[0]
    assert len(run) == len(rows) - 1 > 20
    assert np.array_equal(run.data, np.array(rows[1:], dtype=float))
    assert run.events == []
    assert run.summary["section"] == {"condition": "x = 0", "axes": ["y", "p_y"], "points": len(run)}


def test_points_are_on_the_surface_one_way_in_the_plane_asked() -> None:
    model = lagrange.load(HH, set={"E": 1 / 12})
    run = model.simulate(until=400, section="x < 0", section_axes="y, p_x")
    assert len(run) > 20
    assert np.abs(run["x"]).max() < 1e-10
    assert (run["x'"] < 0).all()
    assert np.abs(run["H"] - 1 / 12).max() < 1e-8
    points = run.section
    assert points is not None and points.shape == (len(run), 2)
    # p_x = x' for this L: the plane's second axis is the momentum.
    assert np.array_equal(points[:, 0], run["y"]) and np.array_equal(points[:, 1], run["x'"])
    assert "section x &lt; 0 (decreasing)" in run.svg() or "section x < 0 (decreasing)" in run.svg()
    assert model.simulate(until=1).section is None


def test_a_section_run_pickles_with_its_figure() -> None:
    run = lagrange.load(HH).simulate(until=200, section="x = 0")
    back = pickle.loads(pickle.dumps(run))
    assert np.array_equal(back.section, run.section)
    assert back.svg() == run.svg()


@pytest.mark.parametrize(
    "kwargs, says",
    [
        ({"section": "z = 0"}, "unknown name 'z'"),
        ({"section": "x = 0", "section_axes": "y"}, "two axes"),
        ({"section": "x = 0", "section_axes": "y, q_y"}, "section_axes:1:4"),
        ({"section": "x = 0", "crossing": "y = 0"}, "do not go together"),
        ({"section_axes": "y, p_y"}, "needs section="),
    ],
)
def test_bad_sections_raise_naming_the_argument(kwargs, says) -> None:
    with pytest.raises(lagrange.ModelError, match=None) as e:
        lagrange.load(HH).simulate(until=1, **kwargs)
    assert says in str(e.value)


def test_a_section_that_is_not_a_string_is_refused() -> None:
    with pytest.raises(TypeError, match="section must be a string"):
        lagrange.load(HH).simulate(until=1, section=0.0)  # type: ignore[arg-type]


def test_the_report_draws_the_section_among_the_analyses(tmp_path: Path) -> None:
    import json
    import re

    page = lagrange.load(HH, set={"E": 0.125}).report(until=300, section="x = 0", path=tmp_path / "hh.html")
    html = (tmp_path / "hh.html").read_text()
    body = re.search(r'<script type="application/json" id="lagrange-data">(.*?)</script>', html, re.S)
    assert body is not None and page.failure is None
    section = json.loads(body.group(1).replace("<\\/", "</"))["analyses"]["section"]
    run = lagrange.load(HH, set={"E": 0.125}).simulate(until=300, samples=2001, section="x = 0")
    assert section["points"] == len(run) and section["axes"] == ["y", "p_y"]
    assert np.array_equal(np.array(section["x"]), run["y"]) and np.array_equal(np.array(section["y"]), run["p_y"])
    with pytest.raises(lagrange.ModelError, match="needs section="):
        lagrange.load(HH).report(until=1, section_axes="y, p_y")
