"""The analyses' results: normal modes, orbits, tops, inertia tensors and
extremals. Each is a :class:`Report`: its fields are the JSON contract's
(``modes.frequencies``, ``orbit.eccentricity``, ``inertia.tensor``...), with
vectors and matrices as numpy arrays; ``report.json`` is the dict, and
``str(report)`` the CLI's text, and in Jupyter a report displays as the
figure the CLI draws for it.
"""

from __future__ import annotations

import json
from typing import Any, Dict, List, Optional

import numpy as np


def _array(value: Any) -> Any:
    """Lists of numbers (and lists of such lists) become numpy arrays."""
    if isinstance(value, list) and value and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
        return np.array(value, dtype=float)
    if isinstance(value, list) and value and all(isinstance(v, list) for v in value):
        rows = [_array(v) for v in value]
        if all(isinstance(r, np.ndarray) and r.shape == rows[0].shape for r in rows):
            return np.array(rows)
        return rows
    if isinstance(value, dict):
        return {k: _array(v) for k, v in value.items()}
    return value


class Report:
    """A report of an analysis: attributes named as in its JSON contract."""

    def __init__(self, json_text: str, text: str, figure: Optional[str] = None) -> None:
        self.json: Dict[str, Any] = json.loads(json_text)
        self.text = text
        self.figure = figure
        self._fields = {k: _array(v) for k, v in self.json.items()}

    def __getattr__(self, name: str) -> Any:
        fields = self.__dict__.get("_fields", {})
        if name in fields:
            return fields[name]
        raise AttributeError(f"{self.json.get('format', 'the report')} has no field {name!r}; fields: {', '.join(sorted(fields))}")

    def __getitem__(self, name: str) -> Any:
        return self._fields[name]

    def __dir__(self) -> List[str]:
        return sorted(set(super().__dir__()) | set(self._fields))

    def keys(self) -> List[str]:
        """The report's field names."""
        return list(self._fields)

    def __str__(self) -> str:
        return self.text

    def __repr__(self) -> str:
        what = self.json.get("format", "report")
        name = self.json.get("name")
        of = f" of {name!r}" if name else ""
        fields = ", ".join(k for k in self._fields if k not in ("format", "name"))
        return f"<Report {what}{of}: {fields}; print() it for the text>"

    def _repr_pretty_(self, p: Any, cycle: bool) -> None:
        p.text(self.text)

    def svg(self) -> Optional[str]:
        """The figure the CLI draws for this analysis (``orbit --plot``,
        ``top --plot``, ``extremal --plot``, ``modes --animate``) as SVG text,
        or None where it has none."""
        return self.figure

    def _repr_svg_(self) -> Optional[str]:
        return self.figure
