#!/usr/bin/env python3
"""Differential test of `lagrange derive` and `lagrange simulate` against SymPy and SciPy.

A long job, not part of CI. For each of --models random models (a seeded generator:
1 to 3 coordinates; a kinetic energy with coordinate-dependent metric, small couplings
and velocity-linear terms, or point particles with gravity; potentials with
polynomial and trigonometric terms, sometimes time-dependent or velocity-dependent;
sometimes Rayleigh dissipation and generalized forces) it

1. writes the model as a lagrange TOML file (sometimes with a quartic velocity term,
   so that L is not quadratic and there is no H);
2. runs `lagrange derive FILE --format json` and reads its expressions into SymPy;
3. derives the same model with SymPy itself (dynamicsymbols: L, p = dL/dq',
   E = d/dt dL/dq' - dL/dq + dR/dq' - Q, M = dE/dq'', f = M q'' - E, h = q' p - L)
   and compares, at random points of (q, q', q'', t): L, the momenta, M, f, the
   equations, the energy function, T + U0, H(q, p) against h, q'(q, p) and
   Hamilton's equations; and the flags: the cyclic coordinates (dL/dq = 0), whether
   H is conserved (dL/dt, R and Q all zero) and whether H is the energy
   (h = T + U0), each zero decided by SymPy's simplify, confirmed numerically;
4. runs `lagrange simulate FILE --until T --method dop853 --rtol 1e-12 --atol 1e-12
   --summary json` and SciPy's solve_ivp (DOP853, the same tolerances) on
   M(q, q', t) q'' = f from SymPy's derivation, from the model's [initial] state,
   and compares the final states.

It prints a JSON summary on stdout: models tried, how many agreed on each check, and
every disagreement with the path of its model file (kept in --out) for reproduction.
Exit 0 when nothing disagreed, 1 otherwise.

If this Python cannot import sympy, numpy and scipy, the script re-runs itself with
the benchmarks' venv (${TMPDIR:-/tmp}/lagrange-bench-venv), creating it with the
pinned versions of ../shared/bench/requirements.txt when needed (--no-install
forbids it).

    python3 tools/differential.py --models 300 --seed 1
    python3 tools/differential.py --models 20 --no-simulate      # derive only, quick
    python3 tools/differential.py /tmp/lagrange-differential-XXXX/model_1_7.toml   # one model again
"""

from __future__ import annotations

import argparse
import json
import math
import os
import random
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
MODULES = ("sympy", "numpy", "scipy")
# Wall seconds one reference run may take: past a singular mass matrix solve_ivp
# shrinks its step without end.
SCIPY_SECONDS = 60


def log(message: str) -> None:
    print(f"[differential.py] {message}", file=sys.stderr, flush=True)


# ------------------------------------------------------------------ environment


def can_import(python: str) -> bool:
    code = "; ".join(f"import {m}" for m in MODULES)
    try:
        return subprocess.run([python, "-c", code], capture_output=True, timeout=120).returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        return False


def reexec_in_venv(allow_install: bool) -> None:
    """Re-runs this script with a Python that imports sympy, numpy and scipy."""
    venv = Path(os.environ.get("TMPDIR") or "/tmp") / "lagrange-bench-venv"
    python = venv / "bin" / "python"
    if not (python.exists() and can_import(str(python))):
        if not allow_install:
            sys.exit("no Python here imports sympy, numpy and scipy (and --no-install was given)")
        requirements = REPO.parent / "shared" / "bench" / "requirements.txt"
        packages = [line.split("#")[0].strip() for line in requirements.read_text().splitlines()] \
            if requirements.exists() else list(MODULES)
        packages = [p for p in packages if p]
        if not python.exists():
            log(f"creating {venv}")
            subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
        log(f"installing {' '.join(packages)} into {venv}")
        subprocess.run([str(python), "-m", "pip", "install", "--quiet", *packages], check=True, timeout=900)
    os.execv(str(python), [str(python), __file__, *sys.argv[1:]])


# ------------------------------------------------------------------ the models


COORDINATES = ["x", "y", "th", "ph", "r", "s"]
PARAMETERS = ["m", "k", "l", "c", "w", "a"]


