"""A mechanical system: read from a model file, from TOML text, or built in
Python, derived once, then simulated and analysed."""

from __future__ import annotations

import os
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

from . import _native, toml_writer
from .analyses import Report
from .derivation import Derivation
from .expr import _name
from .errors import Interrupted, ModelError, RunError
from .rhs import Jac, Rhs
from .run import Run

PathLike = Union[str, "os.PathLike[str]"]


class Model:
    """A model of a mechanical system, derived.

    Build it from a file (:func:`lagrange.load`), from TOML text
    (:meth:`Model.from_toml`), or from Python values, where every expression
    may be a string of the expression language or a SymPy expression::

        th = sympy.physics.mechanics.dynamicsymbols("th")
        m, l, g = sympy.symbols("m l g")
        model = lagrange.Model(
            coordinates=[th],
            parameters={m: 1.0, l: 1.0, g: 9.81},
            particles=[{"mass": m, "position": [l * sympy.sin(th), -l * sympy.cos(th)]}],
            gravity=g,
            initial={"th": 0.5, "th'": 0.0},
        )

    Keyword arguments mirror the model file (the guide's chapter "Model files"):
    ``name``, ``coordinates``, ``parameters``, ``gravity``, ``lagrangian``,
    ``kinetic``, ``potential``, ``dissipation``, ``forces`` (coordinate →
    generalized force), ``initial`` (``"th"``/``"th'"`` → value),
    ``particles``, ``bodies``, ``constraints`` and ``impacts`` (lists of dicts
    with the file's keys). ``set`` overrides parameter values; ``folder`` is where body
    files the model names are read from. Bad input raises
    :class:`lagrange.ModelError` pointing into the model's text
    (``model.source``).
    """

    def __init__(
        self,
        coordinates: Optional[Sequence[Any]] = None,
        *,
        name: str = "model",
        parameters: Optional[Mapping[Any, Any]] = None,
        particles: Optional[Sequence[Mapping[str, Any]]] = None,
        gravity: Any = None,
        lagrangian: Any = None,
        kinetic: Any = None,
        potential: Any = None,
        dissipation: Any = None,
        forces: Optional[Mapping[Any, Any]] = None,
        initial: Optional[Mapping[Any, Any]] = None,
        bodies: Optional[Sequence[Mapping[str, Any]]] = None,
        constraints: Optional[Sequence[Mapping[str, Any]]] = None,
        impacts: Optional[Sequence[Mapping[str, Any]]] = None,
        set: Optional[Mapping[str, float]] = None,
        folder: Optional[PathLike] = None,
    ) -> None:
        if coordinates is None:
            raise TypeError("Model() needs coordinates=[...] (or use lagrange.load / Model.from_toml)")
        text, origins = toml_writer.model(
            name_=name,
            coordinates=coordinates,
            parameters=parameters or {},
            top={"gravity": gravity, "lagrangian": lagrangian, "kinetic": kinetic, "potential": potential,
                 "dissipation": dissipation},
            tables={"forces": forces or {}, "initial": initial or {}},
            arrays={
                "particles": particles or [],
                "bodies": bodies or [],
                "constraints": constraints or [],
                "impacts": impacts or [],
            },
        )
        try:
            native = _native.from_toml(text, "<model>", _floats(set), _folder(folder))
        except ModelError as e:
            raise _at_argument(e, origins) from None
        self._init(native, set, folder)

    def _init(self, native: _native.Derived, set: Optional[Mapping[str, float]], folder: Optional[PathLike]) -> None:
        self._native: _native.Derived = native
        self._set = _floats(set)
        self._folder = _folder(folder)
        self._derivation: Optional[Derivation] = None

    @classmethod
    def _wrap(cls, native: Any, set: Optional[Mapping[str, float]], folder: Optional[PathLike]) -> "Model":
        model = cls.__new__(cls)
        model._init(native, set, folder)
        return model

    @classmethod
    def from_toml(
        cls,
        text: str,
        set: Optional[Mapping[str, float]] = None,
        name: str = "<string>",
        folder: Optional[PathLike] = None,
    ) -> "Model":
        """A model from the text of a model file. ``name`` names it in error
        messages; body files are read from ``folder`` (default: the current one)."""
        return cls._wrap(_native.from_toml(text, name, _floats(set), _folder(folder)), set, folder)

    # --- what the model is --------------------------------------------------
    @property
    def name(self) -> str:
        """The model's name."""
        return self._native.name

    @property
    def coordinates(self) -> List[str]:
        """The generalized coordinates, in order."""
        return self._native.coordinates

    @property
    def parameters(self) -> Dict[str, float]:
        """The parameters' values (after ``set``)."""
        return dict(self._native.parameters)

    @property
    def initial(self) -> Dict[str, float]:
        """The initial state of ``[initial]``: ``{"th": .., "th'": ..}``."""
        q, qd = self._native.initial()
        out = dict(zip(self.coordinates, q))
        out.update({f"{c}'": v for c, v in zip(self.coordinates, qd)})
        return out

    @property
    def source(self) -> str:
        """The model file's text (for a model built in Python, the TOML written for it)."""
        return self._native.source

    @property
    def file(self) -> str:
        """The file the model was read from (``<string>``/``<model>`` otherwise)."""
        return self._native.file

    def with_parameters(self, **values: float) -> "Model":
        """The same model with some parameters set to other values."""
        merged = {**self._set, **{k: float(v) for k, v in values.items()}}
        return Model._wrap(_native.from_toml(self.source, self.file, merged, self._folder), merged, self._folder)

    def __repr__(self) -> str:
        return f"<Model {self.name!r}: coordinates {', '.join(self.coordinates)}>"

    def __reduce__(self) -> Tuple[Any, Tuple[Any, ...]]:
        # Pickled as its text, settings and folder, and derived again where it
        # is unpickled (a Dask worker, a multiprocessing child).
        return (_rebuilt, (self.source, self.file, self._set, self._folder))

    # --- derivation ---------------------------------------------------------
    def derive(self) -> Derivation:
        """The equations of motion, momenta, Hamiltonian, cyclic coordinates,
        conserved quantities and the verdicts, as ``lagrange derive`` gives them."""
        if self._derivation is None:
            self._derivation = Derivation(self)
        return self._derivation

    # --- motion -------------------------------------------------------------
    def simulate(
        self,
        until: float,
        method: Optional[str] = None,
        rtol: Optional[float] = None,
        atol: Optional[float] = None,
        dt: Optional[float] = None,
        samples: Optional[int] = None,
        every_step: bool = False,
        stop_when: Union[str, Iterable[str], None] = None,
        crossing: Union[str, Iterable[str], None] = None,
        initial: Optional[Mapping[str, float]] = None,
        section: Optional[str] = None,
        section_axes: Optional[str] = None,
    ) -> Run:
        """Integrates the motion from ``[initial]`` to ``until``, as ``lagrange
        simulate`` does (the same default method, tolerances and audit).

        ``method``: one of :func:`lagrange.methods` (default: chosen for the
        model); ``rtol``/``atol``: tolerances (default 1e-9 and 1e-12, atol
        rtol/1000 when only rtol is given); ``dt``: a fixed step (symplectic
        methods); ``samples``: rows at equal spacing (default 1001), or
        ``every_step``; ``stop_when``: conditions that end the run
        (``"x < 0"``); ``crossing``: conditions whose crossings are recorded
        as extra rows (``run.events``); ``initial``: values that replace
        ``[initial]``'s for this run (``{"a": 1.0, "a'": 0.0}``, or ``a_dot=``
        spelled as a key); ``section``: a Poincaré section (``"x = 0"``: the
        crossings where x increases through 0; ``"x < 0"``: decreasing), whose
        points are then the run's only rows, drawn by its plot in the plane
        ``section_axes`` (``"y, p_y"``: two expressions, ``p_NAME`` the
        momentum; default the first coordinate the condition does not name
        and its momentum), with ``run.section`` the points in that plane.

        The GIL is released while it runs. Ctrl-C stops it between rows and
        raises :class:`lagrange.Interrupted` (a KeyboardInterrupt) holding the
        rows so far; a run that fails midway raises :class:`lagrange.RunError`
        holding them too.
        """
        raw = self._native.simulate({
            "until": float(until),
            "method": method,
            "rtol": None if rtol is None else float(rtol),
            "atol": None if atol is None else float(atol),
            "dt": None if dt is None else float(dt),
            "samples": _count("samples", samples),
            "every_step": bool(every_step),
            "stop_when": _strings(stop_when),
            "crossing": _strings(crossing),
            "section": None if section is None else _string("section", section),
            "section_axes": None if section_axes is None else _string("section_axes", section_axes),
            "initial": [(_name(k), float(v)) for k, v in (initial or {}).items()],
        })
        run = Run(self, raw)
        if raw["interrupt"] is not None:
            at = f"t = {run.t[-1]}" if len(run) else "before the first row"
            raise Interrupted(f"interrupted at {at}; the exception's .run keeps every row up to there", run) from raw["interrupt"]
        if run.failure is not None:
            raise RunError(run.failure, float(run.summary["t_final"]), run)
        return run

    def rhs(self) -> Rhs:
        """The compiled right-hand side ``f(t, y) -> dy/dt`` with ``y = [q, q']``,
        for ``scipy.integrate.solve_ivp`` or any integrator of your own: an
        array of shape ``(2n,)``, or ``(2n, k)`` for y of shape ``(2n, k)``
        (``vectorized=True``). It pickles as its model, compiled again where it
        is unpickled."""
        return Rhs(self, self._native.rhs())

    def jac(self) -> Jac:
        """The Jacobian ``J(t, y) = ∂f/∂y`` of :meth:`rhs`, shape ``(2n, 2n)``,
        from the symbolic derivatives: ``solve_ivp(..., method="Radau",
        jac=model.jac())`` needs no differences. Models without constraints."""
        return Jac(self, self._native.jac())

    # --- code that leaves lagrange ---------------------------------------------
    def export(self, to: str, path: PathLike) -> None:
        """Writes the equations of motion for another program, as ``lagrange
        export --to`` does: ``"c"`` (one C99 file needing only libm),
        ``"python"`` (a module needing only numpy: ``rhs`` and ``jac`` for
        ``scipy.integrate.solve_ivp``) or ``"fmu"`` (an FMI 2.0 FMU for Model
        Exchange and Co-Simulation, compiled by the system's C compiler). The
        file is written whole or not at all; a model that cannot be exported
        raises ``ModelError`` with the reason, a missing C compiler
        ``LagrangeError``."""
        self._native.export(to, os.fspath(path))

    # --- analyses -------------------------------------------------------------
    def modes(self, at: Optional[Mapping[str, float]] = None, allow_unstable: bool = False) -> Report:
        """Normal modes about the equilibrium nearest ``[initial]`` (or ``at``):
        ``lagrange.modes/1`` (frequencies, modes, T, U, equilibrium, stable)."""
        return Report(*self._native.modes(_floats(at) or None, allow_unstable))

    def linearize(
        self,
        about: str = "equilibrium",
        at: Optional[Mapping[str, float]] = None,
        rates: Optional[Mapping[str, float]] = None,
        allow_unstable: bool = False,
    ) -> Report:
        """The state-space matrix A of the small motion about an equilibrium
        (``about="equilibrium"``, found from ``[initial]`` or ``at``) or a
        steady motion (``about="steady"``, cyclic coordinates at their
        ``[initial]`` rates or ``rates``), with B for a model with inputs, the
        eigenvalues and the verdict on stability, as ``lagrange linearize``:
        ``lagrange.linearize/1``, ``report.A`` and ``report.B`` as arrays."""
        return Report(*self._native.linearize(about, _floats(at) or None, _floats(rates) or None, allow_unstable))

    def report(
        self,
        until: float = 10.0,
        path: Optional[PathLike] = None,
        samples: int = 2001,
        method: Optional[str] = None,
        rtol: Optional[float] = None,
        section: Optional[str] = None,
        section_axes: Optional[str] = None,
    ) -> "Page":
        """The page ``lagrange report`` writes: the derivation typeset, the
        mechanism animated, the run to ``until`` plotted, the audit and the
        analyses that apply, in one HTML file that opens offline. It shows in
        a notebook (``_repr_html_``); ``path`` (or ``page.save(path)``) writes
        it. A run that fails midway gives the page of the rows up to there,
        with the reason in ``page.failure`` and a warning. ``section`` (and
        ``section_axes``) adds a Poincaré section to the analyses, as in
        :meth:`simulate`."""
        html, failure = self._native.report(
            float(until), _count("samples", samples) or 2001, method, None if rtol is None else float(rtol),
            None if section is None else _string("section", section),
            None if section_axes is None else _string("section_axes", section_axes))
        page = Page(html, failure)
        if failure is not None:
            import warnings

            warnings.warn(f"the run failed: {failure}; the page shows the rows up to there", RuntimeWarning, stacklevel=2)
        if path is not None:
            page.save(path)
        return page

    def orbit(self) -> Report:
        """The orbit of a central-force model: ``lagrange.orbit/1``."""
        return Report(*self._native.orbit())

    def top(self) -> Report:
        """The symmetric top's constants, nutation and precession: ``lagrange.top/1``."""
        return Report(*self._native.top())

    def sweep(self, until: float, grid: Any, **options: Any) -> Any:
        """A grid of runs: see :func:`lagrange.sweep`."""
        from .sweeps import sweep

        return sweep(self, until=until, grid=grid, **options)


