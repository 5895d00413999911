"""Sweeps on a Dask cluster: the rows equal a one-process sweep's exactly."""

from __future__ import annotations

import numpy as np
import pytest

import lagrange
from conftest import EXAMPLES

distributed = pytest.importorskip("distributed")


def test_local_sweep_matches_the_cli(tmp_path):
    from conftest import cli

    model = lagrange.load(EXAMPLES / "double_pendulum.toml")
    table = lagrange.sweep(model, until=2, grid={"a": (-1.0, 1.0, 5), "b": (0.0, 1.0, 3)})
    out = tmp_path / "sweep.csv"
    cli("sweep", EXAMPLES / "double_pendulum.toml", "--until", "2", "--grid", "a=-1.0:1.0:5,b=0.0:1.0:3", "--out", out)
    assert table == lagrange.Table(out.read_text())
    assert len(table) == 15
    assert table.columns[:2] == ["a", "b"]


def test_shards_merge_to_the_whole():
    model = lagrange.load(EXAMPLES / "double_pendulum.toml")
    grid = {"a": (-1.0, 1.0, 7)}
    whole = lagrange.sweep(model, until=1, grid=grid)
    parts = [lagrange.sweep(model, until=1, grid=grid, shard=(i, 3)) for i in range(3)]
    assert sorted(r for p in parts for r in p.runs) == list(range(7))
    merged = lagrange.Table(lagrange._native.merge([(f"{i}", p.csv) for i, p in enumerate(parts)]))
    assert merged == whole


def test_dask_local_cluster_equals_one_process():
    model = lagrange.load(EXAMPLES / "double_pendulum.toml")
    grid = {"a": (-3.0, 3.0, 12), "b'": (-1.0, 1.0, 3)}
    local = lagrange.sweep(model, until=5, grid=grid)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            remote = lagrange.sweep(model, until=5, grid=grid, client=client)
            many = lagrange.sweep(model, until=5, grid=grid, client=client, shards=5)
    assert remote == local
    assert many == local
    assert remote.csv.splitlines()[1:] == local.csv.splitlines()[1:]


class _Done:
    """A future that finished (or failed) at once."""

    def __init__(self, call):
        try:
            self._value, self._error = call(), None
        except Exception as e:  # noqa: BLE001 - the future keeps what the shard raised
            self._value, self._error = None, e

    def exception(self):
        return self._error

    def result(self):
        if self._error is not None:
            raise self._error
        return self._value


class _FlakyClient:
    """A client that runs shards here, and fails those in `failing` once."""

    def __init__(self, failing):
        self.failing = set(failing)
        self.submitted = []

    def scheduler_info(self):
        return {"workers": {"a": {}, "b": {}}}

    def submit(self, fn, *args, pure=True):
        shard = args[-1]["shard"][0]
        self.submitted.append(shard)

        def call():
            if shard in self.failing:
                self.failing.discard(shard)
                raise RuntimeError("the worker died")
            return fn(*args)

        return _Done(call)


def test_a_failed_shard_keeps_the_others_and_resumes_alone():
    model = lagrange.load(EXAMPLES / "double_pendulum.toml")
    grid = {"a": lagrange.grid(-3.0, 3.0, 8)}
    whole = lagrange.sweep(model, until=1, grid=grid, lyapunov=False)
    client = _FlakyClient(failing={1, 3})
    with pytest.raises(lagrange.ShardsFailed) as info:
        lagrange.sweep(model, until=1, grid=grid, lyapunov=False, client=client, shards=4)
    e = info.value
    assert "2 of 4 shards failed (1/4, 3/4; shard 1/4: RuntimeError: the worker died)" in str(e)
    assert sorted(e.shards) == [0, 2] and sorted(e.failed) == [1, 3]
    assert list(e.run.runs) == [0, 2, 4, 6]
    assert np.array_equal(e.run.data, whole.data[[0, 2, 4, 6]], equal_nan=True)
    client.submitted.clear()
    resumed = lagrange.sweep(model, until=1, grid=grid, lyapunov=False, client=client, resume=e)
    assert client.submitted == [1, 3]
    assert resumed == whole
    with pytest.raises(ValueError, match="the same model, settings, grid and options"):
        lagrange.sweep(model, until=2, grid=grid, lyapunov=False, client=client, resume=e)