class Generator:
    """Random model files from a small grammar, seeded."""

    def __init__(self, rng: random.Random):
        self.rng = rng

    def leaf(self, qs, ps, time: bool) -> str:
        r = self.rng.random()
        if r < 0.45:
            return self.rng.choice(qs)
        if r < 0.7:
            return self.rng.choice(ps)
        if r < 0.85:
            return self.rng.choice(["1", "2", "3", "1/2", "3/2", "0.3"])
        return "t" if time else self.rng.choice(qs)

    def expr(self, qs, ps, depth: int, time: bool = False) -> str:
        """An expression in the coordinates (and t), finite everywhere."""
        if depth == 0 or self.rng.random() < 0.3:
            return self.leaf(qs, ps, time)
        a = self.expr(qs, ps, depth - 1, time)
        b = self.expr(qs, ps, depth - 1, time)
        return self.rng.choice([
            f"{a} + {b}", f"{a} - {b}", f"({a})*({b})", f"sin({a})", f"cos({a})", f"({a})^2",
            f"({a})^3", f"exp(-({a})^2)", f"sqrt(1 + ({a})^2)", f"atan({a})", f"({a})/(2 + cos({b}))",
        ])

    def potential_term(self, qs, ps, time: bool) -> str:
        q = self.rng.choice(qs)
        p = self.rng.choice(ps)
        q2 = self.rng.choice(qs)
        return self.rng.choice([
            f"{p}*{q}^2/2", f"{p}*{q}^4/4", f"-{p}*cos({q})", f"{p}*{q}*{q2}", f"{p}*sin({q})*cos({q2})",
            f"{p}*(1 - cos({q} - {q2}))", f"{p}*{q}^3/3",
            f"{p}*{q}*cos({self.rng.choice(ps)}*t)" if time else f"{p}*{q}",
            self.expr(qs, ps, 2, time),
        ])

    def kinetic(self, qs, ps) -> str:
        terms = []
        for q in qs:
            p = self.rng.choice(ps)
            if self.rng.random() < 0.6:
                terms.append(f"1/2*({p} + ({self.expr(qs, ps, 1)})^2)*{q}'^2")
            else:
                terms.append(f"{p}*{q}'^2/2")
        for i in range(len(qs)):
            for j in range(i + 1, len(qs)):
                if self.rng.random() < 0.4:
                    terms.append(f"1/10*cos({self.expr(qs, ps, 1)})*{qs[i]}'*{qs[j]}'")
        if self.rng.random() < 0.3:
            terms.append(f"({self.expr(qs, ps, 1)})*{self.rng.choice(qs)}'")
        if self.rng.random() < 0.1:
            # Not quadratic in the velocities: no H, and M depends on q'.
            terms.append(f"{self.rng.choice(ps)}/12*{self.rng.choice(qs)}'^4")
        return " + ".join(terms)

    def model(self) -> str:
        rng = self.rng
        qs = rng.sample(COORDINATES, rng.randint(1, 3))
        ps = rng.sample(PARAMETERS, rng.randint(2, 5))
        time = rng.random() < 0.2
        style = rng.choice(["lagrangian", "kinetic", "particles"])
        gravity = style == "particles" and rng.random() < 0.6
        lines = ['name = "differential"', "coordinates = [" + ", ".join(f'"{q}"' for q in qs) + "]"]
        if gravity:
            lines.append('gravity = "g"')
        potential = " + ".join(self.potential_term(qs, ps, time) for _ in range(rng.randint(1, 3)))
        if rng.random() < 0.15:
            potential += f" + ({self.expr(qs, ps, 1)})*{rng.choice(qs)}'"
        if style == "lagrangian":
            lines.append(f'lagrangian = "{self.kinetic(qs, ps)} - ({potential})"')
        elif style == "kinetic":
            lines.append(f'kinetic = "{self.kinetic(qs, ps)}"')
            lines.append(f'potential = "{potential}"')
        else:
            if rng.random() < 0.5:
                lines.append(f'kinetic = "{self.kinetic(qs, ps)}"')
            if rng.random() < 0.5:
                lines.append(f'potential = "{potential}"')
        if rng.random() < 0.3:
            terms = [f"{rng.choice(ps)}*{q}'^2/2" for q in qs if rng.random() < 0.7]
            if terms:
                lines.append(f'dissipation = "{" + ".join(terms)}"')
        lines += ["", "[parameters]"]
        lines += [f"{p} = {rng.uniform(0.5, 2.0):.3f}" for p in ps]
        if gravity:
            lines.append("g = 9.81")
        if style == "particles":
            for _ in range(rng.randint(1, 3)):
                dims = rng.randint(2, 3) if gravity else rng.randint(1, 3)
                position = [self.expr(qs, ps, 2, time and rng.random() < 0.3) for _ in range(dims)]
                lines += ["", "[[particles]]", f'mass = "{rng.choice(ps)}"',
                          "position = [" + ", ".join(f'"{x}"' for x in position) + "]"]
        forced = [q for q in qs if rng.random() < 0.15]
        if forced:
            lines += ["", "[forces]"]
            for q in forced:
                lines.append(f'{q} = "-{rng.choice(ps)}*{q}\' + {self.expr(qs, ps, 1, time)}"')
        lines += ["", "[initial]"]
        for q in qs:
            lines += [f"{q} = {rng.uniform(-1, 1):.3f}", f"\"{q}'\" = {rng.uniform(-1, 1):.3f}"]
        return "\n".join(lines) + "\n"


