"""Expressions of the expression language as Python objects.

An :class:`Expr` prints as the language (``str(e)``), converts to SymPy
(``e.to_sympy()``), renders in Jupyter (``_repr_latex_``, with dots for
velocities) and evaluates, broadcasting over numpy arrays::

    >>> d.hamiltonian(ph=0.1, p_ph=[0.0, 0.5])        # doctest: +SKIP
    array([-9.76099..., -9.63599...])

Velocities and accelerations are named with primes (``"ph'"``); as keyword
arguments, where a prime cannot stand, write ``ph_dot`` and ``ph_ddot``, or
pass a dict: ``e({"ph'": 0.3})``. Parameters not given take the model's values.
"""

from __future__ import annotations

from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union, overload

import numpy as np

from . import _native

ArrayLike = Union[float, Sequence[float], np.ndarray]


def _name(key: str) -> str:
    """``ph_ddot`` → ``ph''``, ``ph_dot`` → ``ph'``, others unchanged."""
    if key.endswith("_ddot"):
        return key[: -len("_ddot")] + "''"
    if key.endswith("_dot"):
        return key[: -len("_dot")] + "'"
    return key


class Expr:
    """An expression of the expression language, tied to its model (for the
    parameters' values and the names of the coordinates).

    It prints (``str``, ``latex()``), evaluates (``e(th=0.1, th_dot=2.0)``)
    and converts (``to_sympy()``). It has no arithmetic or ``diff`` of its
    own: for algebra, go through SymPy, ``e.to_sympy().diff(...)``, and back
    with ``lagrange.expression(str(result))`` where a string is wanted."""

    __slots__ = ("_text", "_model", "_coordinates")

    def __init__(self, text: str, model: Any = None, coordinates: Sequence[str] = ()) -> None:
        self._text = text
        self._model = model
        self._coordinates = tuple(coordinates)

    # --- printing -------------------------------------------------------
    def __str__(self) -> str:
        return self._text

    def __repr__(self) -> str:
        return f"Expr({self._text!r})"

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Expr):
            return self._text == other._text
        if isinstance(other, str):
            return self._text == other
        return NotImplemented

    def __hash__(self) -> int:
        return hash(self._text)

    def latex(self) -> str:
        """The expression as LaTeX math (no surrounding ``$``)."""
        return _native.latex(self._text)

    def _repr_latex_(self) -> str:
        return f"${self.latex()}$"

    # --- SymPy ----------------------------------------------------------
    def to_sympy(self, dynamic: bool = True) -> Any:
        """The expression in SymPy.

        With ``dynamic`` (the default) coordinates are functions of time as
        ``sympy.physics.mechanics.dynamicsymbols`` makes them, ``th(t)``, and
        velocities their derivatives; otherwise every name is a plain
        ``Symbol`` (``th``, ``th'``). Momenta ``p_th``, parameters and ``t``
        are symbols either way. Numbers stay exact: ``1/2`` is
        ``Rational(1, 2)``.
        """
        from .sympy_bridge import to_sympy

        return to_sympy(_native.tree(self._text), self._coordinates, dynamic)

    # --- values ---------------------------------------------------------
    def __call__(self, values: Optional[Mapping[str, ArrayLike]] = None, **kwargs: ArrayLike) -> Union[float, np.ndarray]:
        """The value at the given coordinates, velocities, momenta, t and
        parameters (a float; an array where arrays are given, broadcast as
        numpy's arithmetic does)."""
        given: Dict[str, Any] = {}
        for key, v in (values or {}).items():
            given[key] = v
        for key, v in kwargs.items():
            given[_name(key)] = v
        if self._model is None:
            raise ValueError("this expression has no model to evaluate with")
        names = list(given)
        arrays = np.broadcast_arrays(*[np.asarray(given[n], dtype=np.float64) for n in names]) if names else []
        shape: Tuple[int, ...] = arrays[0].shape if names else ()
        count = int(np.prod(shape)) if shape else 1
        columns = [np.ascontiguousarray(a, dtype="<f8").ravel().tobytes() for a in arrays]
        out = np.frombuffer(self._model._native.evaluate(self._text, names, columns, count), dtype="<f8")
        if not shape:
            return float(out[0])
        return out.reshape(shape).copy()


class Matrix:
    """A matrix of expressions (the mass matrix M): rows of :class:`Expr`."""

    __slots__ = ("rows",)

    def __init__(self, rows: Sequence[Sequence[Expr]]) -> None:
        self.rows = [list(r) for r in rows]

    @overload
    def __getitem__(self, ij: Tuple[int, int]) -> Expr: ...

    @overload
    def __getitem__(self, ij: int) -> List[Expr]: ...

    def __getitem__(self, ij: Union[int, Tuple[int, int]]) -> Union[Expr, List[Expr]]:
        """``m[i, j]`` is an entry and ``m[i]`` a row, as iterating gives rows."""
        if isinstance(ij, tuple):
            if len(ij) != 2:
                raise IndexError(f"a matrix takes two indices, m[i, j], not {len(ij)}")
            i, j = ij
            return self.rows[i][j]
        if isinstance(ij, slice):
            raise TypeError("a matrix is indexed by m[i, j] (an entry) or m[i] (a row), not by a slice")
        return list(self.rows[ij])

    def __len__(self) -> int:
        return len(self.rows)

    def __iter__(self) -> Any:
        return iter(self.rows)

    def __str__(self) -> str:
        return "[" + ", ".join("[" + ", ".join(str(e) for e in r) + "]" for r in self.rows) + "]"

    __repr__ = __str__

    @property
    def shape(self) -> Tuple[int, int]:
        return (len(self.rows), len(self.rows[0]) if self.rows else 0)

    def to_sympy(self, dynamic: bool = True) -> Any:
        """The matrix as a ``sympy.Matrix``."""
        import sympy  # type: ignore[import-untyped,unused-ignore]

        return sympy.Matrix([[e.to_sympy(dynamic) for e in r] for r in self.rows])

    def __call__(self, values: Optional[Mapping[str, ArrayLike]] = None, **kwargs: ArrayLike) -> np.ndarray:
        """The numeric matrix at a point (scalars only)."""
        return np.array([[float(e(values, **kwargs)) for e in r] for r in self.rows])

    def __array__(self, dtype: Any = None, copy: Any = None) -> np.ndarray:
        """``np.array(d.mass_matrix)``: the numbers, where every entry is
        constant or a function of the parameters alone (their values in the
        model); a matrix of the coordinates needs them: ``d.mass_matrix(th=0.3)``."""
        try:
            values = self()
        except ValueError as e:
            raise TypeError(
                f"the matrix depends on more than the parameters ({e}); evaluate it at a state first, "
                "e.g. np.array(d.mass_matrix(th=0.3))"
            ) from None
        return values if dtype is None else values.astype(dtype)

    def _repr_latex_(self) -> str:
        body = r" \\ ".join(" & ".join(e.latex() for e in r) for r in self.rows)
        return r"$\begin{pmatrix}" + body + r"\end{pmatrix}$"
