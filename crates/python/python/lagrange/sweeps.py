"""Sweeps: a grid of runs, here or on a Dask cluster.

``lagrange.sweep(model, until=20, grid={"a": lagrange.grid(-3.1, 3.1, 100)})``
runs the grid on this machine's cores. With ``client=`` (a ``dask.distributed.Client``)
the grid is cut into shards, the CLI's ``--shard i/n``, which the cluster's
workers run; their tables are merged into the one a single process computes,
bit for bit.
"""

from __future__ import annotations

from typing import Any, Dict, List, Mapping, NamedTuple, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native
from .errors import Interrupted, LagrangeError, RunError


class Linspace(NamedTuple):
    """An axis of a sweep's grid: ``num`` values evenly spaced from
    ``start`` to ``stop``, both included (the CLI's ``NAME=START:STOP:COUNT``).
    Made by :func:`grid`; a plain tuple ``(start, stop, count)`` means the same."""

    start: float
    stop: float
    num: int


def grid(start: float, stop: float, num: int) -> Linspace:
    """``num`` values evenly spaced from ``start`` to ``stop``, both
    included (as ``numpy.linspace``), as an axis of :func:`sweep`'s ``grid``:
    ``grid={"a": lagrange.grid(-3, 3, 100)}``. A list or array is the values
    themselves: ``grid={"g": [1.62, 3.71, 9.81]}``."""
    return Linspace(float(start), float(stop), int(num))


#: An axis: a :class:`Linspace` (or a tuple ``(start, stop, count)``), or the
#: values themselves as a list or array (or one number).
Axis = Union[Linspace, Tuple[float, float, int], Sequence[float], np.ndarray, float]


class Table:
    """A sweep's table: one row per run of the grid, in run order.

    ``columns`` (the numeric columns: the grid's names, ``t_final``,
    ``final_<q>``, ``final_<q>'``, ``energy_drift``, ``lyapunov``), ``data``
    (runs × columns), ``runs`` (run indices), ``failures`` (per row, empty
    when the run did not fail), ``meta`` (provenance), ``csv`` (the CLI's
    file). ``table["lyapunov"]`` is a column; ``to_pandas()`` a DataFrame.
    """

    def __init__(self, csv: str, name: str = "sweep") -> None:
        raw = _native.table(csv, name)
        self.csv = csv
        self._name = name
        self.meta: Dict[str, str] = dict(raw["meta"])
        self.columns: List[str] = list(raw["columns"])
        self.runs = np.array(raw["runs"], dtype=np.int64)
        self.data = np.frombuffer(raw["data"], dtype="<f8").reshape(len(self.runs), len(self.columns))
        self.data.flags.writeable = False
        self.failures: List[str] = list(raw["failures"])

    def __len__(self) -> int:
        return len(self.runs)

    def __reduce__(self) -> Any:
        # Pickled as its CSV, read again where it is unpickled.
        return (Table, (self.csv, self._name))

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.data[:, self.columns.index(name)]
        except ValueError:
            raise KeyError(f"no column {name!r}; columns: {', '.join(self.columns)}") from None

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Table):
            return NotImplemented
        return (self.columns == other.columns and np.array_equal(self.runs, other.runs)
                and np.array_equal(self.data, other.data, equal_nan=True) and self.failures == other.failures)

    def grid(self) -> Dict[str, np.ndarray]:
        """The grid's values per run, by axis name."""
        return {k: self[k] for k in self.columns[: self.columns.index("t_final")]}

    def to_pandas(self) -> Any:
        """The table as a ``pandas.DataFrame`` indexed by run."""
        import pandas as pd  # type: ignore[import-untyped,unused-ignore]

        frame = pd.DataFrame(np.array(self.data), columns=self.columns, index=pd.Index(self.runs, name="run"))
        frame["failure"] = self.failures
        return frame

    def __repr__(self) -> str:
        return f"<Table of {len(self)} runs: {self.meta.get('model', '')!s}, grid {self.meta.get('grid', '')}>"


