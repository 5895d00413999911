"""The derivation of a model, as the ``lagrange.derive/1`` report.

Fields are named as in ``lagrange derive --format json`` (``lagrange.derive/1``): ``d.lagrangian``,
``d.momenta["th"]``, ``d.equations``, ``d.mass_matrix``, ``d.forcing``,
``d.hamiltonian``, ``d.hamilton["th"]["dp"]``, ``d.cyclic``, ``d.conserved``,
``d.hamiltonian_is_energy``, ``d.explanations``... Every expression is an
:class:`~lagrange.expr.Expr`. ``str(d)`` is the CLI's text, and in Jupyter a
derivation displays as typeset equations.
"""

from __future__ import annotations

import json
import re
from typing import TYPE_CHECKING, Any, Dict, List, Optional

from .expr import Expr, Matrix

# Which fields of the report hold expressions, and in which shape.
_SCALAR = {"lagrangian", "kinetic", "potential", "dissipation", "hamiltonian", "energy", "energy_function",
           "expr", "integral", "time_term", "dq", "dp"}
_LISTS = {"forcing", "jacobian", "angular_momentum", "angular_velocity"}
_DICTS = {"momenta", "equations", "velocities", "multiplier_equations", "constraint_forces", "forces"}
_MATRICES = {"mass_matrix", "cartesian_constraint_forces"}


def _convert(key: str, value: Any, make: Any) -> Any:
    if value is None:
        return None
    if key in _SCALAR and isinstance(value, str):
        return make(value)
    if key in _LISTS and isinstance(value, list):
        return [make(v) for v in value]
    if key in _DICTS and isinstance(value, dict):
        return {k: make(v) if isinstance(v, str) else _walk(v, make) for k, v in value.items()}
    if key in _MATRICES and isinstance(value, list):
        return Matrix([[make(v) for v in row] for row in value])
    return _walk(value, make)


def _walk(value: Any, make: Any) -> Any:
    if isinstance(value, dict):
        return {k: _convert(k, v, make) for k, v in value.items()}
    if isinstance(value, list):
        return [_walk(v, make) for v in value]
    return value


class Derivation:
    """Everything ``lagrange derive`` reports about a model.

    Attributes follow ``lagrange.derive/1``; ``json`` is the report as a dict
    of plain values (expressions as strings), ``model`` the model.
    """

    # What mypy sees of the report's main fields (the values come from
    # __getattr__; a field a model does not have is None).
    if TYPE_CHECKING:
        lagrangian: Optional[Expr]
        kinetic: Optional[Expr]
        potential: Optional[Expr]
        dissipation: Optional[Expr]
        hamiltonian: Optional[Expr]
        energy: Optional[Expr]
        energy_function: Expr
        momenta: Dict[str, Expr]
        equations: Dict[str, Expr]
        mass_matrix: Matrix
        forcing: List[Expr]
        coordinates: List[str]
        hamiltonian_is_energy: Optional[bool]

    def __init__(self, model: Any) -> None:
        self.model = model
        self.json: Dict[str, Any] = json.loads(model._native.derive_json())
        coords = self.json.get("coordinates", [])

        def make(text: str) -> Expr:
            return Expr(text, model, coords)

        self._fields = {k: _convert(k, v, make) for k, v in self.json.items()}

    def __reduce__(self) -> Any:
        # Pickled as its model, derived again where it is unpickled.
        return (Derivation, (self.model,))

    def __getattr__(self, name: str) -> Any:
        fields = self.__dict__.get("_fields", {})
        if name in fields:
            return fields[name]
        raise AttributeError(f"a derivation has no field {name!r}; fields: {', '.join(sorted(fields))}")

    def __dir__(self) -> List[str]:
        return sorted(set(super().__dir__()) | set(self._fields))

    def keys(self) -> List[str]:
        """The report's field names."""
        return list(self._fields)

    def __getitem__(self, name: str) -> Any:
        return self._fields[name]

    @property
    def conserved_quantities(self) -> Dict[str, Expr]:
        """The conserved quantities by name (``{"p_th": Expr, "H": Expr}``)."""
        return {c["name"]: c["expr"] for c in self._fields.get("conserved", [])}

    def __str__(self) -> str:
        return str(self.model._native.text())

    def __repr__(self) -> str:
        return f"<Derivation of {self.json.get('name')!r}: coordinates {', '.join(self.json.get('coordinates', []))}>"

    def latex(self) -> str:
        """The derivation as LaTeX (``align*`` blocks), as ``derive --format latex``."""
        return str(self.model._native.latex())

    def _repr_latex_(self) -> str:
        # Each `align*` block as `$$\begin{aligned}...$$`, which MathJax and
        # KaTeX both typeset; comments (the CLI's first line, the labels of
        # equations) are dropped: not every notebook renderer reads them.
        lines = [re.sub(r"(?<!\\)%.*$", "", line).rstrip() for line in self.latex().splitlines()]
        text = "\n".join(line for line in lines if line)
        return text.replace("\\begin{align*}", "$$\\begin{aligned}").replace("\\end{align*}", "\\end{aligned}$$")

    def _repr_pretty_(self, p: Any, cycle: bool) -> None:
        p.text(str(self))


