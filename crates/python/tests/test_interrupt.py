"""Ctrl-C stops a long run promptly and keeps what it computed."""

from __future__ import annotations

import _thread
import threading

import pytest

import lagrange
from conftest import EXAMPLES


def interrupt_soon(seconds: float = 0.5) -> threading.Timer:
    timer = threading.Timer(seconds, _thread.interrupt_main)
    timer.start()
    return timer


def test_ctrl_c_stops_simulate_and_keeps_the_rows():
    model = lagrange.load(EXAMPLES / "chain50.toml")
    timer = interrupt_soon()
    try:
        with pytest.raises(KeyboardInterrupt) as info:
            # Far longer than the test waits: only the interrupt ends it.
            model.simulate(until=1e6, samples=1_000_000)
    finally:
        timer.cancel()
    e = info.value
    assert isinstance(e, lagrange.Interrupted)
    run = e.run
    assert run is not None and len(run) >= 1
    assert run.t[-1] < 1e6
    assert run.summary["interrupted"]["t"] == run.t[-1]
    # The final state is the last row kept, not a step past it.
    assert run.summary["t_final"] == run.t[-1]
    first = model.coordinates[0]
    assert run.final[first] == run[first][-1]


def test_ctrl_c_stops_a_sweep_and_keeps_the_finished_runs():
    model = lagrange.load(EXAMPLES / "double_pendulum.toml")
    timer = interrupt_soon()
    try:
        with pytest.raises(KeyboardInterrupt) as info:
            lagrange.sweep(model, until=2000, grid={"a": (-3.0, 3.0, 400)}, threads=1)
    finally:
        timer.cancel()
    table = info.value.run
    assert isinstance(table, lagrange.Table)
    assert len(table) < 400
    assert list(table.runs) == list(range(len(table)))


def test_the_gil_is_released_while_a_run_integrates():
    # A run on another thread; this thread counts while it goes. Were the GIL
    # held for the whole run, the count would stay near zero until it ended.
    model = lagrange.load(EXAMPLES / "chain50.toml")
    done = threading.Event()

    def work():
        model.simulate(until=1000)
        done.set()

    thread = threading.Thread(target=work)
    thread.start()
    count = 0
    while not done.is_set():
        count += 1
    thread.join()
    assert count > 100_000, f"this thread ran only {count} loop iterations during the run"
