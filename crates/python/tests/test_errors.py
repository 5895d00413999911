"""Bad input raises lagrange.ModelError with file, line, column and the caret
snippet; a failed run raises RunError with its rows; nothing panics."""

from __future__ import annotations

import numpy as np
import pytest

import lagrange
from conftest import EXAMPLES

BAD = """name = "bad"
coordinates = ["x"]
lagrangian = "m*x'^2/2 - k*x^"

[parameters]
m = 1.0
k = 1.0
"""


def test_model_error_points_into_the_text():
    with pytest.raises(lagrange.ModelError) as info:
        lagrange.Model.from_toml(BAD, name="spring.toml")
    e = info.value
    assert e.file == "spring.toml"
    assert e.line == 3
    assert e.column is not None and e.column > len('lagrangian = "')
    assert "lagrangian = \"m*x'^2/2 - k*x^\"" in e.snippet
    assert "^" in e.snippet.splitlines()[-1]
    assert str(e).startswith(f"spring.toml:3:{e.column}: ")
    assert isinstance(e, ValueError) and isinstance(e, lagrange.LagrangeError)
    assert e.kind == "invalid"


def test_the_kind_of_a_model_error_says_what_to_branch_on():
    no_inertia = """name = "no inertia"
coordinates = ["x", "y"]

[[particles]]
mass = "1"
position = ["x + y"]
"""
    with pytest.raises(lagrange.ModelError) as info:
        lagrange.Model.from_toml(no_inertia).derive()
    assert info.value.kind == "singular_mass_matrix"


def test_a_missing_file_is_file_not_found():
    with pytest.raises(FileNotFoundError) as info:
        lagrange.load(EXAMPLES / "no_such_model.toml")
    assert info.value.filename == str(EXAMPLES / "no_such_model.toml")
    with pytest.raises(FileNotFoundError, match="a folder, not a file"):
        lagrange.load(EXAMPLES)
    for analysis in (lagrange.inertia, lagrange.extremal):
        with pytest.raises(FileNotFoundError):
            analysis(EXAMPLES / "no_such_file.toml")


def test_the_package_namespace_and_the_reports_read_well():
    public = [name for name in dir(lagrange) if not name.startswith("_")]
    assert not {"List", "Mapping", "Optional", "Tuple", "Union", "annotations"} & set(public)
    report = lagrange.load(EXAMPLES / "coupled_oscillators.toml").modes()
    assert repr(report).startswith("<Report lagrange.modes/1 of 'two coupled oscillators': equilibrium, T, U, frequencies")


def test_a_matrix_of_numbers_converts_to_an_array():
    oscillators = lagrange.load(EXAMPLES / "coupled_oscillators.toml").derive()
    assert np.array_equal(np.array(oscillators.mass_matrix), np.eye(2))
    pendulum = lagrange.load(EXAMPLES / "double_pendulum.toml").derive()
    with pytest.raises(TypeError, match="evaluate it at a state first"):
        np.array(pendulum.mass_matrix)
    assert np.array(pendulum.mass_matrix(a=0.3, b=0.3)).shape == (2, 2)


def test_unknown_parameter_override():
    with pytest.raises(lagrange.ModelError) as info:
        lagrange.load(EXAMPLES / "pendulum.toml", set={"nope": 1.0})
    assert "nope" in str(info.value)


def test_bad_options():
    model = lagrange.load(EXAMPLES / "pendulum.toml")
    with pytest.raises(lagrange.ModelError, match="method"):
        model.simulate(until=1, method="euler")
    with pytest.raises(lagrange.ModelError, match="until must be a positive time"):
        model.simulate(until=-1)
    with pytest.raises(lagrange.ModelError, match="rtol must be a positive number"):
        model.simulate(until=1, rtol=0)
    with pytest.raises(lagrange.ModelError, match="samples"):
        model.simulate(until=1, samples=1)
    with pytest.raises(lagrange.ModelError) as info:
        model.simulate(until=1, stop_when="ph <")
    assert info.value.file == "stop_when"
    with pytest.raises(lagrange.ModelError):
        model.simulate(until=1, method="dop853", dt=0.01)


def test_bad_expression():
    with pytest.raises(lagrange.ModelError) as info:
        lagrange.expression("sin(x")
    assert info.value.file == "expression" and info.value.column is not None


