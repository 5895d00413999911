"""Objects that travel: a model, its derivation, an expression, a run, a sweep's
table, a compiled right-hand side and its Jacobian pickle (a model as its text, settings and
folder, derived again where it lands; results as their data), so that
multiprocessing and a Dask cluster of processes take them as arguments and
give them back."""

from __future__ import annotations

import multiprocessing
import operator
import pickle

import numpy as np
import pytest

import lagrange
from conftest import EXAMPLES


def again(x):
    return pickle.loads(pickle.dumps(x))


@pytest.fixture(scope="module")
def model():
    return lagrange.load(EXAMPLES / "double_pendulum.toml", set={"g": 1.62})


def test_a_model_and_what_it_gives_pickle(model):
    copy = again(model)
    assert copy.parameters == model.parameters and copy.parameters["g"] == 1.62
    assert copy.source == model.source and copy.file == model.file
    assert copy.simulate(until=1).final == model.simulate(until=1).final
    d = again(model.derive())
    assert str(d.hamiltonian) == str(model.derive().hamiltonian)
    h = again(model.derive().hamiltonian)
    assert h(a=0.1, b=0.2, p_a=0.3, p_b=0.4) == model.derive().hamiltonian(a=0.1, b=0.2, p_a=0.3, p_b=0.4)
    run = model.simulate(until=1)
    moved = again(run)
    assert np.array_equal(moved.data, run.data) and moved.final == run.final and moved.summary == run.summary
    assert moved.svg() == run.svg()
    table = lagrange.sweep(model, until=0.5, grid={"a": [0.0, 1.0]}, lyapunov=False, threads=1)
    assert again(table) == table
    f = model.rhs()
    y = [0.3, -0.2, 0.1, 0.5]
    assert np.array_equal(again(f)(0.0, y), f(0.0, y))
    jac = model.jac()
    assert np.array_equal(again(jac)(0.0, y), jac(0.0, y))


def test_a_model_built_in_python_pickles_with_its_settings():
    oscillator = lagrange.Model(
        coordinates=["x"], parameters={"m": 2.0, "k": 8.0}, lagrangian="m*x'^2/2 - k*x^2/2",
        initial={"x": 1.0, "x'": 0.0}, set={"k": 2.0},
    )
    copy = again(oscillator)
    assert copy.parameters == {"m": 2.0, "k": 2.0}
    assert copy.simulate(until=1).final == oscillator.simulate(until=1).final


def test_multiprocessing_takes_models_and_gives_runs_back(model):
    models = [model, model.with_parameters(g=9.81)]
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        runs = pool.map(operator.methodcaller("simulate", until=1.0), models)
    for m, run in zip(models, runs):
        assert run.final == m.simulate(until=1.0).final


def test_a_dask_cluster_of_processes_takes_a_model_as_an_argument(model):
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            run = client.submit(lambda m: m.simulate(until=1.0), model).result()
            value = client.submit(lambda d: d.hamiltonian(a=0.1, b=0.2, p_a=0.0, p_b=0.0), model.derive()).result()
    assert run.final == model.simulate(until=1.0).final
    assert value == model.derive().hamiltonian(a=0.1, b=0.2, p_a=0.0, p_b=0.0)