# ------------------------------------------------------------------ lagrange text to SymPy


FUNCTIONS = {"sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh", "exp", "log", "ln",
             "sqrt", "abs"}
NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*('{0,2})")


def to_sympy(text: str, sp, exact: bool = False):
    """A lagrange expression as SymPy: q' is the symbol q__d, q'' is q__dd. With
    `exact`, decimals are exact rationals (0.3 is 3/10), so that SymPy's own
    derivation of the model has no rounding of its own."""
    names = {}

    def rename(match):
        word = match.group(0)
        base = word.rstrip("'")
        primes = len(word) - len(base)
        if base in FUNCTIONS or base == "pi":
            return {"abs": "Abs", "ln": "log"}.get(base, base)
        name = base + ("__d" * min(primes, 1)) + ("d" if primes == 2 else "")
        names[name] = sp.Symbol(name, real=True)
        return name

    python = NAME.sub(rename, text).replace("^", "**")
    local = dict(names)
    local.update({"pi": sp.pi, "Abs": sp.Abs, "log": sp.log, "sqrt": sp.sqrt, "atan2": sp.atan2})
    return sp.sympify(python, locals=local, rational=exact)


# ------------------------------------------------------------------ SymPy's derivation


class Reference:
    """The model derived by SymPy, and the model's expressions read with `to_sympy`."""

    def __init__(self, text: str, sp):
        import tomllib

        self.sp = sp
        data = tomllib.loads(text)
        self.names = data["coordinates"]
        self.params = {k: float(v) for k, v in data.get("parameters", {}).items()}
        self.initial = data.get("initial", {})
        t = sp.Symbol("t", real=True)
        self.t = t
        self.q = [sp.Symbol(n, real=True) for n in self.names]
        self.qd = [sp.Symbol(n + "__d", real=True) for n in self.names]
        self.qdd = [sp.Symbol(n + "__dd", real=True) for n in self.names]
        self.p = [sp.Symbol("p_" + n, real=True) for n in self.names]
        # Dynamic symbols: q(t), and the plain symbols they stand for.
        fq = [sp.Function(n)(t) for n in self.names]
        to_dyn = {}
        for i in range(len(self.names)):
            to_dyn[self.qdd[i]] = fq[i].diff(t, 2)
            to_dyn[self.qd[i]] = fq[i].diff(t)
            to_dyn[self.q[i]] = fq[i]
        from_dyn = [(fq[i].diff(t, 2), self.qdd[i]) for i in range(len(fq))]
        from_dyn += [(fq[i].diff(t), self.qd[i]) for i in range(len(fq))]
        from_dyn += [(fq[i], self.q[i]) for i in range(len(fq))]

        def dyn(e):
            return e.xreplace(to_dyn)

        def plain(e):
            for a, b in from_dyn:
                e = e.subs(a, b)
            return e

        exact = lambda text: to_sympy(str(text), sp, exact=True)  # noqa: E731
        read = lambda key: exact(data[key]) if key in data else None  # noqa: E731
        if "lagrangian" in data:
            L = read("lagrangian")
            self.kinetic = self.potential = None
        else:
            T = read("kinetic") or sp.Integer(0)
            U = read("potential") or sp.Integer(0)
            g = exact(data["gravity"]) if "gravity" in data else None
            for part in data.get("particles", []):
                mass = exact(part["mass"])
                xs = [dyn(exact(x)) for x in part["position"]]
                T += plain(mass * sum(x.diff(t) ** 2 for x in xs) / 2)
                if g is not None:
                    U += mass * g * plain(xs[-1])
                if "potential" in part:
                    U += exact(part["potential"])
            L = T - U
            self.kinetic, self.potential = T, U
        self.L = L
        self.R = read("dissipation") or sp.Integer(0)
        forces = data.get("forces", {})
        self.Q = [exact(forces[n]) if n in forces else sp.Integer(0) for n in self.names]

        n = len(self.names)
        Ld = dyn(L)
        self.momenta = [sp.diff(L, v) for v in self.qd]
        E = []
        for i in range(n):
            e = sp.diff(sp.diff(Ld, fq[i].diff(t)), t) - sp.diff(Ld, fq[i])
            E.append(plain(e) + sp.diff(self.R, self.qd[i]) - self.Q[i])
        self.E = E
        self.M = [[sp.diff(E[i], self.qdd[j]) for j in range(n)] for i in range(n)]
        zero_acc = {a: 0 for a in self.qdd}
        self.f = [-E[i].subs(zero_acc) for i in range(n)]
        self.h = sum(self.qd[i] * self.momenta[i] for i in range(n)) - L
        self.dl_dq = [sp.diff(L, x) for x in self.q]
        self.dl_dt = sp.diff(L, t)
        self.rates = [self.dl_dq[i] - sp.diff(self.R, self.qd[i]) + self.Q[i] for i in range(n)]
        if self.kinetic is not None:
            at_rest = {v: 0 for v in self.qd}
            self.energy = self.kinetic + self.potential.subs(at_rest)
        else:
            self.energy = None
        names = {str(x) for x in self.q + self.qd + self.qdd + self.p} | {"t"}
        params = [sp.Symbol(k, real=True) for k in self.params if k not in names]
        self.symbols = self.q + self.qd + self.qdd + self.p + [t] + params
        self._compiled = {}

    def is_zero(self, e, points) -> bool | None:
        """Whether `e` is identically zero: numerically at the points (against the
        size of its terms, `size`), and when it vanishes there, by SymPy's
        simplify too. None when the two disagree (simplify is incomplete)."""
        sp = self.sp
        e = sp.expand(e)
        if e == 0:
            return True
        for pt in points:
            v, size = self.value(e, pt), self.size(e, pt)
            if math.isfinite(v) and math.isfinite(size) and abs(v) > 1e-10 * size:
                return False
        return True if sp.simplify(e) == 0 else None

    def size(self, e, point: dict) -> float:
        """The value of `e` with every term of every sum taken positive: the scale
        against which a value that should cancel to zero is judged."""
        sp = self.sp
        if e.is_Add:
            return sum(self.size(a, point) for a in e.args)
        if e.is_Mul:
            return math.prod(self.size(a, point) for a in e.args)
        if e.is_Pow and e.exp.is_number:
            try:
                return self.size(e.base, point) ** float(e.exp)
            except (OverflowError, ZeroDivisionError):
                return math.inf
        return abs(self.value(e, point))

    def value(self, e, point: dict) -> float:
        """The value of `e` at `point` (a dict from symbols to numbers); NaN
        where it is undefined. Each expression is compiled once."""
        fn = self._compiled.get(e)
        if fn is None:
            fn = self.sp.lambdify(self.symbols, e, modules="math")
            self._compiled[e] = fn
        try:
            v = fn(*[point.get(s, math.nan) for s in self.symbols])
        except (ValueError, ZeroDivisionError, OverflowError, TypeError):
            return math.nan
        v = complex(v)
        return v.real if abs(v.imag) <= 1e-12 * (1 + abs(v.real)) else math.nan

    def regular_at(self, rng: random.Random):
        """A point where SymPy's M is clearly regular (|det M| above 1e-8 of the
        product of its rows' norms), or None when it is singular at every point."""
        n = len(self.names)
        for pt in self.points(rng, 4):
            m = [[self.value(self.M[i][j], pt) for j in range(n)] for i in range(n)]
            if not all(math.isfinite(v) for row in m for v in row):
                continue
            norms = math.prod(math.sqrt(sum(v * v for v in row)) for row in m)
            det = float(self.sp.Matrix(m).det())
            if norms > 0 and abs(det) > 1e-8 * norms:
                return fmt_point(pt)
        return None

    def points(self, rng: random.Random, count: int) -> list[dict]:
        sp = self.sp
        out = []
        for _ in range(count):
            pt = {sp.Symbol(k, real=True): v for k, v in self.params.items()}
            pt[sp.Symbol("g", real=True)] = self.params.get("g", 9.81)
            for i in range(len(self.names)):
                pt[self.q[i]] = rng.uniform(-1.2, 1.2)
                pt[self.qd[i]] = rng.uniform(-1, 1)
                pt[self.qdd[i]] = rng.uniform(-1, 1)
            pt[self.t] = rng.uniform(0, 1.5)
            for i in range(len(self.names)):
                pt[self.p[i]] = self.value(self.momenta[i], pt)
            out.append(pt)
        return out


# ------------------------------------------------------------------ comparison


def close(a: float, b: float, rtol: float = 1e-8) -> bool:
    if math.isnan(a) and math.isnan(b):
        return True
    return abs(a - b) <= rtol * (1 + abs(a) + abs(b))


def compare_derivation(ref: Reference, report: dict, rng: random.Random, sp) -> tuple[list[str], list[str]]:
    """What differs between lagrange's report and SymPy's derivation."""
    problems = []
    n = len(ref.names)
    points = ref.points(rng, 4)
    ours = lambda s: to_sympy(s, sp)  # noqa: E731
    pairs = [("L", ours(report["lagrangian"]), ref.L), ("energy_function", ours(report["energy_function"]), ref.h)]
    for i, name in enumerate(ref.names):
        pairs.append((f"momenta[{name}]", ours(report["momenta"][name]), ref.momenta[i]))
        pairs.append((f"equations[{name}]", ours(report["equations"][name]), ref.E[i]))
        pairs.append((f"forcing[{i}]", ours(report["forcing"][i]), ref.f[i]))
        for j in range(n):
            pairs.append((f"mass_matrix[{i}][{j}]", ours(report["mass_matrix"][i][j]), ref.M[i][j]))
    if ref.energy is not None and report.get("energy") is not None:
        pairs.append(("energy", ours(report["energy"]), ref.energy))
    if report.get("hamiltonian") is not None:
        # H(q, p) at p = dL/dq' is h(q, q'); q'(q, p) is q'; Hamilton's dp is the momentum's true rate.
        pairs.append(("hamiltonian", ours(report["hamiltonian"]), ref.h))
        for i, name in enumerate(ref.names):
            pairs.append((f"velocities[{name}]", ours(report["velocities"][name]), ref.qd[i]))
            pairs.append((f"hamilton[{name}].dq", ours(report["hamilton"][name]["dq"]), ref.qd[i]))
            pairs.append((f"hamilton[{name}].dp", ours(report["hamilton"][name]["dp"]), ref.rates[i]))
    for what, a, b in pairs:
        for pt in points:
            va, vb = ref.value(a, pt), ref.value(b, pt)
            if not math.isfinite(vb) or abs(vb) > 1e6:
                continue
            if not close(va, vb):
                problems.append(f"{what}: lagrange {va!r}, SymPy {vb!r} at {fmt_point(pt)}")
                break

    # The flags, each from zero tests.
    cyclic = []
    undecided = []
    for i, name in enumerate(ref.names):
        z = ref.is_zero(ref.dl_dq[i], points)
        if z is None:
            undecided.append(f"dL/d{name}")
        elif z:
            cyclic.append(name)
    if not undecided and sorted(cyclic) != sorted(report["cyclic"]):
        problems.append(f"cyclic: lagrange {report['cyclic']}, SymPy {cyclic}")
    parts = [ref.dl_dt, ref.R] + ref.Q
    zeros = [ref.is_zero(e, points) for e in parts]
    if None in zeros:
        undecided.append("dL/dt, R or Q")
    else:
        conserved = all(zeros)
        if conserved != report["hamiltonian_conserved"]:
            problems.append(f"hamiltonian_conserved: lagrange {report['hamiltonian_conserved']}, SymPy {conserved}")
    if ref.energy is None:
        if report["hamiltonian_is_energy"] is not None:
            problems.append(f"hamiltonian_is_energy: lagrange {report['hamiltonian_is_energy']}, SymPy null")
    else:
        z = ref.is_zero(ref.h - ref.energy, points)
        if z is None:
            undecided.append("h - (T + U0)")
        elif z != report["hamiltonian_is_energy"]:
            problems.append(f"hamiltonian_is_energy: lagrange {report['hamiltonian_is_energy']}, SymPy {z}")
    return problems, undecided


def fmt_point(pt: dict) -> str:
    return "{" + ", ".join(f"{k}: {v:.6g}" for k, v in pt.items() if not str(k).startswith("p_")) + "}"


def scipy_final(ref: Reference, until: float, rtol: float, sp, np, solve_ivp):
    """The final state by solve_ivp (DOP853) on M q'' = f from SymPy's derivation."""
    n = len(ref.names)
    params = {sp.Symbol(k, real=True): v for k, v in ref.params.items()}
    M = sp.Matrix(ref.M).subs(params)
    f = sp.Matrix(ref.f).subs(params)
    args = ref.q + ref.qd + [ref.t]
    M_fn = sp.lambdify(args, M, modules="numpy")
    f_fn = sp.lambdify(args, f, modules="numpy")

    started = time.time()

    def rhs(t, y):
        if time.time() - started > SCIPY_SECONDS:
            raise RuntimeError(f"solve_ivp ran past {SCIPY_SECONDS} s (at t = {t})")
        values = list(y) + [t]
        acc = np.linalg.solve(np.array(M_fn(*values), dtype=float), np.array(f_fn(*values), dtype=float).ravel())
        return np.concatenate([y[n:], acc])

    initial = []
    for key in ref.names + [name + "'" for name in ref.names]:
        v = ref.initial[key]
        initial.append(float(v) if not isinstance(v, str) else float(to_sympy(v, sp).subs(params)))
    sol = solve_ivp(rhs, (0.0, until), initial, method="DOP853", rtol=rtol, atol=rtol)
    if sol.status != 0:
        raise RuntimeError(sol.message)
    return sol.y[:, -1]


# ------------------------------------------------------------------ main


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--models", type=int, default=100, help="models to try (default 100)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the model generator (default 1)")
    parser.add_argument("--binary", type=Path, default=REPO / "target" / "debug" / "lagrange",
                        help="the lagrange binary (default target/debug/lagrange; built if missing)")
    parser.add_argument("--out", type=Path, default=None,
                        help="folder for the models that disagree (default: a new temporary folder)")
    parser.add_argument("--until", type=float, default=2.0, help="end time of the trajectories (default 2)")
    parser.add_argument("--rtol", type=float, default=1e-12, help="rtol = atol of both integrators (default 1e-12)")
    parser.add_argument("--no-simulate", action="store_true", help="compare derivations only")
    parser.add_argument("--no-install", action="store_true", help="never create or fill the venv")
    parser.add_argument("--timeout", type=float, default=120, help="seconds per lagrange run (default 120)")
    parser.add_argument("files", nargs="*", type=Path,
                        help="model files to check instead of generated ones (a disagreement's file, to reproduce it)")
    args = parser.parse_args(argv)

    try:
        import numpy as np
        import sympy as sp
        from scipy.integrate import solve_ivp
    except ImportError:
        reexec_in_venv(not args.no_install)
        return 2

    if not args.binary.exists():
        log(f"building {args.binary}")
        subprocess.run(["cargo", "build", "-p", "lagrange-cli"], cwd=REPO, check=True)
    out = args.out or Path(tempfile.mkdtemp(prefix="lagrange-differential-"))
    out.mkdir(parents=True, exist_ok=True)
    gen = Generator(random.Random(args.seed))
    summary = {"models": 0, "derived": 0, "rejected": {}, "derive_agreed": 0, "simulated": 0,
               "simulate_agreed": 0, "stopped_early": {}, "both_failed_to_simulate": 0, "coverage": {}, "undecided_flags": 0,
               "disagreements": [], "seed": args.seed, "out": str(out)}
    started = time.time()
    count = len(args.files) or args.models
    for k in range(count):
        if args.files:
            path = args.files[k]
            text = path.read_text()
        else:
            text = gen.model()
            path = out / f"model_{args.seed}_{k}.toml"
            path.write_text(text)
        summary["models"] += 1
        problems = []
        proc = subprocess.run([str(args.binary), "derive", str(path), "--format", "json"],
                              capture_output=True, text=True, timeout=args.timeout)
        if proc.returncode != 0:
            first = (proc.stderr.strip().splitlines() or ["?"])[0]
            reason = re.sub(r"^(error: )?.*?:\d+:\d+: ", "", first)
            summary["rejected"][reason] = summary["rejected"].get(reason, 0) + 1
            ref = None
            if "singular" not in reason:
                problems.append(f"derive exited {proc.returncode}: {first}")
            else:
                # lagrange calls M singular: so must SymPy's M be, at every point.
                gap = Reference(text, sp).regular_at(random.Random(k))
                if gap is not None:
                    problems.append(f"derive calls M singular, but SymPy's M is regular at {gap}")
        else:
            summary["derived"] += 1
            report = json.loads(proc.stdout)
            # What the derived models were like, to show what the agreements cover.
            cover = summary["coverage"]
            for key, value in (("with_cyclic", bool(report["cyclic"])),
                               ("hamiltonian_given", report["hamiltonian"] is not None),
                               ("hamiltonian_conserved", report["hamiltonian_conserved"]),
                               ("hamiltonian_is_energy", report["hamiltonian_is_energy"])):
                tally = cover.setdefault(key, {})
                tally[json.dumps(value)] = tally.get(json.dumps(value), 0) + 1
            ref = Reference(text, sp)
            found, undecided = compare_derivation(ref, report, random.Random(k), sp)
            problems += found
            summary["undecided_flags"] += bool(undecided)
            if not found:
                summary["derive_agreed"] += 1
        if ref is not None and not args.no_simulate:
            def simulate(until: float):
                proc = subprocess.run([str(args.binary), "simulate", str(path), "--until", repr(until), "--method",
                                       "dop853", "--rtol", str(args.rtol), "--atol", str(args.rtol), "--summary",
                                       "json"], capture_output=True, text=True, timeout=args.timeout)
                try:
                    return proc, json.loads(proc.stdout)
                except json.JSONDecodeError:
                    return proc, None

            until = args.until
            sim, ours_summary = simulate(until)
            # A run that stopped early (a singular M at t*) is compared at 0.9 t*,
            # short of the singularity, where both integrators still converge.
            stopped = ours_summary is not None and sim.returncode == 1 and ours_summary.get("failure_reason")
            if stopped:
                summary["stopped_early"][stopped["code"]] = summary["stopped_early"].get(stopped["code"], 0) + 1
                until = 0.9 * ours_summary["t_final"]
                sim, ours_summary = simulate(until) if until > 0 else (sim, None)
            try:
                theirs = scipy_final(ref, until, args.rtol, sp, np, solve_ivp) if until > 0 else None
                scipy_error = None if theirs is not None else "no time to run"
            except Exception as err:  # noqa: BLE001 - any failure of the reference run is reported as such
                theirs, scipy_error = None, str(err)
            if ours_summary is None:
                problems.append(f"simulate exited {sim.returncode} without a summary: {sim.stderr.strip()[:300]}")
            elif scipy_error is not None:
                if stopped:
                    summary["both_failed_to_simulate"] += 1
                else:
                    problems.append(f"SciPy failed ({scipy_error[:200]}) but simulate ran")
            elif sim.returncode != 0:
                problems.append(f"simulate exited {sim.returncode}: {sim.stderr.strip()[:300]}")
            else:
                summary["simulated"] += 1
                final = ours_summary["final"]
                ours = [final[n] for n in ref.names] + [final[n + "'"] for n in ref.names]
                scale = max(1.0, max(abs(v) for v in theirs))
                worst = max(abs(a - b) for a, b in zip(ours, theirs)) / scale
                if worst > 1e-6:
                    problems.append(f"final state at t = {until}: lagrange {ours}, SciPy {list(theirs)} "
                                    f"(relative gap {worst:.2e})")
                else:
                    summary["simulate_agreed"] += 1
        if problems:
            summary["disagreements"].append({"model": str(path), "problems": problems})
            log(f"model {k}: " + "; ".join(problems))
        elif not args.files:
            path.unlink()
        if (k + 1) % 25 == 0:
            log(f"{k + 1} models, {len(summary['disagreements'])} disagreements, {time.time() - started:.0f} s")
    summary["seconds"] = round(time.time() - started, 1)
    print(json.dumps(summary, indent=2, ensure_ascii=False))
    return 1 if summary["disagreements"] else 0


if __name__ == "__main__":
    sys.exit(main())
