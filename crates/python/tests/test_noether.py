"""Conserved quantities from symmetries of L (Noether), from Python: the
derivation's `conserved` entries are the CLI's (`why.code == "symmetry"`,
with the generator), and a run audits them."""

from __future__ import annotations

import numpy as np

import lagrange
from conftest import EXAMPLES, cli_json


def test_two_bodies_in_cartesian_coordinates_conserve_momentum_and_angular_momentum() -> None:
    model = lagrange.load(EXAMPLES / "two_body_cartesian.toml")
    found = {c["name"]: c for c in model.derive().conserved if c["why"]["code"] == "symmetry"}
    assert set(found) == {"P_x", "P_y", "L_z"}
    assert found["L_z"]["why"]["generator"]["kind"] == "rotation"
    assert found["P_x"]["why"]["generator"]["xi"] == {"x1": "1", "x2": "1"}
    cli = cli_json("derive", EXAMPLES / "two_body_cartesian.toml", "--format", "json")["conserved"]
    assert [c["name"] for c in cli] == [c["name"] for c in model.derive().conserved]
    run = model.simulate(until=20, rtol=1e-11)
    for name in ("P_x", "P_y", "L_z"):
        values = run.invariants[name]
        assert np.abs(values - values[0]).max() < 1e-8 * max(1.0, abs(values[0]))
        assert run.summary["invariants"][name]["conserved"] is True


def test_a_model_without_symmetry_gains_nothing() -> None:
    conserved = lagrange.load(EXAMPLES / "double_pendulum.toml").derive().conserved
    assert [c["why"]["code"] for c in conserved] == ["energy_conserved"]
