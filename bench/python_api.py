#!/usr/bin/env python3
"""The Python package against SymPy + SciPy (issue #17), in one run, as ratios.

    python3 bench/python_api.py --report          # a few minutes: the Markdown tables
    python3 bench/python_api.py --quick --report  # a smoke run, under a minute
    python3 bench/python_api.py --report RUN.jsonl  # the tables of an earlier run again

What it measures, on the same machine in the same run:

1. **The double pendulum from Python, whole call.** A fresh interpreter runs
       import lagrange
       lagrange.load("examples/double_pendulum.toml").simulate(until=20, rtol=1e-9)
   (import, start-up, parsing, derivation, compilation, the integration with its audit and
   the 1001 rows as numpy arrays), against a fresh interpreter doing it the SymPy + SciPy
   way: the Lagrangian of ../shared/bench/bench_common.py, LagrangesMethod for M and f,
   lambdify, the right-hand side solving M q'' = f with numpy.linalg.solve (as
   scipy_simulate.py's `lambdify` variant), and solve_ivp(method="DOP853", rtol=1e-9,
   atol=1e-12, t_eval= the same 1001 times) to t = 20. The two run in turn (A B A B ...),
   --repeats times each; median wall time and CPU time (user + system of the child, from
   os.wait4). Beside them the bare imports (`import lagrange` against sympy,
   sympy.physics.mechanics and scipy.integrate), timed the same way. Accuracy: each side's
   state at t = 1 and t = 20 against two tight references computed once in-process
   (lagrange at rtol = 1e-13, atol = 1e-15, and DOP853 at the same tolerances on the
   anchors' hand-written right-hand side), and the energy error at t = 20.
2. **model.rhs() inside solve_ivp against lambdify.** In one process, with every callable
   prepared beforehand: solve_ivp(f, (0, 20), y0, method="DOP853", rtol=1e-9, atol=1e-12)
   with f = model.rhs(), with the lambdified SymPy right-hand side and with the anchors'
   hand-written one (pure Python with `math`: the floor of a Python callable), in turn,
   --repeats times; median wall and CPU seconds of the integration alone, nfev, and the
   final states' disagreement. Then the cost of one call of each at a fixed state passed as
   a numpy array (what solve_ivp passes): --calls calls (10^5) per sample, 5 samples, the
   median CPU microseconds per call. The same per-call cost on the 50-mass chain
   (examples/chain50.toml against scipy_simulate.py's chain(50)), unless SymPy's
   derivation and lambdify take more than --sympy-budget seconds (120).

Ratios are SymPy + SciPy / lagrange: > 1 means the package is faster. The measurements run
in a Python that imports lagrange, sympy, scipy and numpy: --python, else this one, else
${TMPDIR:-/tmp}/lagrange-python-bench-venv, which the script creates and fills (the
anchors' pinned SymPy, SciPy and numpy, and `pip install ./crates/python`, a release build
of a few minutes) unless --no-install or --no-build forbids it. The package measured is the
one that Python imports: rebuild it (`maturin develop --release -m crates/python/Cargo.toml`)
after changing the Rust side.

Every record goes as JSON lines to --out (and to stdout without --report); --report prints
the Markdown tables instead. The driver is standard library only; the measuring runs in
the chosen Python (`--worker`, not for people).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
DEFAULT_ANCHORS = next((p for p in (REPO.parent / "shared" / "bench", REPO.parent.parent / "shared" / "bench") if p.exists()),
                       REPO.parent / "shared" / "bench")
BENCH = "lagrange_python_api"
MODEL = "examples/double_pendulum.toml"
CHAIN = "examples/chain50.toml"
UNTIL = 20.0
RTOL, ATOL = 1e-9, 1e-12
REF_TOL = (1e-13, 1e-15)
SAMPLES = 1001  # the rows simulate() returns by default; SciPy's t_eval has the same times
CHECK_ROWS = {"1": 50, "20": 1000}  # t = 1 and t = 20 on that grid
Y0 = [2.0, 2.5, 0.0, 0.0]  # [a, b, a', b'] of the model file = the anchors' th1, th2
PARAMS = {"m1": 1.0, "m2": 1.0, "l1": 1.0, "l2": 1.0, "g": 9.81}  # the model file's mA, mB, lA, lB, g
IMPORTS = ("lagrange", "sympy", "scipy", "numpy")


def log(message: str) -> None:
    print(f"[python_api.py] {message}", file=sys.stderr, flush=True)


# ------------------------------------------------------------------ the whole calls (what a user writes)

# Each call is written as its user writes it, in three parts: the imports, the derivation
# (ours: reading and deriving the model; SymPy's: LagrangesMethod and lambdify) and the
# integration. The child clocks the last two itself (time.perf_counter between them), so the
# table can show where the whole process's time goes; the bare imports run alone too.
OURS_IMPORTS = """
import lagrange
"""

OURS_DERIVE = f"""
model = lagrange.load({MODEL!r})
"""

OURS_SOLVE = f"""
run = model.simulate(until={UNTIL!r}, rtol={RTOL!r})
"""

SCIPY_IMPORTS = """
import sys
sys.path.insert(0, ANCHORS)
import bench_common as bc
import numpy as np
import sympy
import sympy.physics.mechanics
from scipy.integrate import solve_ivp
"""

SCIPY_DERIVE = """
lagrangian, q, params = bc.pendulum_lagrangian(2)
_, mass, forcing = bc.derive(lagrangian, q)  # LagrangesMethod: M q'' = f
mass_fn, forcing_fn = bc.lambdify_mass_forcing(mass, forcing, q, params)
values = [1.0, 1.0, 1.0, 1.0, 9.81]


