"""The spellings of a sweep's grid: a list or an array is the values
themselves, lagrange.grid(start, stop, count) (or a tuple of three) spaces
them evenly, and anything else is refused, never read another way."""

from __future__ import annotations

import numpy as np
import pytest

import lagrange
from conftest import EXAMPLES


@pytest.fixture(scope="module")
def double():
    return lagrange.load(EXAMPLES / "double_pendulum.toml")


def values_run(double, axis):
    table = lagrange.sweep(double, until=0.05, grid={"a": axis}, lyapunov=False, threads=1)
    return list(table.grid()["a"])


def test_a_list_or_an_array_is_the_values_themselves(double):
    assert values_run(double, [0.0, 1.0, 5.0]) == [0.0, 1.0, 5.0]
    assert values_run(double, np.array([0.0, 1.0, 5.0])) == [0.0, 1.0, 5.0]
    assert values_run(double, [0.0, 1.0, 5.0, 6.0]) == [0.0, 1.0, 5.0, 6.0]
    assert values_run(double, np.linspace(0.0, 1.0, 3)) == [0.0, 0.5, 1.0]
    assert values_run(double, 0.25) == [0.25]


def test_grid_and_a_tuple_space_the_values_evenly(double):
    assert values_run(double, lagrange.grid(0.0, 1.0, 5)) == [0.0, 0.25, 0.5, 0.75, 1.0]
    assert values_run(double, (0.0, 1.0, 5)) == [0.0, 0.25, 0.5, 0.75, 1.0]
    assert lagrange.grid(0, 1, 5) == lagrange.Linspace(0.0, 1.0, 5)


def test_a_parameter_axis_of_values_sets_the_parameter(double):
    table = lagrange.sweep(double, until=0.05, grid={"g": [1.62, 9.81]}, lyapunov=False, threads=1)
    assert list(table.grid()["g"]) == [1.62, 9.81]
    slow, fast = (lagrange.load(EXAMPLES / "double_pendulum.toml", set={"g": g}).simulate(until=0.05) for g in (1.62, 9.81))
    assert table["final_a"][0] == pytest.approx(slow.final["a"], rel=1e-8)
    assert table["final_a"][1] == pytest.approx(fast.final["a"], rel=1e-8)


@pytest.mark.parametrize(
    "axis, message",
    [
        ((0.0, 1.0, 5, 7), "a tuple is \\(start, stop, count\\)"),
        ((0.0, 1.0, 2.5), "the count must be a whole number"),
        ([0.0, float("nan")], "every value must be a finite number"),
        ([], "expected values"),
        ("0:1:3", "expected values"),
        ([[0.0, 1.0]], "expected values"),
    ],
)
def test_other_spellings_are_refused(double, axis, message):
    with pytest.raises(ValueError, match=message):
        lagrange.sweep(double, until=0.05, grid={"a": axis}, lyapunov=False, threads=1)
