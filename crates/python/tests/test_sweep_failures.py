"""A sweep whose every run fails found nothing: ``lagrange.sweep`` raises
:class:`lagrange.RunError` with the first run's reason, as ``lagrange sweep``
exits 1 with it, and the exception keeps the table. Some runs failing is a
finding: the table comes back, the failures in its rows."""

from __future__ import annotations

import pytest

import lagrange
from conftest import cli

# x^(3/2) has no real value for x < 0: a run from there fails at t = 0.
ROOT = "name = \"falling root\"\ncoordinates = [\"x\"]\nlagrangian = \"x'^2/2 - x^(3/2)\"\n[initial]\nx = 1.0\n\"x'\" = 0.0\n"


def test_every_run_failing_raises_the_first_run_s_reason(tmp_path):
    model = lagrange.Model.from_toml(ROOT)
    with pytest.raises(lagrange.RunError, match=r"^every run failed \(3\); the first, run 0: ") as info:
        lagrange.sweep(model, until=0.5, grid={"x": lagrange.grid(-1, -0.5, 3)}, lyapunov=False, threads=1)
    table = info.value.run
    assert isinstance(table, lagrange.Table) and len(table) == 3
    assert all(table.failures)
    assert info.value.message.endswith(table.failures[0])
    # The CLI says the same and exits 1.
    path = tmp_path / "root.toml"
    path.write_text(ROOT)
    r = cli("sweep", path, "--until", "0.5", "--grid", "x=-1:-0.5:3", "--no-lyapunov", check=False)
    assert r.returncode == 1, r.stderr
    assert info.value.message in r.stderr


def test_some_runs_failing_return_the_table():
    model = lagrange.Model.from_toml(ROOT)
    table = lagrange.sweep(model, until=0.5, grid={"x": [-1.0, 1.0]}, lyapunov=False, threads=1)
    assert table.failures[0] and not table.failures[1]
