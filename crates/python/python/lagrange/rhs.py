"""A model's right-hand side and its Jacobian as SciPy's integrators call them.

``model.rhs()`` is ``f(t, y) -> dy/dt`` with ``y = [q, q']``: y of shape
``(2n,)`` gives an array of shape ``(2n,)``, y of shape ``(2n, k)`` (what
``solve_ivp(..., vectorized=True)`` passes) an array of shape ``(2n, k)``.
``model.jac()`` is ``J(t, y) = ∂f/∂y``, shape ``(2n, 2n)``, from the symbolic
derivatives, for the stiff methods (``solve_ivp(..., method="Radau",
jac=model.jac())``). Both are compiled once and pickle as their model.
"""

from __future__ import annotations

import operator
from typing import Any, Tuple

import numpy as np

_F8 = np.dtype("<f8")


class _Compiled:
    """What Rhs and Jac share: the model they came from (what they pickle as:
    the model's method ``_method`` called again), the compiled native
    function and the state's length 2n."""

    __slots__ = ("_model", "_native", "dim")
    _method = ""

    def __init__(self, model: Any, native: Any) -> None:
        self._model = model
        self._native = native
        self.dim: int = native.dim

    def __reduce__(self) -> Tuple[Any, Tuple[Any, ...]]:
        return (operator.methodcaller(self._method), (self._model,))


class Rhs(_Compiled):
    """``f(t, y) -> dy/dt``, compiled: see the module text."""

    __slots__ = ()
    _method = "rhs"

    def __call__(self, t: float, y: Any) -> np.ndarray:
        # Read and written as little-endian float64 bytes; the dtype object is
        # made once (numpy parses a dtype string on every call).
        if type(y) is not np.ndarray or y.dtype != _F8:
            y = np.asarray(y, dtype=_F8)
        if y.ndim == 1 and y.shape[0] == self.dim:
            return np.frombuffer(self._native.many(float(t), y.tobytes(), 1), dtype=_F8)
        if y.ndim == 2 and y.shape[0] == self.dim:
            k = y.shape[1]
            states = np.ascontiguousarray(y.T).tobytes()
            return np.frombuffer(self._native.many(float(t), states, k), dtype=_F8).reshape(k, self.dim).T
        raise ValueError(f"y has shape {y.shape}: give [q, q'] of length {self.dim}, or {self.dim} rows of states")

    def __repr__(self) -> str:
        return repr(self._native)


class Jac(_Compiled):
    """``J(t, y) = ∂f/∂y``, shape ``(2n, 2n)``, compiled: see the module text."""

    __slots__ = ()
    _method = "jac"

    def __call__(self, t: float, y: Any) -> np.ndarray:
        y = np.asarray(y, dtype=_F8)
        if y.shape != (self.dim,):
            raise ValueError(f"jac takes one state [q, q'] of shape ({self.dim},), not {y.shape}")
        out = self._native.eval(float(t), y.tobytes())
        return np.frombuffer(out, dtype=_F8).reshape(self.dim, self.dim)

    def __repr__(self) -> str:
        return f"<Jacobian of the right-hand side of {self._model.name}: {self.dim} × {self.dim}>"