def grid_spec(grid: Union[str, Mapping[str, Axis]]) -> str:
    """The CLI's ``--grid`` text of a grid: a tuple (a :class:`Linspace`) is
    ``(start, stop, count)``, ``NAME=START:STOP:COUNT``; a list, an array or a
    number is the values themselves, ``NAME=V1;V2;...``."""
    if isinstance(grid, str):
        return grid
    parts = []
    for name, axis in grid.items():
        if isinstance(axis, tuple):
            if len(axis) != 3:
                raise ValueError(
                    f"grid[{name!r}]: a tuple is (start, stop, count), not {axis!r}; "
                    "give the values themselves as a list or an array"
                )
            start, stop, count = axis
            if int(count) != count or count < 1:
                raise ValueError(f"grid[{name!r}]: the count must be a whole number of at least 1, not {count!r}")
            parts.append(f"{name}={float(start)!r}:{float(stop)!r}:{int(count)}")
            continue
        try:
            values = np.asarray(axis, dtype=float).reshape(-1) if np.ndim(axis) <= 1 else None
        except (TypeError, ValueError):
            values = None
        if values is None or values.size == 0:
            raise ValueError(f"grid[{name!r}]: expected values (a list or an array of numbers) or lagrange.grid(start, stop, count), not {axis!r}")
        if not np.all(np.isfinite(values)):
            raise ValueError(f"grid[{name!r}]: every value must be a finite number, not {axis!r}")
        parts.append(f"{name}=" + ";".join(repr(float(v)) for v in values))
    return ",".join(parts)


def _options(until: float, grid: str, method: Optional[str], rtol: Optional[float], atol: Optional[float],
             lyapunov: bool, threads: Optional[int], shard: Optional[Tuple[int, int]]) -> Dict[str, Any]:
    return {"grid": grid, "until": float(until), "method": method, "rtol": rtol, "atol": atol,
            "lyapunov": bool(lyapunov), "shard": shard, "threads": threads}


def _run_shard(source: str, file: str, set: Dict[str, float], folder: Optional[str], options: Dict[str, Any]) -> str:
    """One shard on a worker: the model is derived there from its text."""
    native = _native.from_toml(source, file, set, folder)
    out = native.sweep(options)
    if out["interrupt"] is not None:
        raise out["interrupt"]
    return str(out["csv"])


