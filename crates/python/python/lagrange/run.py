"""A run: the trajectory as numpy arrays, the audit, and the summary.

``run.t`` (rows), ``run.q`` and ``run.qd`` (rows × coordinates), ``run.columns``
and ``run.data`` (the CSV's table), ``run.invariants`` (name → array),
``run.multipliers`` (constraint name → λ along the run), ``run.events`` (row,
condition) for crossings, ``run.section`` (a Poincaré section's points), ``run.summary`` (the ``lagrange.simulate/1`` dict),
``run.to_pandas()``. ``str(run)`` is the CLI's summary; in Jupyter a run
displays as the plot ``simulate --plot`` draws.
"""

from __future__ import annotations

import json
from typing import Any, Dict, List, Optional, Tuple

import numpy as np


class Run:
    """The result of :meth:`lagrange.Model.simulate`."""

    def __init__(self, model: Any, raw: Dict[str, Any]) -> None:
        self.model = model
        self.columns: List[str] = list(raw["columns"])
        rows = int(raw["rows"])
        self.data: np.ndarray = np.frombuffer(raw["data"], dtype="<f8").reshape(rows, len(self.columns))
        self.data.flags.writeable = False
        self.events: List[Tuple[int, str]] = [(int(i), str(c)) for i, c in raw["events"]]
        self.summary: Dict[str, Any] = json.loads(raw["summary"])
        self.summary_text: str = raw["summary_text"]
        self.failure: Optional[str] = raw["failure"]
        self.warnings: List[str] = list(raw["warnings"])
        self.coordinates: List[str] = list(model.coordinates)
        self._plot = raw["plot"]

    def __getstate__(self) -> Dict[str, Any]:
        # The plot travels drawn: the native keeper of its points stays here.
        state = dict(self.__dict__)
        state["_plot"] = _DrawnPlot(self._plot.svg())
        return state

    def __setstate__(self, state: Dict[str, Any]) -> None:
        self.__dict__.update(state)
        self.data.flags.writeable = False

    # --- the table ----------------------------------------------------------
    def __len__(self) -> int:
        return int(self.data.shape[0])

    def column(self, name: str) -> np.ndarray:
        """One column of the CSV table by its header name (``"th'"``, ``"H"``)."""
        try:
            return self.data[:, self.columns.index(name)]
        except ValueError:
            raise KeyError(f"no column {name!r}; columns: {', '.join(self.columns)}") from None

    def __getitem__(self, name: str) -> np.ndarray:
        return self.column(name)

    @property
    def t(self) -> np.ndarray:
        """The times of the rows."""
        return self.data[:, 0]

    @property
    def q(self) -> np.ndarray:
        """The coordinates, rows × coordinates."""
        n = len(self.coordinates)
        return self.data[:, 1 : 1 + n]

    @property
    def qd(self) -> np.ndarray:
        """The velocities, rows × coordinates."""
        n = len(self.coordinates)
        return self.data[:, 1 + n : 1 + 2 * n]

    @property
    def y(self) -> np.ndarray:
        """The state [q, q'] per row, rows × 2n (as ``solve_ivp``'s ``y.T``)."""
        n = len(self.coordinates)
        return self.data[:, 1 : 1 + 2 * n]

    @property
    def invariants(self) -> Dict[str, np.ndarray]:
        """The audited quantities (H, conserved momenta, ...) along the run."""
        return {name: self.column(name) for name in self.summary.get("invariants", {})}

    @property
    def multipliers(self) -> Dict[str, np.ndarray]:
        """The Lagrange multipliers λ of the constraints along the run."""
        return {c[len("lambda_"):]: self.column(c) for c in self.columns if c.startswith("lambda_")}

    @property
    def constraint_forces(self) -> Dict[str, np.ndarray]:
        """|Aᵀλ| per constraint along the run."""
        return {c[len("force_"):]: self.column(c) for c in self.columns if c.startswith("force_")}

    @property
    def section(self) -> Optional[np.ndarray]:
        """A Poincaré section's points in its plane (``simulate(section=...)``),
        rows × 2, the axes named by ``summary["section"]["axes"]``; None for
        a run without a section."""
        info = self.summary.get("section")
        if info is None:
            return None
        return np.column_stack([self.column(name) for name in info["axes"]])

    @property
    def final(self) -> Dict[str, float]:
        """The final state, ``{"th": .., "th'": ..}``."""
        return dict(self.summary["final"])

    def to_pandas(self) -> Any:
        """The table as a ``pandas.DataFrame`` (needs pandas), with an
        ``event`` column when the run recorded crossings."""
        import pandas as pd  # type: ignore[import-untyped,unused-ignore]

        frame = pd.DataFrame(np.array(self.data), columns=self.columns)
        if self.events:
            event = [""] * len(frame)
            for i, condition in self.events:
                event[i] = condition
            frame["event"] = event
        return frame

    # --- display ------------------------------------------------------------
    def __str__(self) -> str:
        return self.summary_text

    def __repr__(self) -> str:
        s = self.summary
        return f"<Run of {self.model.name!r}: {len(self)} rows to t = {s['t_final']}, method {s['method']}>"

    def _repr_pretty_(self, p: Any, cycle: bool) -> None:
        p.text(str(self))

    def svg(self) -> str:
        """The plot ``simulate --plot`` draws, as SVG text."""
        return str(self._plot.svg())

    def _repr_svg_(self) -> str:
        return self.svg()


class _DrawnPlot:
    """A run's plot as drawn before the run was pickled."""

    def __init__(self, svg: str) -> None:
        self._svg = svg

    def svg(self) -> str:
        return self._svg