def rhs(t, y):
    acc = np.linalg.solve(mass_fn(y[:2], y[2:], values), forcing_fn(y[:2], y[2:], values).ravel())
    return np.concatenate((y[2:], acc))
"""

SCIPY_SOLVE = f"""
sol = solve_ivp(rhs, (0.0, {UNTIL!r}), {Y0!r}, method="DOP853", rtol={RTOL!r}, atol={ATOL!r},
                t_eval=np.linspace(0.0, {UNTIL!r}, {SAMPLES}))
"""

# What each call prints after the timed work, for the accuracy check: the state at the
# check rows, and its own clock. It is part of the timed process, and as small for both.
OURS_PRINT = f"""
import json
print(json.dumps({{"states": {{t: run.y[i].tolist() for t, i in {CHECK_ROWS!r}.items()}}, "rows": len(run),
                  "method": run.summary["method"], "steps": run.summary.get("steps"),
                  "derive_s": _derived - _start, "solve_s": _solved - _derived}}))
"""

SCIPY_PRINT = f"""
import json
print(json.dumps({{"states": {{t: sol.y[:, i].tolist() for t, i in {CHECK_ROWS!r}.items()}}, "rows": sol.t.size,
                  "method": "DOP853", "steps": sol.t.size - 1, "nfev": sol.nfev,
                  "derive_s": _derived - _start, "solve_s": _solved - _derived}}))
