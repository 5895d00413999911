"""The exceptions lagrange raises.

Every error from lagrange is a :class:`LagrangeError`:

- :class:`ModelError`: bad input (a model file, an expression, an option),
  with the file, line and column and the caret snippet the CLI prints.
- :class:`RunError`: a run that failed midway, with the rows it computed.
- :class:`Interrupted`: Ctrl-C during a long run, with what the run kept; it
  is a ``KeyboardInterrupt``, so code that stops on Ctrl-C still does.
"""

from __future__ import annotations

from typing import Any, Optional


class LagrangeError(Exception):
    """The base class of lagrange's errors."""


class ModelError(LagrangeError, ValueError):
    """Bad input: a model, body or problem file, an expression, or an option.

    Attributes: ``file`` (the file's name, the option's name, or None for a
    model given as text without ``name=`` or built with ``lagrange.Model``),
    ``line`` and ``column`` (1-based, or None when the error is about the
    file as a whole), ``message`` (what is wrong and what was
    expected), ``help`` (a hint, or None) and ``snippet`` (the offending line
    with carets under the place), and ``kind``, what kind of problem it is,
    for code that branches on it: ``"invalid"`` (the input as written is
    wrong), ``"file"`` (a file the model names could not be read),
    ``"singular_mass_matrix"``, ``"too_large"`` (the derivation passed its
    bound), ``"does_nothing"`` (a constraint, force or torque that acts on
    nothing), ``"start"`` (a start the motion cannot begin from) or
    ``"unsupported"`` (an analysis that does not handle this model).
    ``str(error)`` is all of it, as the CLI prints it. For a model built
    with ``lagrange.Model(...)``, ``file`` is None and ``argument`` names the
    argument at fault (``Model(potential=...)``, ``Model(particles[0]['mass'])``).
    """

    def __init__(
        self,
        message: str = "",
        file: Optional[str] = "<string>",
        line: Optional[int] = None,
        column: Optional[int] = None,
        help: Optional[str] = None,
        snippet: str = "",
        text: Optional[str] = None,
        kind: str = "invalid",
        argument: Optional[str] = None,
    ) -> None:
        self.message = message
        self.kind = kind
        # A file's name, or None for text and values that came from no file
        # (the name the text was given under stays in `_source`).
        self._source = file
        self.file = None if file in ("<string>", "<model>") else file
        self.argument = argument
        self.line = line
        self.column = column
        self.help = help
        self.snippet = snippet
        super().__init__(text if text is not None else f"{file}: {message}")


class RunError(LagrangeError):
    """A run that failed midway (the step budget ran out, the mass matrix
    became singular, ...).

    Attributes: ``message``, ``t`` (the time it reached, or None) and ``run``
    (a :class:`lagrange.Run` with every row computed up to there, or None
    where there are no rows, e.g. a failed extremal). A sweep whose every
    run failed raises it too, its ``run`` the sweep's :class:`lagrange.Table`.
    """

    def __init__(self, message: str = "", t: Optional[float] = None, run: Any = None) -> None:
        self.message = message
        self.t = t
        self.run = run
        super().__init__(message)


class Interrupted(KeyboardInterrupt):
    """Ctrl-C (or another signal whose handler raised) stopped a long run.

    ``run`` holds what it computed: a :class:`lagrange.Run` with the rows up to
    the interruption, or for a sweep a :class:`lagrange.Table` with the runs
    finished in grid order. The exception the handler raised is the
    ``__cause__``.
    """

    def __init__(self, message: str, run: Any = None) -> None:
        self.run = run
        super().__init__(message)
