"""Between SymPy and the expression language.

``to_sympy`` builds SymPy objects from the tree the extension gives
(``_native.tree``). ``from_sympy`` prints a SymPy expression in the
expression language, so that a SymPy user can hand lagrange an existing model:
``dynamicsymbols`` (``th(t)``) become coordinates, their time derivatives
velocities and accelerations (``th'``, ``th''``), ``Rational`` stays exact.
"""

from __future__ import annotations

import sys
from typing import Any, Sequence

_FUNCTIONS = ("sin", "cos", "tan", "asin", "acos", "atan", "sinh", "cosh", "tanh", "exp", "log", "sqrt", "abs")


def to_sympy(tree: Any, coordinates: Sequence[str], dynamic: bool) -> Any:
    """A SymPy expression from a tree of ``_native.tree``."""
    import sympy  # type: ignore[import-untyped,unused-ignore]

    t = sympy.Symbol("t")
    coords = set(coordinates)

    def symbol(name: str, order: int) -> Any:
        if dynamic and (name in coords or order > 0):
            f = sympy.Function(name)(t)
            return f if order == 0 else sympy.Derivative(f, (t, order))
        if name == "t" and order == 0:
            return t
        return sympy.Symbol(name + "'" * order)

    def build(node: Any) -> Any:
        kind = node[0]
        if kind == "num":
            text = node[1]
            # Rationals (`1/2`) stay exact; a float keeps its 53 bits.
            return sympy.Rational(text) if "e" not in text and "." not in text else sympy.Float(text, precision=53)
        if kind == "pi":
            return sympy.pi
        if kind == "sym":
            return symbol(node[1], node[2])
        if kind == "add":
            return sympy.Add(*[build(a) for a in node[1]])
        if kind == "mul":
            return sympy.Mul(*[build(a) for a in node[1]])
        if kind == "pow":
            return sympy.Pow(build(node[1]), build(node[2]))
        if kind == "call":
            name = node[1]
            arg = build(node[2])
            if name == "abs":
                return sympy.Abs(arg)
            return getattr(sympy, name)(arg)
        if kind == "atan2":
            return sympy.atan2(build(node[1]), build(node[2]))
        raise ValueError(f"unknown expression node {kind!r}")

    return build(tree)


def from_sympy(expr: Any) -> str:
    """The expression language's text of a SymPy expression (fully
    parenthesized; lagrange simplifies it when it reads it)."""
    import sympy
    from sympy.core.function import AppliedUndef  # type: ignore[import-untyped,unused-ignore]

    def p(e: Any) -> str:
        if isinstance(e, sympy.Integer):
            return f"({int(e)})" if e < 0 else str(int(e))
        if isinstance(e, sympy.Rational):
            return f"({e.p}/{e.q})"
        if isinstance(e, sympy.Float):
            return f"({float(e)!r})"
        if e is sympy.pi:
            return "pi"
        if e is sympy.E:
            return "exp(1)"
        if isinstance(e, sympy.Symbol):
            return str(e.name)
        if isinstance(e, AppliedUndef):
            if len(e.args) == 1 and isinstance(e.args[0], sympy.Symbol) and e.args[0].name == "t":
                return type(e).__name__
            raise TypeError(f"cannot write {e} in the expression language: only functions of t alone are coordinates")
        if isinstance(e, sympy.Derivative):
            inner = e.expr
            counts = e.variable_count
            if isinstance(inner, AppliedUndef) and len(counts) == 1 and str(counts[0][0]) == "t" and counts[0][1] <= 2:
                return p(inner) + "'" * int(counts[0][1])
            raise TypeError(f"cannot write {e} in the expression language: only first and second time derivatives of coordinates")
        if isinstance(e, sympy.Add):
            return "(" + " + ".join(p(a) for a in e.args) + ")"
        if isinstance(e, sympy.Mul):
            return "(" + "*".join(p(a) for a in e.args) + ")"
        if isinstance(e, sympy.Pow):
            base, exp = e.args
            if exp == sympy.Rational(1, 2):
                return f"sqrt({p(base)})"
            return f"({p(base)})^{p(exp)}"
        if isinstance(e, sympy.Abs):
            return f"abs({p(e.args[0])})"
        if isinstance(e, sympy.atan2):
            return f"atan2({p(e.args[0])}, {p(e.args[1])})"
        name = type(e).__name__
        if name == "exp":
            return f"exp({p(e.args[0])})"
        if name in _FUNCTIONS and len(e.args) == 1:
            return f"{name}({p(e.args[0])})"
        raise TypeError(f"cannot write {e} ({name}) in the expression language")

    return p(sympy.sympify(expr))


def is_sympy(value: Any) -> bool:
    """Whether a value is a SymPy object (without importing SymPy: a value
    cannot be one unless SymPy is loaded)."""
    sympy = sys.modules.get("sympy")
    return sympy is not None and isinstance(value, sympy.Basic)