"""


def whole_call(imports: str, derive: str, solve: str, printing: str) -> str:
    """The user's script with the child's own clock between its parts."""
    return ("import time as _time\n" + imports + "_start = _time.perf_counter()\n" + derive
            + "_derived = _time.perf_counter()\n" + solve + "_solved = _time.perf_counter()\n" + printing)


def run_process(python: str, code: str, anchors: Path, timeout: float) -> dict:
    """One fresh interpreter running `code`: wall time from outside, the child's CPU time
    (user + system, os.wait4), its peak RSS, and the JSON line it printed (if any)."""
    code = f"ANCHORS = {str(anchors)!r}\n" + code
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    start = time.perf_counter()
    proc = subprocess.Popen([python, "-c", code], cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
    try:
        stdout, stderr = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        return {"error": f"stopped by the bench after {timeout:.0f} s"}
    wall = time.perf_counter() - start
    # communicate() has reaped the child; its rusage is in the children's total.
    return {"wall_s": wall, "exit": proc.returncode, "stdout": stdout.decode(), "stderr": stderr.decode()}


class ChildClock:
    """CPU seconds of the children reaped since the last reading (RUSAGE_CHILDREN deltas)."""

    def __init__(self) -> None:
        self.last = self.read()

    @staticmethod
    def read() -> float:
        import resource

        usage = resource.getrusage(resource.RUSAGE_CHILDREN)
        return usage.ru_utime + usage.ru_stime

    def lap(self) -> float:
        now = self.read()
        cpu, self.last = now - self.last, now
        return cpu


def measure_whole_calls(python: str, anchors: Path, repeats: int, timeout: float) -> list[dict]:
    """The four fresh-process cases in turn (A B C D, B C D A, ...), `repeats` timed runs each
    after one untimed warm-up of each (file cache, the extension loaded once from disk)."""
    cases = [("whole", "lagrange", whole_call(OURS_IMPORTS, OURS_DERIVE, OURS_SOLVE, OURS_PRINT)),
             ("whole", "sympy_scipy", whole_call(SCIPY_IMPORTS, SCIPY_DERIVE, SCIPY_SOLVE, SCIPY_PRINT)),
             ("import", "lagrange", OURS_IMPORTS), ("import", "sympy_scipy", SCIPY_IMPORTS)]
    samples: dict[tuple[str, str], list[dict]] = {(kind, tool): [] for kind, tool, _ in cases}
    clock = ChildClock()
    for round_ in range(repeats + 1):
        # Each round starts one case later, so that no case always follows the same one
        # (a process right after SymPy's 2-second one meets a warmer or a busier machine).
        for kind, tool, code in cases[round_ % len(cases):] + cases[:round_ % len(cases)]:
            clock.lap()
            result = run_process(python, code, anchors, timeout)
            result["cpu_s"] = clock.lap()
            if result.get("error") or result["exit"] != 0:
                message = result.get("error") or result["stderr"].strip().splitlines()[-1:]
                raise SystemExit(f"python_api.py: the {kind} call of {tool} failed: {message}")
            if round_ > 0:
                samples[(kind, tool)].append(result)
        log(f"whole calls: round {round_}/{repeats} done" + (" (warm-up)" if round_ == 0 else ""))
    records = []
    for (kind, tool), runs in samples.items():
        walls = [r["wall_s"] for r in runs]
        cpus = [r["cpu_s"] for r in runs]
        record = {"bench": BENCH, "record": kind, "tool": tool, "wall_s": statistics.median(walls),
                  "cpu_s": statistics.median(cpus), "wall_samples": walls, "cpu_samples": cpus}
        if kind == "whole":
            printed = [json.loads(r["stdout"].strip().splitlines()[-1]) for r in runs]
            derive = [p.pop("derive_s") for p in printed]
            solve = [p.pop("solve_s") for p in printed]
            record.update(until=UNTIL, rtol=RTOL, atol=ATOL, derive_s=statistics.median(derive),
                          solve_s=statistics.median(solve), derive_samples=derive, solve_samples=solve, **printed[-1])
        records.append(record)
    return records


# ------------------------------------------------------------------ the worker (runs in the chosen Python)


def worker(anchors: Path, repeats: int, calls: int, sympy_budget: float) -> None:
    """Part 2 and the references of part 1, in-process; JSON lines on stdout."""
    sys.dont_write_bytecode = True  # importing the anchors must not leave a __pycache__ beside them
    sys.path.insert(0, str(anchors))
    import bench_common as bc  # noqa: F401  (one BLAS thread, before numpy)
    import numpy as np
    import scipy_simulate as ss
    from scipy.integrate import solve_ivp

    import lagrange

    def emit(record: dict) -> None:
        print(json.dumps({"bench": BENCH, **record}), flush=True)

    def cpu_per_call(fn, y, number: int) -> list[float]:
        """CPU microseconds per call of fn(0.0, y), 5 samples of `number` calls."""
        out = []
        for _ in range(5):
            start = time.process_time()
            for _ in range(number):
                fn(0.0, y)
            out.append(1e6 * (time.process_time() - start) / number)
        return out

    emit({"record": "versions", "lagrange": lagrange.__version__, "lagrange_path": os.path.dirname(lagrange.__file__),
          "numpy": np.__version__, "sympy": __import__("sympy").__version__, "scipy": __import__("scipy").__version__,
          "python": platform.python_version()})

    # The references for part 1's accuracy check (not timed).
    model = lagrange.load(str(REPO / MODEL))
    tight = model.simulate(until=UNTIL, rtol=REF_TOL[0], atol=REF_TOL[1])
    system = ss.double_pendulum(cse_variant=False)  # derives and lambdifies; checks hand == lambdify
    grid = np.linspace(0.0, UNTIL, SAMPLES)
    hand_tight = solve_ivp(system.rhs["hand"], (0.0, UNTIL), np.array(Y0), method="DOP853", rtol=REF_TOL[0],
                           atol=REF_TOL[1], t_eval=grid)
    emit({"record": "reference", "tool": "lagrange", "method": tight.summary["method"], "rtol": REF_TOL[0],
          "atol": REF_TOL[1], "states": {t: tight.y[i].tolist() for t, i in CHECK_ROWS.items()}})
    emit({"record": "reference", "tool": "scipy_hand", "method": "DOP853", "rtol": REF_TOL[0], "atol": REF_TOL[1],
          "states": {t: hand_tight.y[:, i].tolist() for t, i in CHECK_ROWS.items()}})

    # Part 2: the integration alone, every callable prepared beforehand.
    ours = model.rhs()
    rng = np.random.default_rng(17)
    for y in rng.normal(size=(20, 4)) * 2:
        a, b = np.asarray(ours(0.0, y)), system.rhs["lambdify"](0.0, y)
        if not np.allclose(a, b, rtol=1e-9, atol=1e-9):
            raise SystemExit(f"python_api.py: model.rhs() and lambdify disagree at {y.tolist()}: {a} vs {b}")
    variants = {"lagrange_rhs": ours, "lambdify": system.rhs["lambdify"], "hand": system.rhs["hand"]}
    walls: dict[str, list[float]] = {v: [] for v in variants}
    cpus: dict[str, list[float]] = {v: [] for v in variants}
    solutions = {}
    for _ in range(repeats):
        for name, fn in variants.items():
            cpu0, wall0 = time.process_time(), time.perf_counter()
            sol = solve_ivp(fn, (0.0, UNTIL), np.array(Y0), method="DOP853", rtol=RTOL, atol=ATOL)
            walls[name].append(time.perf_counter() - wall0)
            cpus[name].append(time.process_time() - cpu0)
            solutions[name] = sol
    # Do the right-hand sides give the same motion? At t = 1 (untimed); at t = 20 the chaos has
    # amplified their rounding differences past any tolerance.
    at_one = {name: solve_ivp(fn, (0.0, 1.0), np.array(Y0), method="DOP853", rtol=RTOL, atol=ATOL).y[:, -1]
              for name, fn in variants.items()}
    probe = system.probe
    per_call = {name: cpu_per_call(fn, probe, calls) for name, fn in variants.items()}
    for name in variants:
        sol = solutions[name]
        emit({"record": "integration", "system": "double_pendulum", "rhs": name, "until": UNTIL, "rtol": RTOL,
              "atol": ATOL, "wall_s": statistics.median(walls[name]), "cpu_s": statistics.median(cpus[name]),
              "wall_samples": walls[name], "cpu_samples": cpus[name], "nfev": int(sol.nfev),
              "steps": int(sol.t.size - 1), "final": sol.y[:, -1].tolist(),
              "final_vs_lambdify": float(np.max(np.abs(sol.y[:, -1] - solutions["lambdify"].y[:, -1]))),
              "t1_vs_lambdify": float(np.max(np.abs(at_one[name] - at_one["lambdify"])))})
        emit({"record": "per_call", "system": "double_pendulum", "rhs": name, "calls": calls,
              "us": statistics.median(per_call[name]), "us_samples": per_call[name], "probe": probe.tolist()})

    # The 50-mass chain, per call, if SymPy derives it within the budget.
    chain_model = lagrange.load(str(REPO / CHAIN))
    chain_ours = chain_model.rhs()
    import signal

    def give_up(signum, frame):
        raise TimeoutError()

    signal.signal(signal.SIGALRM, give_up)
    signal.setitimer(signal.ITIMER_REAL, sympy_budget)
    start = time.perf_counter()
    try:
        chain = ss.chain(50)
    except TimeoutError:
        chain = None
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
    if chain is None:
        emit({"record": "per_call_skipped", "system": "chain50",
              "reason": f"SymPy's derivation and lambdify took more than {sympy_budget:g} s"})
        return
    emit({"record": "sympy_setup", "system": "chain50", "wall_s": time.perf_counter() - start, "derive_lambdify_s": chain.setup_s})
    y = chain.probe
    a, b = np.asarray(chain_ours(0.0, y)), chain.rhs["lambdify"](0.0, y)
    if not np.allclose(a, b, rtol=1e-9, atol=1e-9):
        raise SystemExit("python_api.py: model.rhs() and lambdify disagree on the chain")
    chain_number = max(calls // 10, 1000)
    for name, fn in {"lagrange_rhs": chain_ours, "lambdify": chain.rhs["lambdify"], "hand": chain.rhs["hand"]}.items():
        samples = cpu_per_call(fn, y, chain_number)
        emit({"record": "per_call", "system": "chain50", "rhs": name, "calls": chain_number,
              "us": statistics.median(samples), "us_samples": samples, "probe": "scipy_simulate.chain(50).probe"})


# ------------------------------------------------------------------ accuracy


def energy(y: list[float]) -> float:
    """H = T + V of the double pendulum (absolute angles, masses and lengths 1, g = 9.81)."""
    a, b, ad, bd = y
    m1, m2, l1, l2, g = (PARAMS[k] for k in ("m1", "m2", "l1", "l2", "g"))
    kinetic = 0.5 * (m1 + m2) * l1 * l1 * ad * ad + 0.5 * m2 * l2 * l2 * bd * bd + m2 * l1 * l2 * ad * bd * math.cos(a - b)
    potential = -(m1 + m2) * g * l1 * math.cos(a) - m2 * g * l2 * math.cos(b)
    return kinetic + potential


def max_abs(a: list[float], b: list[float]) -> float:
    return max(abs(x - y) for x, y in zip(a, b))


def accuracy_records(records: list[dict]) -> list[dict]:
    refs = {r["tool"]: r for r in records if r.get("record") == "reference"}
    out = []
    if len(refs) == 2:
        out.append({"bench": BENCH, "record": "reference_agreement",
                    **{f"t{t}": max_abs(refs["lagrange"]["states"][t], refs["scipy_hand"]["states"][t]) for t in CHECK_ROWS}})
    h0 = energy(Y0)
    for r in records:
        if r.get("record") != "whole":
            continue
        acc = {"bench": BENCH, "record": "accuracy", "tool": r["tool"],
               "energy_error_t20": abs(energy(r["states"]["20"]) - h0) / abs(h0)}
        for name, ref in refs.items():
            for t in CHECK_ROWS:
                acc[f"error_t{t}_vs_{name}"] = max_abs(r["states"][t], ref["states"][t])
        out.append(acc)
    return out


def ratio_records(records: list[dict]) -> list[dict]:
    def find(kind, **match):
        return next((r for r in records if r.get("record") == kind and all(r.get(k) == v for k, v in match.items())), None)

    out = []
    for kind in ("whole", "import"):
        ours, theirs = find(kind, tool="lagrange"), find(kind, tool="sympy_scipy")
        if ours and theirs:
            out.append({"bench": BENCH, "record": "ratio", "what": f"{kind}_call" if kind == "whole" else "import",
                        "wall": theirs["wall_s"] / ours["wall_s"], "cpu": theirs["cpu_s"] / ours["cpu_s"]})
    ours, theirs = find("integration", rhs="lagrange_rhs"), find("integration", rhs="lambdify")
    if ours and theirs:
        out.append({"bench": BENCH, "record": "ratio", "what": "solve_ivp_integration",
                    "wall": theirs["wall_s"] / ours["wall_s"], "cpu": theirs["cpu_s"] / ours["cpu_s"]})
    for system in ("double_pendulum", "chain50"):
        ours, theirs = find("per_call", system=system, rhs="lagrange_rhs"), find("per_call", system=system, rhs="lambdify")
        if ours and theirs:
            out.append({"bench": BENCH, "record": "ratio", "what": f"per_call_{system}", "cpu": theirs["us"] / ours["us"]})
    return out


# ------------------------------------------------------------------ the report


def fmt_s(seconds) -> str:
    if seconds is None:
        return "n/a"
    if seconds < 0.01:
        return f"{seconds * 1e3:.2f} ms"
    return f"{seconds * 1e3:.0f} ms" if seconds < 1 else f"{seconds:.2f} s"


def fmt_us(us) -> str:
    return f"{us:.2f} µs" if us < 10 else f"{us:.1f} µs"


def report(records: list[dict]) -> str:
    """The tables of a run's records, as the run printed them."""

    def find(kind, **match):
        return next((r for r in records if r.get("record") == kind and all(r.get(k) == v for k, v in match.items())), None)

    def ratio(what, key):
        r = find("ratio", what=what)
        return "n/a" if r is None or key not in r else f"**{r[key]:.1f}×**"

    machine = find("machine") or {}
    versions = find("versions") or {}
    text = [f"Started {machine.get('started', '?')} (`{machine.get('command', '?')}`, commit {machine.get('commit', '?')}) "
            f"on {machine.get('cpu', '?')}, "
            f"{machine.get('nproc', '?')} cores; Python {versions.get('python', '?')}, lagrange "
            f"{versions.get('lagrange', '?')}, SymPy {versions.get('sympy', '?')}, SciPy {versions.get('scipy', '?')}, "
            f"numpy {versions.get('numpy', '?')}. Ratios are SymPy + SciPy / lagrange (> 1: lagrange is faster).\n"]

    ours, theirs = find("whole", tool="lagrange"), find("whole", tool="sympy_scipy")
    if ours and theirs:
        io, it = find("import", tool="lagrange"), find("import", tool="sympy_scipy")
        text.append(f"## The double pendulum from Python, whole call (fresh process, t = 0..{UNTIL:g}, "
                    f"rtol = {RTOL:g}, atol = {ATOL:g}, {SAMPLES} rows)\n")
        text.append("| | lagrange | SymPy + SciPy | ratio |")
        text.append("| --- | ---: | ---: | ---: |")
        text.append(f"| whole call, wall (median of {len(ours['wall_samples'])}) | {fmt_s(ours['wall_s'])} "
                    f"| {fmt_s(theirs['wall_s'])} | {ratio('whole_call', 'wall')} |")
        text.append(f"| whole call, CPU | {fmt_s(ours['cpu_s'])} | {fmt_s(theirs['cpu_s'])} | {ratio('whole_call', 'cpu')} |")
        if io and it:
            text.append(f"| of which the imports alone, wall | {fmt_s(io['wall_s'])} | {fmt_s(it['wall_s'])} "
                        f"| {ratio('import', 'wall')} |")
        if "derive_s" in ours and "derive_s" in theirs:
            text.append(f"| in the process: derivation (load / LagrangesMethod + lambdify) | {fmt_s(ours['derive_s'])} "
                        f"| {fmt_s(theirs['derive_s'])} | {theirs['derive_s'] / ours['derive_s']:.0f}× |")
            text.append(f"| in the process: integration (simulate / solve_ivp), {SAMPLES} rows | {fmt_s(ours['solve_s'])} "
                        f"| {fmt_s(theirs['solve_s'])} | {theirs['solve_s'] / ours['solve_s']:.0f}× |")
        text.append(f"| method, steps | {ours['method']}, {ours['steps']:,} | DOP853, {theirs['steps']:,} "
                    f"({theirs['nfev']:,} RHS calls) | |")
        acc = {r["tool"]: r for r in records if r.get("record") == "accuracy"}
        refs = {r["tool"]: r for r in records if r.get("record") == "reference"}
        for name, label in (("lagrange", f"lagrange {refs.get('lagrange', {}).get('method', '?')}"),
                            ("scipy_hand", "DOP853 (hand-written RHS)")):
            if name not in refs:
                continue
            for t in CHECK_ROWS:
                key = f"error_t{t}_vs_{name}"
                text.append(f"| max \\|y − y_ref\\| at t = {t}, ref. {label} at {REF_TOL[0]:g}/{REF_TOL[1]:g} "
                            f"| {acc['lagrange'][key]:.1e} | {acc['sympy_scipy'][key]:.1e} | |")
        text.append(f"| \\|H − H₀\\|/\\|H₀\\| at t = {UNTIL:g} | {acc['lagrange']['energy_error_t20']:.1e} "
                    f"| {acc['sympy_scipy']['energy_error_t20']:.1e} | |")
        agree = find("reference_agreement")
        if agree:
            text.append("")
            text.append("The two references differ by " + ", ".join(f"{agree[f't{t}']:.1e} at t = {t}" for t in CHECK_ROWS)
                        + " (the double pendulum is chaotic: errors grow by e every 0.25 time units or so, so a "
                        "difference at t = 20 measures the chaos as much as the tolerance).")
        text.append("")

    integ = {r["rhs"]: r for r in records if r.get("record") == "integration"}
    calls = {(r["system"], r["rhs"]): r for r in records if r.get("record") == "per_call"}
    if integ:
        labels = {"lagrange_rhs": "`model.rhs()`", "lambdify": "lambdified SymPy M, f + `numpy.linalg.solve`",
                  "hand": "hand-written Python (`math`)"}
        text.append(f"## `model.rhs()` inside `solve_ivp` against `lambdify` (DOP853, t = 0..{UNTIL:g}, "
                    f"rtol = {RTOL:g}, atol = {ATOL:g}; callables prepared beforehand)\n")
        text.append("| right-hand side | integration, wall (median) | CPU | RHS calls | one call (CPU) "
                    "| solve_ivp's own share per call | lambdify / this (integration) |")
        text.append("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
        lam = integ.get("lambdify")
        for name, r in integ.items():
            one = calls.get(("double_pendulum", name))
            own = (r["cpu_s"] * 1e6 / r["nfev"] - one["us"]) if one else None
            rel = f"{lam['cpu_s'] / r['cpu_s']:.1f}×" if lam else "n/a"
            if name == "lagrange_rhs":
                rel = f"**{rel}**"
            text.append(f"| {labels.get(name, name)} | {fmt_s(r['wall_s'])} | {fmt_s(r['cpu_s'])} | {r['nfev']:,} "
                        f"| {fmt_us(one['us']) if one else 'n/a'} | {fmt_us(own) if own is not None else 'n/a'} | {rel} |")
        text.append("")
        near = max(r["t1_vs_lambdify"] for r in integ.values())
        far = max(r["final_vs_lambdify"] for r in integ.values())
        text.append(f"Median of {len(lam['wall_samples']) if lam else '?'} integrations each, in turn. The three give the "
                    f"same motion: their states at t = 1 agree to {near:.1e}; at t = 20 the chaos has amplified the "
                    f"rounding differences to {far:.1e}, hence the slightly different numbers of RHS calls. "
                    f"One call: at a fixed state as a numpy array, "
                    f"{next(iter(calls.values()))['calls']:,} calls a sample, median of 5. \"solve_ivp's own share\" is "
                    "the integration's CPU time per RHS call minus one call: the time DOP853's Python steps spend around "
                    "each call, which no right-hand side, however fast, takes off.\n")
        text.append(f"Per call: lambdify / `model.rhs()` = {ratio('per_call_double_pendulum', 'cpu')} (double pendulum)"
                    + (f", {ratio('per_call_chain50', 'cpu')} (50-mass chain)." if find("ratio", what="per_call_chain50") else "."))
        text.append("")
    chain = [calls[k] for k in calls if k[0] == "chain50"]
    if chain:
        setup = find("sympy_setup", system="chain50")
        text.append("## One call of the 50-mass chain's right-hand side (100 components)\n")
        text.append("| right-hand side | one call (CPU) | lambdify / this |")
        text.append("| --- | ---: | ---: |")
        lam = calls.get(("chain50", "lambdify"))
        labels = {"lagrange_rhs": "`model.rhs()`", "lambdify": "lambdified SymPy M, f + `numpy.linalg.solve`",
                  "hand": "hand-written Python (vectorised numpy)"}
        for r in chain:
            text.append(f"| {labels.get(r['rhs'], r['rhs'])} | {fmt_us(r['us'])} | {lam['us'] / r['us']:.1f}× |")
        if setup:
            text.append("")
            text.append(f"SymPy's derivation + lambdify of the chain took {fmt_s(setup['derive_lambdify_s'])}.")
        text.append("")
    skipped = find("per_call_skipped")
    if skipped:
        text.append(f"The 50-mass chain's per-call cost was skipped: {skipped['reason']}.\n")
    return "\n".join(text)


# ------------------------------------------------------------------ choosing the Python


def can_import(python: str, modules) -> bool:
    code = "; ".join(f"import {m}" for m in modules)
    try:
        return subprocess.run([python, "-c", code], capture_output=True, timeout=300, cwd="/").returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        return False


def pinned(anchors: Path) -> list[str]:
    """The anchors' pinned SymPy, mpmath, SciPy and numpy (requirements.txt)."""
    path = anchors / "requirements.txt"
    if not path.exists():
        return ["sympy", "scipy", "numpy"]
    return [line.split("#", 1)[0].strip() for line in path.read_text().splitlines() if "==" in line.split("#", 1)[0]]


def bench_python(anchors: Path, allow_install: bool) -> str | None:
    """A Python that imports lagrange, sympy, scipy and numpy: this one, the bench venv,
    or that venv after installing the anchors' pins and the package (a release build)."""
    if can_import(sys.executable, IMPORTS):
        return sys.executable
    venv = Path(os.environ.get("TMPDIR") or "/tmp") / "lagrange-python-bench-venv"
    python = venv / "bin" / "python"
    if python.exists() and can_import(str(python), IMPORTS):
        return str(python)
    if not allow_install:
        log(f"no Python imports {', '.join(IMPORTS)}; give --python, or allow the bench to fill {venv}")
        return None
    try:
        if not python.exists():
            log(f"creating {venv}")
            subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
        log(f"installing {' '.join(pinned(anchors))} and ./crates/python into {venv} (a release build, minutes)")
        subprocess.run([str(python), "-m", "pip", "install", "--quiet", *pinned(anchors), str(REPO / "crates" / "python")],
                       check=True, timeout=3600)
    except (OSError, subprocess.SubprocessError) as err:
        log(f"cannot set up {venv}: {err}")
    return str(python) if python.exists() and can_import(str(python), IMPORTS) else None


# ------------------------------------------------------------------ main


def machine_record(argv) -> dict:
    cpu = None
    try:
        cpu = next((line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo") if line.startswith("model name")), None)
    except OSError:
        pass
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=REPO, capture_output=True, text=True).stdout.strip()
    return {"bench": BENCH, "record": "machine", "nproc": os.cpu_count(), "cpu": cpu, "platform": platform.platform(),
            "commit": commit or None, "started": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
            "command": " ".join([Path(sys.argv[0]).name, *(argv if argv is not None else sys.argv[1:])])}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="a smoke run: 3 repeats, 10^4 calls a sample, chain budget 30 s")
    parser.add_argument("--repeats", type=int, default=None, help="timed runs per case (median; default 7, 3 with --quick)")
    parser.add_argument("--calls", type=int, default=None, help="calls per per-call sample (default 10^5, 10^4 with --quick)")
    parser.add_argument("--sympy-budget", type=float, default=None,
                        help="seconds SymPy may take to derive and lambdify the chain (default 120; 30 with --quick)")
    parser.add_argument("--python", default=None, help="the Python that imports lagrange, sympy, scipy and numpy")
    parser.add_argument("--no-install", action="store_true", help="never create or fill the bench venv")
    parser.add_argument("--no-build", action="store_true", help="never build the package (implies --no-install)")
    parser.add_argument("--anchors", type=Path, default=DEFAULT_ANCHORS, help="folder of bench_common.py, scipy_simulate.py")
    parser.add_argument("--report", nargs="?", type=Path, const=True, default=None,
                        help="print Markdown tables instead of JSON lines; with FILE, those of an earlier run's --out, "
                             "running nothing")
    parser.add_argument("--timeout", type=float, default=600.0, help="seconds per fresh process or worker")
    parser.add_argument("--out", type=Path, default=Path(os.environ.get("TMPDIR") or "/tmp") / "lagrange-python-api.jsonl")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    repeats = args.repeats or (3 if args.quick else 7)
    calls = args.calls or (10**4 if args.quick else 10**5)
    budget = args.sympy_budget or (30.0 if args.quick else 120.0)

    if args.worker:
        worker(args.anchors, repeats, calls, budget)
        return 0
    if isinstance(args.report, Path):
        print(report([json.loads(line) for line in args.report.read_text().splitlines() if line.strip()]))
        return 0
    if not (args.anchors / "bench_common.py").exists():
        log(f"{args.anchors} has no bench_common.py (give --anchors)")
        return 2
    python = args.python or bench_python(args.anchors, allow_install=not (args.no_install or args.no_build))
    if python is None:
        return 1
    log(f"measuring with {python}")
    records = [machine_record(argv)]
    records += measure_whole_calls(python, args.anchors, repeats, args.timeout)
    log("in-process: references, solve_ivp, per call")
    proc = subprocess.run([python, str(Path(__file__).resolve()), "--worker", "--anchors", str(args.anchors),
                           "--repeats", str(repeats), "--calls", str(calls), "--sympy-budget", str(budget)],
                          cwd=REPO, stdout=subprocess.PIPE, text=True, timeout=args.timeout * 3,
                          env=dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1"))
    records += [json.loads(line) for line in proc.stdout.splitlines() if line.startswith("{")]
    status = 0 if proc.returncode == 0 else 1
    if status:
        log(f"the in-process part failed (exit {proc.returncode}); the records so far are kept")
    records += accuracy_records(records)
    records += ratio_records(records)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with args.out.open("w") as f:
        for r in records:
            f.write(json.dumps(r) + "\n")
    if args.report:
        print(report(records))
    else:
        for r in records:
            print(json.dumps(r))
    log(f"records in {args.out}")
    return status


if __name__ == "__main__":
    sys.exit(main())
