#!/usr/bin/env python3
"""The measurements behind `lagrange simulate`'s default method (issue #16), in one run.

    python3 bench/default_method.py            # the full run (about 5-8 minutes on 2 cores)
    python3 bench/default_method.py --quick    # a few minutes: 3 repeats, t = 10^4, 16 bodies
    python3 bench/default_method.py --report RUN.jsonl   # the tables of an earlier run again

What it does, in order (every run is the whole `lagrange simulate` process, timed from
outside as bench/simulate.py times it: time.perf_counter() around subprocess.run):

1. **Per system, per method.** For the six bench systems (the double pendulum, the
   50-mass chain, Kepler, the heavy top, a rheonomic model -- the pendulum with a shaken
   pivot, bench/models/shaken_pendulum.toml -- and a dissipative one, the damped
   oscillator) it runs the default (no --method) and taylor, dop853, dopri5, gauss6,
   gauss4 and kahanli8 (where H is separable; refused otherwise) at rtol = atol = 1e-10
   to t = 100, writing the 1001-row CSV: median whole-process wall time of --repeats
   runs; the largest relative drift of every conserved invariant, at the steps (one more
   run with --every-step) and at the 1001 rows; and the trajectory error at t = 10
   against a reference (taylor at rtol = atol = 1e-15, cross-checked with dop853 at
   1e-14): max_i |y_i - y_ref,i| / (atol + rtol * max_{t<=10} |y_ref,i|) over the
   coordinates and velocities, so 1 means "as accurate as the tolerance asks". Then, per
   method, its time over the fastest method's whose error is equal or smaller (the
   energy drift where H is conserved, the trajectory error where it is not), and a flag
   on the default when that ratio exceeds 2.
2. **Long horizon.** The default, gauss6 and kahanli8 (where H is separable) at rtol
   1e-10, and the default at 1e-12 and 1e-14, to t = 10^5 (--samples 11) on the double
   pendulum, Kepler, the heavy top and the chain: wall time and energy drift (at the 11
   rows). A run refused by the step budget is reported as such. A run whose pace at
   t = 100 (part 1) says it would take longer than --long-budget seconds is given 20 s at
   the whole horizon (the step budget refuses before integrating), then run to the
   largest power of ten that fits, and the table says so.
3. **Robustness.** (a) crates/cli/tests/robust/cubic_runaway.toml (the issue's runaway model) to t = 3
   under the default and every method: t reached and u(3), against SciPy's DOP853 at
   rtol = atol = 1e-12 on the hand-written ODE (cross-checked at 1e-13), computed in the
   anchors' venv. (b) --bodies random rigid bodies (seeded): principal moments about
   the centre of mass satisfying the triangle inequality, a random mass, either heavy (a
   random centre-of-mass offset from a fixed pivot, gravity; the tensor about the pivot
   by the parallel-axis theorem) or free (no offset, no gravity), random Euler angles and
   rates; a third of them aimed to pass the Euler-angle singularity at a distance
   |sin(beta)| between 0.002 and 0.1. Each runs
   to t = --body-until under the default, gauss6 and dop853 at rtol = atol = 1e-10,
   against a reference (taylor at 1e-14, every step; dop853 at 1e-13 must agree with it
   to 1e-10 of the state's scale, else the body is not scored). Per method: runs stopped
   by the gimbal guard before the reference is, runs whose H drift or final-state error
   (the measure of part 1, at t_end) exceeds 100 (x rtol), and the worst of each.

Everything is printed as Markdown tables and written as JSON lines to --out. Standard
library only on our side; SciPy runs in the anchors' venv (bench/derive.py's logic).
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import platform
import random
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.dont_write_bytecode = True  # importing derive.py must not leave bench/__pycache__
sys.path.insert(0, str(Path(__file__).resolve().parent))

import derive as derive_bench  # noqa: E402  (ensure_binary, anchor_python)

REPO = Path(__file__).resolve().parent.parent
DEFAULT_ANCHORS = next((p for p in (REPO.parent / "shared" / "bench", REPO.parent.parent / "shared" / "bench") if p.exists()),
                       REPO.parent / "shared" / "bench")
BENCH = "lagrange_default_method"
RTOL = 1e-10

# (name, model file, kind, t_check): kind says what measures accuracy (the energy where H
# is conserved, the trajectory error where not); t_check is where the trajectory is
# compared with the reference: t = 10, but t = 1 for the chaotic double pendulum, whose
# neighbouring motions separate by e in 0.25 time units (at t = 10 even the two
# references, taylor at 1e-15 and dop853 at 1e-14, differ by 10^3 x the tolerance 1e-10).
SYSTEMS = [
    ("double_pendulum", "examples/double_pendulum.toml", "conservative", 1.0),
    ("chain50", "examples/chain50.toml", "conservative", 10.0),
    ("kepler", "examples/kepler.toml", "conservative", 10.0),
    ("heavy_top", "examples/tops/heavy_top.toml", "conservative", 10.0),
    ("shaken_pendulum", "bench/models/shaken_pendulum.toml", "rheonomic", 10.0),
    ("damped_oscillator", "examples/damped_oscillator.toml", "dissipative", 10.0),
]
METHODS = ["default", "taylor", "dop853", "dopri5", "gauss6", "gauss4", "kahanli8"]
LONG_SYSTEMS = ["double_pendulum", "kepler", "heavy_top", "chain50"]
RUNAWAY = "crates/cli/tests/robust/cubic_runaway.toml"
RUNAWAY_SCIPY_ISSUE = -714.25234


def log(message: str) -> None:
    print(f"[default_method.py] {message}", file=sys.stderr, flush=True)


# ------------------------------------------------------------------ running ours


def simulate(binary: Path, model: str, until: float, rtol: float, method: str | None, out: str | None,
             extra=(), timeout: float = 600.0) -> dict:
    """One whole `lagrange simulate` process: its summary (when it printed one), exit code,
    stderr and the wall time from outside."""
    args = [str(binary), "simulate", model, "--until", repr(until), "--rtol", repr(rtol), "--atol", repr(rtol),
            "--summary", "json", *extra]
    if method is not None:
        args += ["--method", method]
    if out is not None:
        args += ["--out", out]
    start = time.perf_counter()
    try:
        proc = subprocess.run(args, cwd=REPO, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"exit": None, "error": f"stopped by the bench after {timeout:.0f} s", "wall_s": None}
    wall = time.perf_counter() - start
    try:
        summary = json.loads(proc.stdout) if proc.stdout.strip() else None
    except json.JSONDecodeError:
        summary = None
    return {"exit": proc.returncode, "summary": summary, "stderr": proc.stderr.strip(), "wall_s": wall,
            "error": None if proc.returncode == 0 else first_error(proc.stderr)}


def first_error(stderr: str) -> str:
    lines = [line for line in stderr.splitlines() if line.startswith("error")]
    line = lines[0] if lines else stderr.strip().splitlines()[-1] if stderr.strip() else "no message"
    return re.sub(r"^error: [^ ]+\.toml: ", "error: ", line)[:400]


def read_csv(path: str) -> tuple[list[str], list[list[float]]]:
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], [[float(v) for v in row] for row in rows[1:]]


def state_columns(header: list[str], summary: dict) -> list[int]:
    """The columns of the coordinates and velocities (the keys of the summary's `final`)."""
    names = set((summary or {}).get("final") or {})
    return [k for k, name in enumerate(header) if name in names]


def row_at(rows: list[list[float]], t: float) -> list[float]:
    return min(rows, key=lambda r: abs(r[0] - t))


def scaled_error(y, y_ref, scale, rtol: float) -> float:
    """max_i |y_i - y_ref,i| / (atol + rtol * scale_i), atol = rtol: 1 is the tolerance."""
    return max(abs(a - b) / (rtol + rtol * s) for a, b, s in zip(y, y_ref, scale))


def conserved_drifts(summary: dict | None) -> dict:
    return {name: a["max_rel_drift"] for name, a in ((summary or {}).get("invariants") or {}).items() if a["conserved"]}


# ------------------------------------------------------------------ 1. systems x methods


class Reference:
    """The reference trajectory of one system on the 1001-row grid to t = 100."""

    def __init__(self, binary: Path, model: str, workdir: Path, t_check: float):
        self.t_check = t_check
        ref_csv, check_csv = str(workdir / "ref.csv"), str(workdir / "check.csv")
        run = simulate(binary, model, 100.0, 1e-15, "taylor", ref_csv)
        check = simulate(binary, model, 100.0, 1e-14, "dop853", check_csv)
        if run["exit"] != 0 or check["exit"] != 0:
            raise RuntimeError(f"reference runs of {model} failed: {run['error'] or check['error']}")
        header, rows = read_csv(ref_csv)
        self.columns = state_columns(header, run["summary"])
        self.names = [header[k] for k in self.columns]
        window = [r for r in rows if r[0] <= t_check + 1e-9]
        self.scale = [max(abs(r[k]) for r in window) for k in self.columns]
        self.y = [row_at(rows, t_check)[k] for k in self.columns]
        _, check_rows = read_csv(check_csv)
        # the disagreement of the two references, on the scale of rtol 1e-10
        self.cross_check = self.error(check_rows)

    def error(self, rows: list[list[float]]) -> float:
        y = [row_at(rows, self.t_check)[k] for k in self.columns]
        return scaled_error(y, self.y, self.scale, RTOL)


def measure_systems(binary: Path, repeats: int, workdir: Path) -> list[dict]:
    records = []
    for system, model, kind, t_check in SYSTEMS:
        ref = Reference(binary, model, workdir, t_check)
        log(f"{system}: reference taylor 1e-15 vs dop853 1e-14 disagree by {ref.cross_check:.2g} "
            f"(x tolerance 1e-10) at t = {t_check:g}")
        records.append({"bench": BENCH, "record": "reference", "system": system, "model": model, "t_check": t_check,
                        "components": ref.names, "scale": ref.scale, "cross_check": ref.cross_check})
        runs = []
        # First each method once: the CSV it writes, its invariants at the steps, or its refusal.
        for method in METHODS:
            requested = None if method == "default" else method
            out = str(workdir / f"{system}-{method}.csv")
            first = simulate(binary, model, 100.0, RTOL, requested, out)
            record = {"bench": BENCH, "record": "run", "system": system, "model": model, "kind": kind,
                      "requested": method, "rtol": RTOL, "atol": RTOL, "t_end": 100.0, "t_check": t_check}
            if first["exit"] != 0:
                record.update(method=None, error=first["error"], refused=first["exit"] == 2)
                log(f"{system} {method}: {first['error']}")
                runs.append(record)
                continue
            summary = first["summary"]
            _, rows = read_csv(out)
            steps_run = simulate(binary, model, 100.0, RTOL, requested, None, extra=["--every-step"])
            drift_steps = conserved_drifts(steps_run["summary"])
            drift_rows = conserved_drifts(summary)
            record.update(
                first_wall_s=first["wall_s"],
                method=summary["method"], dt=summary.get("dt"), steps=summary["steps"],
                rhs_evaluations=summary["rhs_evaluations"], tolerance_controls=summary.get("tolerance_controls"),
                wall_samples=[], drift_steps=drift_steps, drift_rows=drift_rows,
                energy_drift=drift_steps.get("H") if "H" in drift_steps else None,
                max_invariant_drift=max(list(drift_steps.values()) + list(drift_rows.values()), default=None),
                trajectory_error=ref.error(rows), warnings=summary.get("warnings"), error=None)
            runs.append(record)
        # Then the timed repeats, the methods in turn (A B C A B C ...), so that a slow
        # spell of the shared machine falls on all of them alike.
        timed = [r for r in runs if r["error"] is None]
        for r in timed:
            # at least --repeats runs; more for the fast ones (about half a second's worth, at most 3x)
            r["repeats"] = min(max(repeats, int(0.5 / max(r.pop("first_wall_s"), 1e-3))), 3 * repeats)
        for round_ in range(3 * repeats):
            for r in timed:
                if round_ >= r["repeats"]:
                    continue
                run = simulate(binary, model, 100.0, RTOL, None if r["requested"] == "default" else r["requested"],
                               str(workdir / f"{system}-{r['requested']}.csv"))
                if run["exit"] == 0:
                    r["wall_samples"].append(run["wall_s"])
        for r in timed:
            walls = r["wall_samples"]
            r.update(process_wall_s=statistics.median(walls), process_wall_min_s=min(walls),
                     process_wall_max_s=max(walls))
            log(f"{system} {r['requested']} -> {r['method']}: {fmt_s(r['process_wall_s'])} "
                f"H drift {fmt_e(r['energy_drift'])} trajectory error {r['trajectory_error']:.3g}")
        add_ratios(runs)
        records += runs
    return records


def accuracy(record: dict) -> float | None:
    """What "equal or better" compares: the energy drift where H is conserved, else the
    trajectory error at t = 10 (in units of the tolerance)."""
    return record["energy_drift"] if record["kind"] == "conservative" else record["trajectory_error"]


def add_ratios(runs: list[dict]) -> None:
    ok = [r for r in runs if r.get("error") is None]
    for r in ok:
        mine = accuracy(r)
        rivals = [s for s in ok if s["requested"] != "default" and accuracy(s) is not None and mine is not None
                  and accuracy(s) <= mine]
        best = min(rivals + [r], key=lambda s: s["process_wall_s"])
        r["fastest_at_equal_or_better"] = best["requested"]
        r["ratio_to_fastest"] = r["process_wall_s"] / best["process_wall_s"]
        r["flag"] = r["requested"] == "default" and r["ratio_to_fastest"] > 2.0


def systems_table(records: list[dict]) -> str:
    lines = ["| system | method | steps | process wall (median) | H drift (steps) | other invariants' drift (steps) "
             "| trajectory error at t_check (× tol) | / fastest at equal or better error |",
             "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |"]
    refs = {r["system"]: r for r in records if r.get("record") == "reference"}
    for r in records:
        if r.get("record") != "run":
            continue
        label = r["requested"] if r["requested"] != "default" else f"default ({r.get('method') or '?'})"
        if r.get("error"):
            lines.append(f"| {r['system']} | {label} | – | {'refused' if r.get('refused') else 'failed'}: "
                         f"{short(r['error'], 64)} | | | | |")
            continue
        if r.get("dt"):
            label += f", dt {r['dt']:.3g}"
        others = {k: v for k, v in r["drift_steps"].items() if k != "H"}
        other = ", ".join(f"{k} {v:.1e}" for k, v in others.items()) or "–"
        best = r["fastest_at_equal_or_better"]
        ratio = f"{r['ratio_to_fastest']:.2f}× ({'itself' if best == r['requested'] else best})"
        if r["flag"]:
            ratio = f"**{ratio} > 2×**"
        lines.append(f"| {r['system']} | {label} | {r['steps']:,} | {fmt_s(r['process_wall_s'])} "
                     f"| {fmt_e(r['energy_drift']) if r['kind'] == 'conservative' else 'not conserved'} | {other} "
                     f"| {r['trajectory_error']:.2g} | {ratio} |")
    lines.append("")
    lines.append("t_check = " + ", ".join(f"{s} {r['t_check']:g}" for s, r in refs.items())
                 + ". References (taylor at 1e-15; its disagreement with dop853 at 1e-14 at t_check, × tol 1e-10): "
                 + "; ".join(f"{s} {r['cross_check']:.1e}" for s, r in refs.items()) + ".")
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------------ 2. long horizon


def measure_long(binary: Path, until: float, budget: float, part1: list[dict], workdir: Path) -> list[dict]:
    pace = {(r["system"], r["requested"]): r["process_wall_s"] for r in part1
            if r.get("record") == "run" and r.get("error") is None}
    separable = {r["system"] for r in part1 if r.get("record") == "run" and r["requested"] == "kahanli8"
                 and r.get("error") is None}
    models = {s: m for s, m, _, _ in SYSTEMS}
    records = []
    for system in LONG_SYSTEMS:
        cases = [("default", RTOL), ("gauss6", RTOL)] + ([("kahanli8", RTOL)] if system in separable else []) \
            + [("default", 1e-12), ("default", 1e-14)]
        for method, rtol in cases:
            horizon = until
            per_100 = pace.get((system, method)) if rtol == RTOL else None
            requested = None if method == "default" else method
            run = None
            if per_100 is not None and per_100 * until / 100.0 > budget:
                # Its pace says it would take too long: give the whole horizon a short try
                # (the step budget refuses a run before it starts), then run it shorter.
                probe = simulate(binary, models[system], until, rtol, requested, str(workdir / "long.csv"),
                                 extra=["--samples", "11"], timeout=min(budget, 20.0))
                if probe["exit"] is not None:
                    run = probe
                else:
                    while per_100 * horizon / 100.0 > budget and horizon > 100.0:
                        horizon /= 10.0
            if run is None:
                run = simulate(binary, models[system], horizon, rtol, requested, str(workdir / "long.csv"),
                               extra=["--samples", "11"], timeout=budget * 3)
            summary = run.get("summary") or {}
            refused = run["exit"] == 2 and "steps a run may take" in (run.get("stderr") or "")
            record = {"bench": BENCH, "record": "long", "system": system, "requested": method, "rtol": rtol,
                      "t_end": horizon, "shortened": horizon < until, "method": summary.get("method"),
                      "dt": summary.get("dt"), "steps": summary.get("steps"), "t_final": summary.get("t_final"),
                      "process_wall_s": run["wall_s"], "drifts": conserved_drifts(summary),
                      "error": run["error"], "refused": bool(run["error"]) and refused}
            log(f"long {system} {method} rtol {rtol:g} to {horizon:g}: "
                + (run["error"] or f"{fmt_s(run['wall_s'])}, H drift {fmt_e(record['drifts'].get('H'))}"))
            records.append(record)
    return records


def long_table(records: list[dict], until: float) -> str:
    lines = ["| system | method | rtol | t_end | steps | process wall | max rel. drift (11 rows) |",
             "| --- | --- | --- | ---: | ---: | ---: | --- |"]
    for r in records:
        label = r["requested"] if r["requested"] != "default" else f"default ({r.get('method') or '?'})"
        if r.get("dt"):
            label += f", dt {r['dt']:.3g}"
        t_end = f"{r['t_end']:g}" + (f" (not {until:g}: its pace)" if r["shortened"] else "")
        if r["error"]:
            what = "refused by the step budget" if r["refused"] else "failed"
            lines.append(f"| {r['system']} | {label} | {r['rtol']:g} | {t_end} | – | {what}: {short(r['error'])} | |")
            continue
        drift = ", ".join(f"{k} {v:.1e}" for k, v in r["drifts"].items())
        lines.append(f"| {r['system']} | {label} | {r['rtol']:g} | {t_end} | {r['steps']:,} "
                     f"| {fmt_s(r['process_wall_s'])} | {drift} |")
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------------ 3a. the runaway model

SCIPY_RUNAWAY = r"""
import json, math, time
from scipy.integrate import solve_ivp
m, l = 0.508289, 1.226315
def rhs(t, y):
    u, v = y
    s, c = math.sin(u), math.cos(u)
    # m*(1 + 0.2 s^2) u'' + 0.2 m s c u'^2 = -(l c + u^2/2); the term 0.5 u^2 u' is a total derivative
    return [v, (-(l * c + u * u / 2) - 0.2 * m * s * c * v * v) / (m * (1 + 0.2 * s * s))]
out = []
for rtol in (1e-12, 1e-13):
    start = time.perf_counter()
    sol = solve_ivp(rhs, (0.0, 3.0), [0.423913, -0.318997], method="DOP853", rtol=rtol, atol=rtol)
    out.append({"rtol": rtol, "status": int(sol.status), "t_final": float(sol.t[-1]), "u": float(sol.y[0, -1]),
                "u_dot": float(sol.y[1, -1]), "wall_s": time.perf_counter() - start, "nfev": int(sol.nfev)})
print(json.dumps(out))
"""


def measure_runaway(binary: Path, python: str | None) -> list[dict]:
    records = []
    scipy = None
    if python is not None:
        proc = subprocess.run([python, "-c", SCIPY_RUNAWAY], capture_output=True, text=True, timeout=300)
        if proc.returncode == 0:
            scipy = json.loads(proc.stdout)
            for s in scipy:
                records.append({"bench": BENCH, "record": "runaway_scipy", **s})
                log(f"runaway SciPy DOP853 rtol {s['rtol']:g}: t = {s['t_final']}, u(3) = {s['u']!r}")
        else:
            log(f"SciPy's runaway run failed: {proc.stderr.strip()[-300:]}")
    listing = subprocess.run([str(binary), "simulate", "--list-methods"], capture_output=True, text=True).stdout
    methods = ["default"] + [line.split()[0] for line in listing.splitlines() if line.strip()]
    for method in methods:
        run = simulate(binary, RUNAWAY, 3.0, RTOL, None if method == "default" else method, None, timeout=300)
        summary = run.get("summary") or {}
        final = summary.get("final") or {}
        records.append({"bench": BENCH, "record": "runaway", "requested": method, "method": summary.get("method"),
                        "rtol": RTOL, "exit": run["exit"], "t_final": summary.get("t_final"), "u": final.get("u"),
                        "dt": summary.get("dt"), "steps": summary.get("steps"), "process_wall_s": run["wall_s"],
                        "error": run["error"], "failure": summary.get("failure")})
        log(f"runaway {method}: exit {run['exit']}, t = {summary.get('t_final')}, u = {final.get('u')}")
    return records


def runaway_table(records: list[dict]) -> str:
    scipy = [r for r in records if r["record"] == "runaway_scipy"]
    ref = scipy[0]["u"] if scipy else RUNAWAY_SCIPY_ISSUE
    lines = ["| method | exit | t reached | u(t reached) | relative error of u(3) | process wall | what stopped it |",
             "| --- | ---: | ---: | ---: | ---: | ---: | --- |"]
    for r in records:
        if r["record"] != "runaway":
            continue
        label = r["requested"] if r["requested"] != "default" else f"default ({r.get('method') or '?'})"
        if r.get("dt"):
            label += f", dt {r['dt']:.3g}"
        reached = r["t_final"] is not None and abs(r["t_final"] - 3.0) < 1e-12
        rel = f"{abs(r['u'] - ref) / abs(ref):.1e}" if reached and r["u"] is not None else "–"
        stop = short(r["error"], 100) if r["error"] else ""
        lines.append(f"| {label} | {r['exit']} | {fmt_opt(r['t_final'], '.6g')} | {fmt_opt(r['u'], '.8g')} | {rel} "
                     f"| {fmt_s(r['process_wall_s'])} | {stop} |")
    for s in scipy:
        lines.append(f"| SciPy DOP853 hand-written, rtol = atol = {s['rtol']:g} | {s['status']} | {s['t_final']:.6g} "
                     f"| {s['u']:.8g} | {abs(s['u'] - ref) / abs(ref):.1e} | {fmt_s(s['wall_s'])} (integration) | |")
    lines.append("")
    lines.append(f"Relative errors against SciPy's DOP853 at rtol = atol = 1e-12 (u(3) = {ref!r}; the issue quotes "
                 f"{RUNAWAY_SCIPY_ISSUE}).")
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------------ 3b. random rigid bodies


def random_body(rng: random.Random, index: int) -> tuple[str, dict]:
    """A seeded random rigid body: model text and what it is."""
    while True:
        moments = [rng.uniform(0.3, 3.0) for _ in range(3)]
        a, b, c = sorted(moments)
        if a + b >= c * 1.02:  # the triangle inequality, with a margin
            break
    mass = rng.uniform(0.5, 3.0)
    heavy = index % 2 == 0
    offset = [rng.uniform(-0.5, 0.5) for _ in range(3)] if heavy else [0.0, 0.0, 0.0]
    # the tensor about the pivot: I_cm + M (|c|^2 1 - c c^T)
    c2 = sum(x * x for x in offset)
    tensor = [[(moments[i] if i == j else 0.0) + mass * ((c2 if i == j else 0.0) - offset[i] * offset[j])
               for j in range(3)] for i in range(3)]
    near = index % 3 == 1
    alpha_dot = rng.uniform(-2.0, 2.0)
    if near:
        # Near the pole the body's 3-axis moves about on the sphere almost in a straight
        # line in the plane (beta cos(alpha), beta sin(alpha)): started at beta0 = 0.3 and
        # aimed to pass the pole at a distance d (|sin(beta)| from 0.002 to 0.1 at its
        # closest), radial rate -v cos(phi), tangential beta0 alpha' = v sin(phi), with
        # sin(phi) = d / beta0. Gravity, the spin and the asymmetry bend the path: the
        # table reports the reference's own min |sin(beta)|.
        d = math.exp(rng.uniform(math.log(0.002), math.log(0.1)))
        speed = rng.uniform(0.5, 2.0)
        phi = math.asin(d / 0.3)
        beta, beta_dot, alpha_dot = 0.3, -speed * math.cos(phi), speed * math.sin(phi) / 0.3
        if rng.random() < 0.5:  # the other pole
            beta, beta_dot = math.pi - beta, -beta_dot
    else:
        beta = rng.uniform(0.3, math.pi - 0.3)
        beta_dot = rng.uniform(-2.0, 2.0)
    initial = {"al": rng.uniform(0, 2 * math.pi), "al'": alpha_dot, "be": beta, "be'": beta_dot,
               "ga": rng.uniform(0, 2 * math.pi), "ga'": rng.uniform(-5.0, 5.0) if not near else rng.uniform(-1.0, 1.0)}
    rows = ", ".join("[" + ", ".join(f'"{v!r}"' for v in row) + "]" for row in tensor)
    text = "\n".join([
        f'name = "random rigid body {index}"',
        'coordinates = ["al", "be", "ga"]',
        *(['gravity = "g"', "", "[parameters]", "g = 9.81"] if heavy else []),
        "",
        "[[bodies]]",
        f'mass = "{mass!r}"',
        f"inertia = [{rows}]",
        'angles = ["al", "be", "ga"]',
        'position = ["0", "0", "0"]',
        "center_of_mass = [" + ", ".join(f'"{x!r}"' for x in offset) + "]",
        "",
        "[initial]",
        *[f'"{k}" = {v!r}' for k, v in initial.items()],
        "",
    ])
    return text, {"index": index, "heavy": heavy, "near_singularity": near, "moments": moments, "mass": mass,
                  "offset": offset, "initial": initial}


def stopped_early(t_final, ref_t: float, dt) -> bool:
    """Whether a run ended before the reference did, by more than 10^-3 or two of its fixed
    steps (a fixed-step run stops at the end of a step)."""
    return t_final is not None and t_final < ref_t - max(1e-3, 2 * (dt or 0.0))


def gimbal(run: dict) -> bool:
    text = ((run.get("summary") or {}).get("failure") or "") + (run.get("error") or "")
    return "sin" in text and ("β" in text or "be" in text or "Euler" in text)


def measure_bodies(binary: Path, count: int, until: float, seed: int, workdir: Path) -> list[dict]:
    rng = random.Random(seed)
    records = []
    for index in range(count):
        text, info = random_body(rng, index)
        model = workdir / f"body_{index}.toml"
        model.write_text(text)
        ref_csv = str(workdir / "body_ref.csv")
        ref = simulate(binary, str(model), until, 1e-14, "taylor", ref_csv, extra=["--every-step"])
        check = simulate(binary, str(model), until, 1e-13, "dop853", None)
        record = {"bench": BENCH, "record": "body", **info, "until": until}
        if ref["summary"] is None or (ref["exit"] not in (0, 1)):
            record["error"] = f"reference: {ref['error']}"
            records.append(record)
            log(f"body {index}: reference failed: {ref['error']}")
            continue
        header, rows = read_csv(ref_csv)
        cols = state_columns(header, ref["summary"])
        be = header.index("be")
        scale = [max(abs(r[k]) for r in rows) for k in cols]
        names = [header[k] for k in cols]
        ref_final = [ref["summary"]["final"][n] for n in names]
        ref_t = ref["summary"]["t_final"]
        record.update(min_sin_beta=min(abs(math.sin(r[be])) for r in rows), ref_t_final=ref_t,
                      ref_gimbal=gimbal(ref), ref_h_drift=conserved_drifts(ref["summary"]).get("H"))
        check_t = (check.get("summary") or {}).get("t_final")
        agree = None
        if check.get("summary") and check_t == ref_t == until:
            agree = scaled_error([check["summary"]["final"][n] for n in names], ref_final, scale, RTOL)
        record["reference_agreement"] = agree
        # the final state is scored where both references reach t_end and agree there
        record["scored"] = agree is not None and agree <= 1.0
        results = {}
        for method in ("default", "gauss6", "dop853"):
            run = simulate(binary, str(model), until, RTOL, None if method == "default" else method, None)
            summary = run.get("summary") or {}
            t_final = summary.get("t_final")
            final_error = None
            if summary.get("final") and t_final == ref_t:
                final_error = scaled_error([summary["final"][n] for n in names], ref_final, scale, RTOL)
            results[method] = {"method": summary.get("method"), "exit": run["exit"], "t_final": t_final,
                               "dt": summary.get("dt"), "gimbal": gimbal(run),
                               "stopped_early": stopped_early(t_final, ref_t, summary.get("dt")),
                               "h_drift": conserved_drifts(summary).get("H"), "final_error": final_error,
                               "wall_s": run["wall_s"], "error": run["error"]}
        record["runs"] = results
        records.append(record)
        log(f"body {index} ({'heavy' if info['heavy'] else 'free'}, min|sin be| {record['min_sin_beta']:.3g}, "
            f"ref to t = {ref_t:g}, refs agree {fmt_opt(agree, '.2g')}): "
            + "; ".join(f"{m} t={fmt_opt(r['t_final'], 'g')} H {fmt_e(r['h_drift'])} err {fmt_opt(r['final_error'], '.2g')}"
                        for m, r in results.items()))
    return records


def bodies_table(records: list[dict]) -> str:
    bodies = [r for r in records if r["record"] == "body" and "runs" in r]
    if not bodies:
        return "No body ran.\n"
    scored = [r for r in bodies if r["scored"]]
    lines = [f"{len(bodies)} bodies ({sum(r['heavy'] for r in bodies)} heavy, "
             f"{sum(r['near_singularity'] for r in bodies)} started near sin β = 0; min |sin β| of the reference "
             f"runs from {min(r['min_sin_beta'] for r in bodies):.2g} to {max(r['min_sin_beta'] for r in bodies):.2g}, "
             f"{sum(r['min_sin_beta'] < 0.1 for r in bodies)} below 0.1; {sum(r['ref_gimbal'] for r in bodies)} "
             f"references stopped by the gimbal guard). The final state is scored on the {len(scored)} bodies whose "
             f"two references reach t_end and agree there to ≤ 1 × tol 1e-10; the other columns count every body.",
             "",
             "| method (rtol 1e-10) | runs | stopped by the gimbal guard before the reference | failed otherwise "
             "| H drift > 100 × rtol | final-state error > 1 × tol | > 100 × tol | worst H drift (body) "
             "| worst final-state error (body) | median process wall |",
             "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]

    def worst(pairs):
        pairs = [(v, i) for v, i in pairs if v is not None]
        return max(pairs) if pairs else (None, None)

    for method in ("default", "gauss6", "dop853"):
        runs = [(r["runs"][method], r["index"]) for r in bodies]
        final = [(r["runs"][method], r["index"]) for r in scored]
        chosen = sorted({run["method"] for run, _ in runs if run["method"]})
        label = method if method != "default" else f"default ({', '.join(chosen)})"
        early = {i: stopped_early(run["t_final"], r["ref_t_final"], run["dt"])
                 for r in bodies for run, i in [(r["runs"][method], r["index"])]}
        gimbal_early = sum(run["gimbal"] and early[i] for run, i in runs)
        failed = sum(run["exit"] not in (0, None) and not run["gimbal"] for run, _ in runs)
        h_bad = sum(run["h_drift"] is not None and run["h_drift"] > 100 * RTOL for run, _ in runs)
        e_over = sum(run["final_error"] is not None and run["final_error"] > 1 for run, _ in final)
        e_bad = sum(run["final_error"] is not None and run["final_error"] > 100 for run, _ in final)
        worst_h, body_h = worst((run["h_drift"], i) for run, i in runs)
        worst_e, body_e = worst((run["final_error"], i) for run, i in final)
        wall = median_of(run["wall_s"] for run, _ in runs)
        lines.append(f"| {label} | {len(runs)} | {gimbal_early} | {failed} | {h_bad} | {e_over} | {e_bad} "
                     f"| {fmt_e(worst_h)} ({body_h}) | {fmt_opt(worst_e, '.2g')} ({body_e}) | {fmt_s(wall)} |")
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------------ formatting


def fmt_s(seconds) -> str:
    if seconds is None:
        return "n/a"
    return f"{seconds * 1e3:.1f} ms" if seconds < 1 else f"{seconds:.2f} s"


def fmt_e(value) -> str:
    return "n/a" if value is None else f"{value:.1e}"


def fmt_opt(value, spec: str) -> str:
    return "n/a" if value is None else format(value, spec)


def short(text, limit: int = 120) -> str:
    text = (text or "").replace("|", "/").replace("error: ", "")
    return text if len(text) <= limit else text[:limit - 1] + "…"


def median_of(values):
    values = [v for v in values if v is not None]
    return statistics.median(values) if values else None


def report(records) -> str:
    """The tables of a run's records, as the run printed them."""
    records = list(records)
    kinds = {r.get("record") for r in records}
    machine = next((r for r in records if r.get("record") == "machine"), {})
    text = [f"Started {machine.get('started', '?')} (`{machine.get('command', '?')}`).\n"]
    if "run" in kinds:
        text.append("## Per system, per method (t = 0..100, 1001-row CSV)\n\n" + systems_table(records))
    long_records = [r for r in records if r.get("record") == "long"]
    if long_records:
        until = max(r["t_end"] for r in long_records)
        text.append(f"## Long horizon (t = {until:g}, --samples 11)\n\n" + long_table(long_records, until))
    runaway = [r for r in records if r.get("record") in ("runaway", "runaway_scipy")]
    if runaway:
        text.append("## Robustness: the runaway model to t = 3\n\n" + runaway_table(runaway))
    bodies = [r for r in records if r.get("record") == "body"]
    if bodies:
        text.append(f"## Robustness: {len(bodies)} random rigid bodies to t = {bodies[0]['until']:g}\n\n"
                    + bodies_table(bodies))
    return "\n".join(text)


# ------------------------------------------------------------------ main


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="3 repeats, long horizon 10^4, 16 bodies to t = 5")
    parser.add_argument("--repeats", type=int, default=None, help="whole-process runs per case (median; default 7)")
    parser.add_argument("--long-until", type=float, default=None, help="the long horizon (default 1e5)")
    parser.add_argument("--long-budget", type=float, default=None,
                        help="seconds one long run may take by its pace at t = 100 (default 150; 10 with --quick)")
    parser.add_argument("--bodies", type=int, default=None, help="random rigid bodies (default 60)")
    parser.add_argument("--body-until", type=float, default=None, help="their end time (default 10)")
    parser.add_argument("--seed", type=int, default=16, help="seed of the random bodies (default 16)")
    parser.add_argument("--parts", default="systems,long,runaway,bodies",
                        help="which parts to run, comma-separated (long needs systems)")
    parser.add_argument("--no-scipy", action="store_true", help="skip SciPy's run of the runaway model")
    parser.add_argument("--no-install", action="store_true", help="never create or fill the anchors' venv")
    parser.add_argument("--binary", type=Path, default=REPO / "target" / "release" / "lagrange")
    parser.add_argument("--no-build", action="store_true", help="never run cargo")
    parser.add_argument("--anchors", type=Path, default=DEFAULT_ANCHORS, help="folder of the anchors' requirements")
    parser.add_argument("--report", type=Path, default=None,
                        help="print the tables of an earlier run's JSON lines (its --out) and run nothing")
    parser.add_argument("--out", type=Path,
                        default=Path(os.environ.get("TMPDIR") or "/tmp") / "lagrange-default-method.jsonl")
    args = parser.parse_args(argv)
    repeats = args.repeats or (3 if args.quick else 7)
    long_until = args.long_until or (1e4 if args.quick else 1e5)
    long_budget = args.long_budget or (10.0 if args.quick else 150.0)
    bodies = args.bodies if args.bodies is not None else (16 if args.quick else 60)
    body_until = args.body_until or (5.0 if args.quick else 10.0)
    parts = set(p for p in args.parts.split(",") if p)

    if args.report is not None:
        print(report(json.loads(line) for line in args.report.read_text().splitlines() if line.strip()))
        return 0
    if not derive_bench.ensure_binary(args.binary, build=not args.no_build):
        return 1
    started = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    records: list[dict] = [{"bench": BENCH, "record": "machine", "nproc": os.cpu_count(), "platform": platform.platform(),
                            "python": platform.python_version(), "started": started,
                            "command": " ".join([Path(sys.argv[0]).name, *(argv if argv is not None else sys.argv[1:])])}]
    text = [f"Started {started}; rtol = atol = {RTOL:g} unless a table says otherwise.\n"]
    with tempfile.TemporaryDirectory(prefix="lagrange-default-method-") as tmp:
        workdir = Path(tmp)
        part1: list[dict] = []
        if "systems" in parts:
            part1 = measure_systems(args.binary, repeats, workdir)
            records += part1
            text.append("## Per system, per method (t = 0..100, 1001-row CSV)\n\n" + systems_table(part1))
        if "long" in parts and part1:
            long_records = measure_long(args.binary, long_until, long_budget, part1, workdir)
            records += long_records
            text.append(f"## Long horizon (t = {long_until:g}, --samples 11)\n\n" + long_table(long_records, long_until))
        if "runaway" in parts:
            python = None
            if not args.no_scipy:
                python = derive_bench.anchor_python(args.anchors, ("scipy", "numpy"), allow_install=not args.no_install)
            runaway = measure_runaway(args.binary, python)
            records += runaway
            text.append("## Robustness: the runaway model to t = 3\n\n" + runaway_table(runaway))
        if "bodies" in parts and bodies > 0:
            body_records = measure_bodies(args.binary, bodies, body_until, args.seed, workdir)
            records += body_records
            text.append(f"## Robustness: {bodies} random rigid bodies to t = {body_until:g} (seed {args.seed})\n\n"
                        + bodies_table(body_records))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with args.out.open("w") as f:
        for r in records:
            f.write(json.dumps(r) + "\n")
    print("\n".join(text))
    log(f"records in {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