class Page:
    """An HTML page of :meth:`Model.report`: ``html`` (the text), ``failure``
    (why the run stopped early, or None); ``save(path)`` writes it whole."""

    def __init__(self, html: str, failure: Optional[str] = None) -> None:
        self.html = html
        self.failure = failure

    def save(self, path: PathLike) -> None:
        """Writes the page to ``path``: the whole page or, on failure, the file as it was."""
        target = os.fspath(path)
        part = f"{target}.{os.getpid()}.part"
        try:
            with open(part, "w", encoding="utf-8") as f:
                f.write(self.html)
            os.replace(part, target)
        finally:
            if os.path.exists(part):
                os.remove(part)

    def _repr_html_(self) -> str:
        return self.html

    def __repr__(self) -> str:
        failed = f", the run failed: {self.failure}" if self.failure else ""
        return f"<Page of {len(self.html) // 1000} kB{failed}; save(path) writes it>"


def _at_argument(e: ModelError, origins: List[str]) -> ModelError:
    """An error in the text ``Model(...)`` wrote, pointed at the argument the
    line came from (``Model(potential=...)``) rather than at the text."""
    if e._source != "<model>":
        return e
    where = origins[e.line - 1] if e.line is not None and 0 < e.line <= len(origins) else ""
    place = f"Model({where}...)" if where.endswith("=") else (f"Model({where})" if where else "Model(...)")
    text = f"{place}: {e.message}"
    if e.snippet:
        text += "\n" + e.snippet
    if e.help:
        text += f"\nhelp: {e.help}"
    return ModelError(e.message, file=None, help=e.help, snippet=e.snippet, text=text, kind=e.kind, argument=place)