def test_a_failed_run_keeps_its_rows():
    # x'' = x^2 from x = 1 blows up at t = √6·... < 3: the run fails midway.
    model = lagrange.Model(
        coordinates=["x"],
        parameters={"m": 1.0},
        lagrangian="m*x'^2/2 + x^3/3",
        initial={"x": 1.0, "x'": 0.0},
    )
    with pytest.raises(lagrange.RunError) as info:
        model.simulate(until=10)
    e = info.value
    assert e.t is not None and 0 < e.t < 10
    assert e.run is not None and len(e.run) > 1
    assert e.run.t[-1] <= e.t


def test_analysis_refusals_name_the_model():
    with pytest.raises(lagrange.ModelError) as info:
        lagrange.load(EXAMPLES / "double_pendulum.toml").orbit()
    assert info.value.file.endswith("double_pendulum.toml")
    with pytest.raises(lagrange.ModelError):
        lagrange.load(EXAMPLES / "constraints" / "pendulum_cartesian.toml").rhs()


def test_hostile_text_does_not_panic():
    for text in ["", "coordinates = 3", "coordinates = [\"x\"]\nlagrangian = \"x'^\"", "\x00\xff", "[[particles]]\nmass = 1e400"]:
        with pytest.raises(lagrange.ModelError):
            lagrange.Model.from_toml(text)


def test_a_parameter_set_to_nan_is_refused_everywhere():
    # As Model(parameters=...) and the CLI's --set refuse it.
    for bad in (float("nan"), float("inf")):
        with pytest.raises(lagrange.ModelError, match="must be a finite number") as info:
            lagrange.load(EXAMPLES / "pendulum.toml", set={"g": bad})
        assert "parameter 'g'" in str(info.value)
        model = lagrange.load(EXAMPLES / "pendulum.toml")
        with pytest.raises(lagrange.ModelError, match="must be a finite number"):
            model.with_parameters(g=bad)


def test_a_misspelt_name_in_an_evaluation_raises_naming_the_closest():
    d = lagrange.load(EXAMPLES / "spherical_pendulum.toml").derive()
    names = lagrange.load(EXAMPLES / "spherical_pendulum.toml").coordinates
    q = names[-1]
    with pytest.raises(ValueError, match='"gg" is not a name of this model \\(did you mean "g"\\?\\)'):
        d.hamiltonian(**{q: 0.0, f"p_{q}": 0.0, "gg": 1.0})
    # Names of the model that the expression does not use are fine.
    assert isinstance(d.hamiltonian(**{n: 0.1 for n in names}, **{f"p_{n}": 0.0 for n in names}, g=1.0), float)


def test_an_error_in_a_model_built_in_python_names_the_argument():
    with pytest.raises(lagrange.ModelError) as info:
        lagrange.Model(coordinates=["x"], parameters={"k": 1.0}, kinetic="x'^2/2", potential="k*x^")
    e = info.value
    assert e.file is None and e.line is None
    assert e.argument == "Model(potential=...)"
    assert str(e).startswith("Model(potential=...): in the potential: expected an exponent")
    with pytest.raises(lagrange.ModelError) as info:
        lagrange.Model(
            coordinates=["x"], parameters={"m": 1.0},
            particles=[{"mass": "m", "position": ["x", "0"]}, {"mass": "q", "position": ["x", "1"]}],
        )
    assert info.value.argument == "Model(particles[1]['mass'])", str(info.value)
    assert "unknown name 'q'" in str(info.value)


def test_option_errors_name_the_option_not_an_internal_field():
    model = lagrange.load(EXAMPLES / "pendulum.toml")
    for options, message in (
        ({"samples": 2.5}, "samples must be a whole number, not 2.5"),
        ({"stop_when": 3}, "expected a condition or a list of them"),
    ):
        with pytest.raises(TypeError) as info:
            model.simulate(until=1, **options)
        assert message in str(info.value) and "Options" not in str(info.value)


def test_the_file_of_an_error_in_text_is_none():
    with pytest.raises(lagrange.ModelError) as info:
        lagrange.Model.from_toml(BAD)
    assert info.value.file is None and info.value.line == 3
    assert str(info.value).startswith("<string>:3:")


def test_a_matrix_is_indexed_by_entry_or_by_row():
    pendulum = lagrange.load(EXAMPLES / "double_pendulum.toml").derive()
    m = pendulum.mass_matrix
    assert [str(e) for e in m[0]] == [str(e) for e in list(m)[0]] and len(m[1]) == 2
    assert str(m[0, 1]) == str(m[0][1]) == str(list(m)[0][1])
    with pytest.raises(IndexError, match=r"two indices, m\[i, j\]"):
        m[0, 1, 0]
    with pytest.raises(TypeError, match=r"m\[i, j\] \(an entry\) or m\[i\] \(a row\)"):
        m[0:1]
