"""Model files written from Python values, for ``lagrange.Model(...)``.

Only what model files hold: strings (expressions), numbers, arrays, tables
and arrays of tables. SymPy expressions are printed in the expression
language first (:func:`lagrange.sympy_bridge.from_sympy`).
"""

from __future__ import annotations

import json
import math
from numbers import Number
from typing import Any, Dict, List, Mapping, Sequence, Tuple

from .sympy_bridge import from_sympy, is_sympy


def expression(value: Any) -> str:
    """An expression as text: a string as it is, a SymPy object printed, a
    number as its shortest exact decimal."""
    if isinstance(value, str):
        return value
    if is_sympy(value):
        return from_sympy(value)
    if isinstance(value, bool):
        raise TypeError(f"expected an expression, not {value!r}")
    if isinstance(value, Number):
        return _number(value)
    raise TypeError(f"expected an expression (a string or a SymPy expression), not {type(value).__name__}")


def name(value: Any) -> str:
    """A name: a string, or a SymPy symbol or dynamic symbol (``th(t)``)."""
    if isinstance(value, str):
        return value
    if is_sympy(value):
        return from_sympy(value)
    raise TypeError(f"expected a name, not {value!r}")


def _number(value: Any) -> str:
    x = float(value)
    if not math.isfinite(x):
        raise ValueError(f"a model holds finite numbers, not {x}")
    return repr(int(value)) if isinstance(value, int) else repr(x)


def _value(v: Any) -> str:
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, Number) and not is_sympy(v):
        return _number(v)
    return json.dumps(expression(v), ensure_ascii=False)


def _key(k: Any) -> str:
    return json.dumps(name(k), ensure_ascii=False)


def model(
    *,
    name_: str,
    coordinates: Sequence[Any],
    parameters: Mapping[Any, Any],
    top: Mapping[str, Any],
    tables: Mapping[str, Mapping[Any, Any]],
    arrays: Mapping[str, Sequence[Mapping[str, Any]]],
) -> Tuple[str, List[str]]:
    """The TOML text of a model (top-level keys, then tables, then arrays of
    tables), and for each of its lines the Python argument it came from
    (``potential=``, ``parameters["g"]``, ``particles[0]["position"]``; empty
    for headers), so that an error in the text can name the argument."""
    lines: List[str] = [f"name = {json.dumps(name_, ensure_ascii=False)}"]
    origins: List[str] = ["name="]
    lines.append("coordinates = [" + ", ".join(json.dumps(name(c), ensure_ascii=False) for c in coordinates) + "]")
    origins.append("coordinates=")
    for key, v in top.items():
        if v is not None:
            lines.append(f"{key} = {_value(v)}")
            origins.append(f"{key}=")
    sections: Dict[str, Mapping[Any, Any]] = {"parameters": parameters, **tables}
    for table, entries in sections.items():
        if entries:
            lines += ["", f"[{table}]"]
            origins += ["", f"{table}="]
            for k, v in entries.items():
                lines.append(f"{_key(k)} = {_number(v) if table == 'parameters' else _value(v)}")
                origins.append(f"{table}[{name(k)!r}]")
    for table, items in arrays.items():
        for i, item in enumerate(items or ()):
            lines += ["", f"[[{table}]]"]
            origins += ["", f"{table}[{i}]"]
            for k, v in item.items():
                if v is not None:
                    lines.append(f"{k} = {_value(v)}")
                    origins.append(f"{table}[{i}][{k!r}]")
    return "\n".join(lines) + "\n", origins