def _rebuilt(source: str, file: str, set: Dict[str, float], folder: Optional[str]) -> Model:
    """A pickled model, derived again from its text."""
    return Model._wrap(_native.from_toml(source, file, set, folder), set, folder)


def load(path: PathLike, set: Optional[Mapping[str, float]] = None) -> Model:
    """Reads and derives a model file; ``set`` overrides parameters
    (``set={"g": 1.62}``). Body files it names are read from its folder."""
    folder = os.path.dirname(os.fspath(path)) or "."
    return Model._wrap(_native.load(_existing(path), _floats(set)), set, folder)


def _existing(path: PathLike) -> str:
    """The path as text; a file that is not there raises ``FileNotFoundError``."""
    text = os.fspath(path)
    if not os.path.isfile(text):
        import errno

        what = "a folder, not a file" if os.path.isdir(text) else "no such file"
        raise FileNotFoundError(errno.ENOENT, what, text)
    return text


def _floats(values: Optional[Mapping[str, float]]) -> Dict[str, float]:
    return {str(k): float(v) for k, v in (values or {}).items()}


def _folder(folder: Optional[PathLike]) -> Optional[str]:
    return None if folder is None else os.fspath(folder)


def _strings(value: Union[str, Iterable[str], None]) -> List[str]:
    if value is None:
        return []
    if isinstance(value, str):
        return [value]
    try:
        return [str(v) for v in value]
    except TypeError:
        raise TypeError(f"expected a condition or a list of them (strings), not {value!r}") from None


def _string(what: str, value: Any) -> str:
    """A text of the caller's (a condition, axes), refused with its name where it is not one."""
    if not isinstance(value, str):
        raise TypeError(f"{what} must be a string, not {value!r}")
    return value


def _count(what: str, value: Any) -> Optional[int]:
    """A whole number of the caller's, refused with its name where it is not one."""
    if value is None:
        return None
    if isinstance(value, bool) or not float(value).is_integer() or value < 0:
        raise TypeError(f"{what} must be a whole number, not {value!r}")
    return int(value)