def sweep(
    model: Any,
    until: float,
    grid: Union[str, Mapping[str, Axis]],
    *,
    method: Optional[str] = None,
    rtol: Optional[float] = None,
    atol: Optional[float] = None,
    lyapunov: bool = True,
    threads: Optional[int] = None,
    shard: Optional[Tuple[int, int]] = None,
    client: Any = None,
    shards: Optional[int] = None,
    resume: Optional["ShardsFailed"] = None,
) -> Table:
    """Runs ``model`` from every point of ``grid`` to ``until``, as ``lagrange
    sweep`` does: the final state, the drift of the energy and (unless
    ``lyapunov=False``) the largest Lyapunov exponent per run.

    ``grid``: ``{"a": lagrange.grid(start, stop, num), "g": [1.62, 9.81]}``
    over initial coordinates (``"a"``), velocities (``"a'"``) and
    parameters: :func:`grid` (or a tuple ``(start, stop, num)``) spaces
    ``num`` values evenly; a list or an array is the values themselves. The
    first axis varies slowest. ``shard=(i, n)``: only runs i, i+n, i+2n, ... (the CLI's
    ``--shard i/n``). ``threads``: worker threads here (default: one per core).

    ``client``: a ``dask.distributed.Client``. The grid is cut into
    ``shards`` parts (default: one per worker), each run on a worker with all
    its cores, and the tables merged; the result equals a one-process sweep's.
    Files a model names (body files) must be readable at the same path on the
    workers. Shards that fail raise :class:`lagrange.ShardsFailed`, which
    keeps the runs of the shards that finished; ``resume=`` that exception
    runs only the failed shards.

    Runs that fail (blow up, meet a singular mass matrix) have NaN and their
    reason in ``failures``; when every run fails, the sweep found nothing and
    raises :class:`lagrange.RunError` with the first run's reason, its
    ``.run`` the table all the same (``lagrange sweep`` exits 1).

    Ctrl-C stops a local sweep and raises :class:`lagrange.Interrupted` holding
    the runs finished so far, in grid order.
    """
    spec = grid_spec(grid)
    if client is None:
        out = model._native.sweep(_options(until, spec, method, rtol, atol, lyapunov, threads, shard))
        table = Table(out["csv"])
        if out["interrupt"] is not None:
            raise Interrupted(f"interrupted after {len(table)} runs; the exception's .run keeps them", table) from out["interrupt"]
        return _found(table)
    if shard is not None:
        raise ValueError("give either shard= (one part, here) or client= (every part, on the cluster)")
    options = _options(until, spec, method, rtol, atol, lyapunov, threads, None)
    sweep_of = (model.source, model.file, dict(model._set), model._folder, options)
    done: Dict[int, str] = {}
    if resume is not None:
        if not isinstance(resume, ShardsFailed):
            raise TypeError(f"resume= takes the lagrange.ShardsFailed a sweep raised, not {type(resume).__name__}")
        if resume.sweep_of != sweep_of:
            raise ValueError("resume= continues the same sweep: the same model, settings, grid and options")
        if shards is not None and shards != resume.count:
            raise ValueError(f"resume= continues a sweep of {resume.count} shards, not {shards}")
        n, done = resume.count, dict(resume.shards)
    else:
        n = shards if shards is not None else max(1, len(client.scheduler_info().get("workers", {})))
    if n < 1:
        raise ValueError(f"shards must be at least 1, not {n}")
    futures = {
        i: client.submit(_run_shard, model.source, model.file, model._set, model._folder,
                         {**options, "shard": (i, n)}, pure=False)
        for i in range(n)
        if i not in done
    }
    failed: Dict[int, BaseException] = {}
    for i, future in futures.items():
        error = future.exception()
        if error is None:
            done[i] = future.result()
        else:
            failed[i] = error
    if failed:
        raise ShardsFailed(sweep_of, n, done, failed)
    merged = _native.merge([(f"shard {i}/{n}", done[i]) for i in range(n)])
    return _found(Table(merged))


def _found(table: Table) -> Table:
    """``table``, unless every run of it failed: then :class:`RunError` with
    the first run's reason, as ``lagrange sweep`` exits 1 with it."""
    if len(table) and all(table.failures):
        raise RunError(
            f"every run failed ({len(table)}); the first, run {table.runs[0]}: {table.failures[0]}", run=table
        )
    return table


class ShardsFailed(LagrangeError):
    """Shards of a sweep on a cluster failed (a worker died, a file a worker
    could not read). ``run`` is a :class:`Table` of the runs of the shards
    that finished, in grid order; ``shards`` their CSVs by shard index;
    ``failed`` the exceptions by shard index. ``lagrange.sweep(..., client=,
    resume=e)`` runs only the failed shards and merges them with the rest."""

    def __init__(self, sweep_of: Any, count: int, shards: Dict[int, str], failed: Dict[int, BaseException]) -> None:
        self.sweep_of = sweep_of
        self.count = count
        self.shards = shards
        self.failed = failed
        self.run = _partial(shards)
        which = ", ".join(f"{i}/{count}" for i in sorted(failed))
        first = failed[min(failed)]
        super().__init__(
            f"{len(failed)} of {count} shards failed ({which}; shard {min(failed)}/{count}: "
            f"{type(first).__name__}: {first}); the exception's .run keeps the {len(self.run)} runs of the "
            f"{len(shards)} that finished; lagrange.sweep(..., client=client, resume=e) runs only the failed ones"
        )


def _partial(shards: Dict[int, str]) -> Table:
    """The runs of some shards as one table in grid order (empty without any)."""
    if not shards:
        return Table("# lagrange sweep; partial\nrun,t_final,failure\n")
    texts = [shards[i] for i in sorted(shards)]
    lines = texts[0].splitlines()
    header = [line for line in lines if line.startswith("#")] + [next(line for line in lines if line.startswith("run,"))]
    rows = [line for text in texts for line in text.splitlines()[len(header):] if line]
    rows.sort(key=lambda line: int(line.split(",", 1)[0]))
    return Table("\n".join(header + rows) + "\n")
