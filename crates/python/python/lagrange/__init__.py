"""lagrange: analytical mechanics from a model, in Python.

Write a mechanical system once (coordinates, parameters, particles or a
Lagrangian, dissipation, constraints, rigid bodies) and get its equations of
motion derived symbolically, its motion integrated with an audit of every
conserved quantity, and the analyses of a mechanics course::

    import lagrange
    model = lagrange.load("double_pendulum.toml")   # a model file
    d = model.derive()              # momenta, equations, M, f, H, ...
    d.hamiltonian.to_sympy()
    run = model.simulate(until=20)  # run.t, run.q, run.qd: numpy arrays
    f = model.rhs()                 # for scipy.integrate.solve_ivp

The package is the Rust library behind the ``lagrange`` command line; results
mirror its JSON output field for field (the guide's chapter "Python"
and the reports' formats, ``lagrange.derive/1`` and the others).
"""

import typing as _t

from . import _native
from .analyses import Report
from .derivation import Derivation
from .errors import Interrupted, LagrangeError, ModelError, RunError
from .expr import Expr, Matrix
from .model import Model, Page, PathLike, _existing, load
from .run import Run
from .sweeps import Linspace, ShardsFailed, Table, grid, sweep

__version__: str = _native.VERSION

__all__ = [
    "Derivation", "Expr", "Interrupted", "LagrangeError", "Linspace", "Matrix", "Model", "ModelError", "Page", "Report",
    "Run", "RunError", "ShardsFailed", "Table", "expression", "extremal", "grid", "inertia", "load", "methods", "sweep",
]


def methods() -> _t.List[_t.Tuple[str, str]]:
    """The integrators ``simulate(method=...)`` takes: (name, description)."""
    return list(_native.METHODS)


def expression(text: str) -> Expr:
    """An expression of the expression language (checked, printed in normal
    form), for LaTeX or SymPy: ``lagrange.expression("m*l^2*th'^2/2")``."""
    return Expr(_native.check(text))


def inertia(
    path: _t.Optional[PathLike] = None,
    *,
    text: _t.Optional[str] = None,
    set: _t.Optional[_t.Mapping[str, float]] = None,
    about: str = "com",
) -> Report:
    """The mass properties of a body file (``lagrange inertia``): mass,
    centre of mass, the inertia tensor about ``about`` (``"com"``, or a point
    ``"x,y,z"`` of expressions in the parameters, as the CLI's ``--about``) and its principal axes.
    Give the file's ``path``, or its ``text``."""
    p = None if path is None else _existing(path)
    return Report(*_native.inertia(p, text, {k: float(v) for k, v in (set or {}).items()}, about))


def extremal(
    path: _t.Optional[PathLike] = None,
    *,
    text: _t.Optional[str] = None,
    set: _t.Optional[_t.Mapping[str, float]] = None,
    check_minimum: bool = False,
    points: int = 201,
) -> Report:
    """The extremal of a variational problem file (``lagrange extremal``):
    the Euler–Lagrange equation, its first integral, the path and the value."""
    p = None if path is None else _existing(path)
    return Report(*_native.extremal(p, text, {k: float(v) for k, v in (set or {}).items()}, check_minimum, points))
