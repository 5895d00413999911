"""Sweeps on a Dask cluster: the rows equal a one-process sweep's exactly."""

from __future__ import annotations

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
