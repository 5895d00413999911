#!/usr/bin/env python3
"""Benchmark `lagrange simulate` against SciPy's solve_ivp on SymPy-derived motion, in one run.

What it does, in order:

1. times `target/release/lagrange simulate MODEL --until T --rtol R --atol R --every-step
   --summary json` (building the binary with `cargo build --release` if it is missing) for
   the double pendulum (examples/double_pendulum.toml, t = 0..100), the 50-mass chain
   (examples/chain50.toml, t = 0..100) and Kepler (examples/kepler.toml, t = 0..1000),
   each with `--method dop853`, `--method taylor` and with the method the derivation
   picks (no --method):
   median over --repeats runs of the integration's `wall_seconds` (compilation and, for
   fixed-step methods, the pilot runs that choose the step included) and of the whole
   process, and the summary's steps, rhs_evaluations and H's max_rel_drift (H is the
   energy for all three);
2. runs the anchor ../shared/bench/scipy_simulate.py on the same systems with DOP853, the
   `lambdify` and `hand` right-hand sides and the same tolerances (rtol = atol), in a venv
   under ${TMPDIR:-/tmp} with the anchors' pinned requirements if this Python cannot import
   sympy, numpy and scipy (the venv logic is bench/derive.py's);
3. runs the strong anchor ../shared/bench/heyoka_simulate.py (heyoka, Taylor method with
   LLVM) on the double pendulum at the same tolerances, and its 200x200 double-pendulum
   ensemble to t = 20 on one worker against `lagrange sweep` (Taylor on one thread with
   and without the Lyapunov twin -- heyoka integrates no twin --, DOP853 on one thread,
   and Taylor on every core), unless --no-heyoka;
4. times one right-hand side of the double pendulum with the criterion bench
   crates/sym/benches/rhs.rs (JIT, tape interpreter, hand-written Rust) against SciPy's
   lambdified and hand-written Python ones (the anchor's `rhs` records), unless --no-rhs;
5. prints Markdown tables -- setup (model file to first step), one RHS, every run, the
   ratios ours vs SciPy and heyoka (wall time, RHS evaluations, energy drift), and the
   ensemble -- and writes every record as JSON lines to --out.

Matched settings: rtol = atol = R on both sides (SciPy's anchor uses rtol = atol); both
sides report the energy drift at the accepted steps (`--every-step` for us, SciPy's
`energy_drift_steps`), and both time the integration without dense output. Standard
library only.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

sys.dont_write_bytecode = True  # importing derive.py must not leave bench/__pycache__
sys.path.insert(0, str(Path(__file__).resolve().parent))

import derive as derive_bench  # noqa: E402  (ensure_binary, anchor_python, run_anchor)

REPO = Path(__file__).resolve().parent.parent
DEFAULT_ANCHORS = next((p for p in (REPO.parent / "shared" / "bench", REPO.parent.parent / "shared" / "bench") if p.exists()),
                       REPO.parent / "shared" / "bench")
BENCH = "lagrange_simulate"

# (name in the anchor, model file, end time)
SYSTEMS = [
    ("double_pendulum", "examples/double_pendulum.toml", 100.0),
    ("chain", "examples/chain50.toml", 100.0),
    ("kepler", "examples/kepler.toml", 1000.0),
]


def log(message: str) -> None:
    print(f"[simulate.py] {message}", file=sys.stderr, flush=True)


# ------------------------------------------------------------------ our side


def run_ours(binary: Path, model: str, until: float, rtol: float, method: str | None, timeout: float) -> dict:
    """One `simulate` run: its summary JSON plus the process wall time."""
    args = [str(binary), "simulate", model, "--until", repr(until), "--rtol", repr(rtol), "--atol", repr(rtol),
            "--every-step", "--summary", "json"]
    if method is not None:
        args += ["--method", method]
    start = time.perf_counter()
    try:
        proc = subprocess.run(args, cwd=REPO, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"error": f"timed out after {timeout:.0f} s"}
    wall = time.perf_counter() - start
    if proc.returncode != 0:
        return {"error": f"exit {proc.returncode}: {proc.stderr.strip()[-500:]}"}
    try:
        summary = json.loads(proc.stdout)
    except json.JSONDecodeError as err:
        return {"error": f"summary is not JSON: {err}"}
    summary["process_wall_s"] = wall
    # The same run with the CSV output of 1001 samples (what a user runs), whole process.
    csv_args = [a for a in args if a != "--every-step"] + ["--out", os.devnull]
    start = time.perf_counter()
    csv_run = subprocess.run(csv_args, cwd=REPO, capture_output=True, text=True, timeout=timeout)
    summary["csv_process_wall_s"] = time.perf_counter() - start if csv_run.returncode == 0 else None
    summary["stderr"] = proc.stderr.strip()
    return summary


def measure_ours(binary: Path, rtols, methods, repeats: int, timeout: float) -> list[dict]:
    records = []
    for system, model, until in SYSTEMS:
        for rtol in rtols:
            for method in methods:
                requested = None if method == "default" else method
                runs = []
                for _ in range(repeats):
                    run = run_ours(binary, model, until, rtol, requested, timeout)
                    runs.append(run)
                    if "error" in run:
                        break
                ok = [r for r in runs if "error" not in r]
                last = runs[-1]
                record = {
                    "bench": BENCH,
                    "record": "run",
                    "tool": "lagrange",
                    "system": system,
                    "model": model,
                    "t_end": until,
                    "rtol": rtol,
                    "atol": rtol,
                    "requested": method,
                    "method": last.get("method"),
                    "dt": last.get("dt"),
                    "wall_s": statistics.median(r["wall_seconds"] for r in ok) if ok else None,
                    "process_wall_s": statistics.median(r["process_wall_s"] for r in ok) if ok else None,
                    "process_wall_min_s": min(r["process_wall_s"] for r in ok) if ok else None,
                    "csv_process_wall_s": median_of(r.get("csv_process_wall_s") for r in ok),
                    "setup_s": median_of(r.get("setup_seconds") for r in ok),
                    "derive_s": median_of(r.get("derive_seconds") for r in ok),
                    "wall_samples": [r["wall_seconds"] for r in ok],
                    "steps": last.get("steps"),
                    "rhs_evaluations": last.get("rhs_evaluations"),
                    "energy_drift_steps": (last.get("invariants") or {}).get("H", {}).get("max_rel_drift"),
                    "invariants": last.get("invariants"),
                    "final": last.get("final"),
                    "warnings": last.get("warnings"),
                    "repeats": len(ok),
                    "error": None if ok else last.get("error"),
                }
                log(f"lagrange {system} rtol={rtol:g} {method} -> {record['method']}: wall={fmt_s(record['wall_s'])} "
                    f"steps={record['steps']} rhs={record['rhs_evaluations']} drift={fmt_e(record['energy_drift_steps'])}")
                records.append(record)
    return records


def fmt_us(value) -> str:
    return "n/a" if value is None else f"{value:,.0f}"


def median_of(values):
    values = [v for v in values if v is not None]
    return statistics.median(values) if values else None


def heyoka_python(anchors: Path, allow_install: bool) -> str | None:
    """A Python that imports heyoka: this one, the anchors' venv, or that venv after
    installing heyoka's pinned version (requirements-strong.txt) into it."""
    modules = ("heyoka", "numpy")
    if derive_bench.can_import(sys.executable, modules):
        return sys.executable
    venv = Path(os.environ.get("TMPDIR") or "/tmp") / "lagrange-bench-venv"
    python = venv / "bin" / "python"
    if python.exists() and derive_bench.can_import(str(python), modules):
        return str(python)
    if not allow_install:
        log("no Python imports heyoka (and --no-install was given)")
        return None
    try:
        if not python.exists():
            subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
        packages = derive_bench.pinned(anchors, ["heyoka", "numpy", "cloudpickle"])
        log(f"installing {' '.join(packages)} into {venv}")
        subprocess.run([str(python), "-m", "pip", "install", "--quiet", *packages], check=True, timeout=900)
    except (OSError, subprocess.SubprocessError) as err:
        log(f"cannot set up {venv}: {err}")
    return str(python) if python.exists() and derive_bench.can_import(str(python), modules) else None


def measure_sweep(binary: Path, grid: int, until: float, rtol: float, timeout: float) -> list[dict]:
    """`lagrange sweep` of the double pendulum's chaos map: the Taylor method (the default)
    with and without the twin on one thread, DOP853 without the twin on one thread, and the
    Taylor method without the twin on every core."""
    records = []
    cores = os.cpu_count() or 1
    cases = [("taylor", False, 1), ("taylor", True, 1), ("dop853", False, 1)]
    if cores > 1:
        cases.append(("taylor", False, cores))
    for method, lyapunov, threads in cases:
        args = [str(binary), "sweep", "examples/double_pendulum.toml", "--until", repr(until),
                "--grid", f"a=0:3.1:{grid},b=0:3.1:{grid}", "--rtol", repr(rtol), "--atol", repr(rtol),
                "--method", method, "--threads", str(threads), "--out", os.devnull]
        if not lyapunov:
            args.append("--no-lyapunov")
        start = time.perf_counter()
        try:
            proc = subprocess.run(args, cwd=REPO, capture_output=True, text=True, timeout=timeout)
            wall = time.perf_counter() - start
            error = None if proc.returncode == 0 else f"exit {proc.returncode}: {proc.stderr.strip()[-300:]}"
        except subprocess.TimeoutExpired:
            wall, error = None, f"timed out after {timeout:.0f} s"
        record = {"bench": BENCH, "record": "ensemble", "tool": "lagrange", "grid": grid, "n": grid * grid,
                  "t_end": until, "rtol": rtol, "method": method, "lyapunov": lyapunov, "threads": threads,
                  "wall_s": wall, "us_per_trajectory": None if wall is None else wall / (grid * grid) * 1e6,
                  "error": error}
        log(f"lagrange sweep {grid}x{grid} {method} lyapunov={lyapunov} threads={threads}: {fmt_s(wall)}"
            + (f" ({error})" if error else ""))
        records.append(record)
    return records


def measure_rhs(repo: Path, build: bool) -> list[dict]:
    """One double-pendulum RHS: the criterion bench crates/sym/benches/rhs.rs (ns per call)."""
    if not build:
        return []
    log("cargo bench -p lagrange-sym --bench rhs (criterion, --quick)")
    proc = subprocess.run(["cargo", "bench", "-p", "lagrange-sym", "--bench", "rhs", "--", "--quick", "--noplot"],
                          cwd=repo, capture_output=True, text=True)
    if proc.returncode != 0:
        log(f"the rhs bench failed: {proc.stderr.strip()[-300:]}")
        return []
    records = []
    for name in ("jit", "tape_eval", "hand"):
        path = repo / "target" / "criterion" / "double_pendulum_rhs" / name / "new" / "estimates.json"
        try:
            ns = json.loads(path.read_text())["median"]["point_estimate"]
        except (OSError, KeyError, json.JSONDecodeError):
            continue
        records.append({"bench": BENCH, "record": "rhs", "tool": "lagrange", "variant": name, "ns_per_call": ns})
    return records


# ------------------------------------------------------------------ report


def fmt_s(seconds) -> str:
    if seconds is None:
        return "n/a"
    return f"{seconds * 1e3:.1f} ms" if seconds < 1 else f"{seconds:.2f} s"


def fmt_e(value) -> str:
    return "n/a" if value is None else f"{value:.1e}"


def fmt_int(value) -> str:
    return "n/a" if value is None else f"{value:,}"


def fmt_ratio(num, den, digits: int = 1) -> str:
    if num is None or den is None or den == 0:
        return "n/a"
    return f"{num / den:.{digits}f}×" if num / den >= 0.1 else f"{num / den:.2g}×"


def scipy_index(records: list[dict]) -> dict:
    """SciPy DOP853 runs by (system, rtol, variant)."""
    out = {}
    for r in records:
        if r.get("record") == "run" and r.get("method") == "DOP853" and not r.get("timeout"):
            out[(r["system"], float(r["rtol"]), r["variant"])] = r
    return out


def tables(ours: list[dict], scipy: dict, variants) -> tuple[str, list[dict]]:
    runs = ["| system | rtol = atol | run | steps | RHS evaluations | integration wall | process wall | max rel. energy drift (steps) |",
            "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: |"]
    ratios = ["| system | rtol | ours | wall: SciPy lambdify / ours | wall: SciPy hand / ours | "
              "RHS evals: SciPy / ours | energy drift: ours / SciPy |",
              "| --- | --- | --- | ---: | ---: | ---: | ---: |"]
    ratio_records = []
    seen = set()
    for r in ours:
        key = (r["system"], r["rtol"])
        label = f"lagrange {r['method'] or r['requested']}" + (" (default)" if r["requested"] == "default" else "")
        if r["dt"]:
            label += f", dt {r['dt']:.3g}"
        runs.append(f"| {r['system']} | {r['rtol']:g} | {label} | {fmt_int(r['steps'])} | {fmt_int(r['rhs_evaluations'])} "
                    f"| {fmt_s(r['wall_s'])} | {fmt_s(r['process_wall_s'])} | {fmt_e(r['energy_drift_steps'])} |")
        if key not in seen:
            seen.add(key)
            for variant in variants:
                s = scipy.get((r["system"], r["rtol"], variant))
                if s is None:
                    runs.append(f"| {r['system']} | {r['rtol']:g} | SciPy DOP853 {variant} | n/a | n/a | n/a | – | n/a |")
                    continue
                runs.append(f"| {r['system']} | {r['rtol']:g} | SciPy DOP853 {variant} | {fmt_int(s.get('n_steps'))} "
                            f"| {fmt_int(s.get('rhs_calls'))} | {fmt_s(s.get('wall_s'))} | – "
                            f"| {fmt_e(s.get('energy_drift_steps'))} |")
        lam = scipy.get((r["system"], r["rtol"], "lambdify"))
        hand = scipy.get((r["system"], r["rtol"], "hand"))
        ref = hand or lam
        ratio = {
            "bench": BENCH,
            "record": "ratio",
            "system": r["system"],
            "rtol": r["rtol"],
            "ours": r["method"],
            "wall_lambdify_over_ours": None if not (lam and r["wall_s"]) else lam["wall_s"] / r["wall_s"],
            "wall_hand_over_ours": None if not (hand and r["wall_s"]) else hand["wall_s"] / r["wall_s"],
            "rhs_scipy_over_ours": None if not (ref and r["rhs_evaluations"]) else ref["rhs_calls"] / r["rhs_evaluations"],
            "drift_ours_over_scipy": None if not (ref and r["energy_drift_steps"] is not None and ref.get("energy_drift_steps"))
            else r["energy_drift_steps"] / ref["energy_drift_steps"],
        }
        ratio_records.append(ratio)
        ratios.append(
            f"| {r['system']} | {r['rtol']:g} | {label} "
            f"| {fmt_ratio(lam and lam['wall_s'], r['wall_s'])} | {fmt_ratio(hand and hand['wall_s'], r['wall_s'])} "
            f"| {fmt_ratio(ref and ref['rhs_calls'], r['rhs_evaluations'], 2)} "
            f"| {fmt_ratio(r['energy_drift_steps'], ref and ref.get('energy_drift_steps'), 2)} |"
        )
    return "\n".join(runs) + "\n\n" + "\n".join(ratios) + "\n", ratio_records


def extra_tables(ours: list[dict], scipy_records: list[dict], heyoka_records: list[dict], rhs_records: list[dict],
                 sweep_records: list[dict]) -> str:
    """Setup, one RHS, whole runs against heyoka, and the ensemble."""
    out = []
    dp = [r for r in ours if r["system"] == "double_pendulum" and r["wall_s"] is not None]
    scipy_setup = next((r for r in scipy_records if r.get("record") == "setup" and r.get("system") == "double_pendulum"), None)
    hey_runs = {float(r["rtol"]): r for r in heyoka_records if r.get("record") == "run" and r.get("problem") == "double_pendulum"}
    if dp:
        # Adaptive runs start integrating right after compiling; fixed-step ones
        # first run their pilots (listed apart).
        adaptive = [r for r in dp if not r["dt"]] or dp
        setup = median_of(r["setup_s"] for r in adaptive)
        hey = next(iter(hey_runs.values()), None)
        out += ["| double pendulum: model file to first step | seconds | anchor / ours |", "| --- | ---: | ---: |",
                f"| lagrange: read, parse, derive, compile (`setup_seconds`, {adaptive[0]['method']}) | {fmt_s(setup)} | |",
                f"| lagrange: of which read, parse, derive (`derive_seconds`) "
                f"| {fmt_s(median_of(r['derive_s'] for r in adaptive))} | |",
                *[f"| lagrange {r['method']}: the same plus the pilot runs that choose its step | {fmt_s(r['setup_s'])} | |"
                  for r in dp if r["dt"]],
                f"| SciPy anchor: derive + lambdify | {fmt_s(scipy_setup and scipy_setup.get('derive_and_lambdify_s'))} "
                f"| {fmt_ratio(scipy_setup and scipy_setup.get('derive_and_lambdify_s'), setup)} |",
                f"| heyoka: compile (cold) | {fmt_s(hey and hey.get('compile_s'))} | {fmt_ratio(hey and hey.get('compile_s'), setup)} |",
                ""]
    rhs = {r["variant"]: r["ns_per_call"] for r in rhs_records}
    scipy_rhs = {r["variant"]: r["us_per_call"] * 1e3 for r in scipy_records
                 if r.get("record") == "rhs" and r.get("system") == "double_pendulum" and r.get("us_per_call")}
    if rhs:
        jit = rhs.get("jit")
        out += ["| double pendulum: one RHS | ns per call | / lagrange JIT |", "| --- | ---: | ---: |"]
        for label, ns in [("lagrange JIT (cranelift)", jit), ("lagrange tape interpreter", rhs.get("tape_eval")),
                          ("hand-written Rust (criterion bench)", rhs.get("hand")),
                          ("SciPy anchor: lambdify", scipy_rhs.get("lambdify")),
                          ("SciPy anchor: hand-written Python", scipy_rhs.get("hand"))]:
            out.append(f"| {label} | {'n/a' if ns is None else f'{ns:,.1f}'} | {fmt_ratio(ns, jit, 2)} |")
        out.append("")
    if hey_runs:
        out += ["| double pendulum t = 0..100 | ours | process wall (1001-row CSV) | integration wall | energy drift "
                "| heyoka propagate | heyoka compile + propagate | heyoka drift | heyoka propagate / our process "
                "| drift ours / heyoka |",
                "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
        for r in dp:
            h = hey_runs.get(float(r["rtol"]))
            if h is None:
                continue
            total = (h.get("compile_s") or 0) + (h.get("wall_s") or 0)
            label = r["method"] + (" (default)" if r["requested"] == "default" else "")
            out.append(f"| rtol {r['rtol']:g} | {label} | {fmt_s(r['csv_process_wall_s'])} | {fmt_s(r['wall_s'])} "
                       f"| {fmt_e(r['energy_drift_steps'])} | {fmt_s(h.get('wall_s'))} | {fmt_s(total)} "
                       f"| {fmt_e(h.get('energy_rel_drift'))} | {fmt_ratio(h.get('wall_s'), r['csv_process_wall_s'], 2)} "
                       f"| {fmt_ratio(r['energy_drift_steps'], h.get('energy_rel_drift'), 2)} |")
        out.append("")
    targets = target_table(dp, scipy_records, hey_runs)
    if targets:
        out += targets
    hey_ens = next((r for r in heyoka_records if r.get("record") == "ensemble" and r.get("workers") == 1), None)
    if sweep_records:
        out += ["| chaos map, double pendulum, t = 0..20 | runs | wall | µs per run | heyoka (1 worker) / ours |",
                "| --- | ---: | ---: | ---: | ---: |"]
        for r in sweep_records:
            label = (f"lagrange sweep --method {r.get('method', 'dop853')}"
                     + (" with Lyapunov twin" if r["lyapunov"] else " --no-lyapunov")
                     + (f", {r['threads']} threads" if r.get("threads", 1) > 1 else ", 1 thread"))
            out.append(f"| {label} (rtol {r['rtol']:g}) | {r['n']:,} | {fmt_s(r['wall_s'])} "
                       f"| {fmt_us(r['us_per_trajectory'])} "
                       f"| {fmt_ratio(hey_ens and hey_ens['wall_s'] * r['n'] / hey_ens['n'], r['wall_s'], 2)} |")
        if hey_ens:
            out.append(f"| heyoka ensemble, batch {hey_ens.get('batch_size')}, 1 worker (tol {hey_ens['tol_label']}) "
                       f"| {hey_ens['n']:,} | {fmt_s(hey_ens['wall_s'])} | {hey_ens['us_per_trajectory']:,.0f} | |")
        out.append("")
    return "\n".join(out)


def target_table(dp: list[dict], scipy_records: list[dict], hey_runs: dict) -> list[str]:
    """Issue #16's targets for the default method (no --method) on the double pendulum to
    t = 100: its whole process writing the 1001-row CSV at least 10x faster than heyoka's
    compile + propagate and at least 50x faster than SciPy's DOP853 with the hand-written
    right-hand side, at a relative energy drift of at most 1e-8."""
    scipy = scipy_index(scipy_records)
    out = []
    for r in dp:
        if r["requested"] != "default" or not r["csv_process_wall_s"]:
            continue
        if not out:
            out += ["| double pendulum t = 0..100, the default method | rtol | ours: process wall (1001-row CSV) "
                    "| heyoka compile + propagate / ours (target ≥ 10) | SciPy DOP853 hand / ours (target ≥ 50) "
                    "| our energy drift (target ≤ 1e-8) |",
                    "| --- | --- | ---: | ---: | ---: | ---: |"]
        h = hey_runs.get(float(r["rtol"]))
        hey_total = None if h is None else (h.get("compile_s") or 0) + (h.get("wall_s") or 0)
        hand = scipy.get(("double_pendulum", float(r["rtol"]), "hand"))
        ours = r["csv_process_wall_s"]
        drift = r["energy_drift_steps"]

        def verdict(ratio, target):
            return "n/a" if ratio is None else f"{ratio:.1f}× ({'met' if ratio >= target else 'not met'})"

        out.append(f"| {r['method']} (default) | {r['rtol']:g} | {fmt_s(ours)} "
                   f"| {verdict(hey_total and hey_total / ours, 10)} "
                   f"| {verdict(hand and hand['wall_s'] / ours, 50)} "
                   f"| {fmt_e(drift)} ({'n/a' if drift is None else 'met' if drift <= 1e-8 else 'not met'}) |")
    return out + [""] if out else []


# ------------------------------------------------------------------ main


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rtols", default="1e-10", help="comma-separated tolerances, rtol = atol (default 1e-10)")
    parser.add_argument("--methods", default="dop853,taylor,default",
                        help="our methods, comma-separated; `default` = the derivation's choice (default dop853,taylor,default)")
    parser.add_argument("--repeats", type=int, default=5, help="runs of ours per case (median; default 5)")
    parser.add_argument("--anchor-repeats", type=int, default=3, help="timed repeats per SciPy run (default 3)")
    parser.add_argument("--grid-points", type=int, default=0,
                        help="SciPy's dense t_eval audit grid (a second run per case); 0 skips it (default)")
    parser.add_argument("--timeout", type=float, default=300.0, help="seconds per run of ours (default 300)")
    parser.add_argument("--anchor-timeout", type=float, default=3600.0, help="seconds for the SciPy script (default 3600)")
    parser.add_argument("--no-scipy", action="store_true", help="skip the SciPy anchor")
    parser.add_argument("--no-heyoka", action="store_true", help="skip the heyoka anchor")
    parser.add_argument("--no-rhs", action="store_true", help="skip the criterion RHS bench")
    parser.add_argument("--ensemble-grid", type=int, default=200,
                        help="points per angle of the chaos map (both sides; 0 skips it; default 200)")
    parser.add_argument("--ensemble-until", type=float, default=20.0, help="end time of the chaos map (default 20)")
    parser.add_argument("--no-install", action="store_true", help="never create or fill the anchors' venv")
    parser.add_argument("--binary", type=Path, default=REPO / "target" / "release" / "lagrange")
    parser.add_argument("--no-build", action="store_true", help="never run cargo")
    parser.add_argument("--anchors", type=Path, default=DEFAULT_ANCHORS, help="folder of scipy_simulate.py")
    parser.add_argument("--out", type=Path,
                        default=Path(os.environ.get("TMPDIR") or "/tmp") / "lagrange-simulate-bench.jsonl")
    args = parser.parse_args(argv)
    rtols = [float(v) for v in args.rtols.split(",") if v]
    methods = [m for m in args.methods.split(",") if m]
    variants = ["lambdify", "hand"]

    records: list[dict] = [{"bench": BENCH, "record": "machine", "nproc": os.cpu_count(), "platform": platform.platform(),
                            "python": platform.python_version(), "cpu": platform.processor()}]
    if not derive_bench.ensure_binary(args.binary, build=not args.no_build):
        return 1
    ours = measure_ours(args.binary, rtols, methods, args.repeats, args.timeout)
    records += ours

    scipy_records: list[dict] = []
    if not args.no_scipy:
        python = derive_bench.anchor_python(args.anchors, ("sympy", "numpy", "scipy"), allow_install=not args.no_install)
        if python is None:
            records.append({"bench": BENCH, "record": "anchor_error", "anchor": "scipy_simulate", "error": "no Python with scipy"})
        else:
            anchor_args = [
                "--systems", ",".join(s for s, _, _ in SYSTEMS),
                "--variants", ",".join(variants),
                "--methods", "DOP853",
                "--rtols", ",".join(repr(r) for r in rtols),
                "--repeats", str(args.anchor_repeats),
                "--grid-points", str(args.grid_points),
                "--no-cse",
            ]
            scipy_records, error = derive_bench.run_anchor(python, args.anchors / "scipy_simulate.py", anchor_args,
                                                           args.anchor_timeout)
            for r in scipy_records:
                r["source"] = "scipy_simulate.py"
            if error:
                records.append({"bench": BENCH, "record": "anchor_error", "anchor": "scipy_simulate", "error": error})
                log(f"scipy_simulate.py: {error}")
    records += scipy_records

    heyoka_records: list[dict] = []
    if not args.no_heyoka:
        python = heyoka_python(args.anchors, allow_install=not args.no_install)
        if python is None:
            records.append({"bench": BENCH, "record": "anchor_error", "anchor": "heyoka_simulate", "error": "no Python with heyoka"})
        else:
            problems = ["double_pendulum"] + (["ensemble"] if args.ensemble_grid > 0 else [])
            anchor_args = ["--problems", *problems, "--tols", *[repr(r) for r in rtols],
                           "--ensemble-tols", "1e-10", "--ensemble-modes", "threads", "--workers", "1",
                           "--ensemble-repeats", "1", "--ensemble-grid", str(args.ensemble_grid),
                           "--ensemble-t-end", repr(args.ensemble_until), "--repeats", str(args.anchor_repeats)]
            heyoka_records, error = derive_bench.run_anchor(python, args.anchors / "heyoka_simulate.py", anchor_args,
                                                            args.anchor_timeout)
            for r in heyoka_records:
                r["source"] = "heyoka_simulate.py"
            if error:
                records.append({"bench": BENCH, "record": "anchor_error", "anchor": "heyoka_simulate", "error": error})
                log(f"heyoka_simulate.py: {error}")
    records += heyoka_records
    sweep_records = (measure_sweep(args.binary, args.ensemble_grid, args.ensemble_until, 1e-10, args.timeout * 10)
                     if args.ensemble_grid > 0 else [])
    records += sweep_records
    rhs_records = [] if args.no_rhs else measure_rhs(REPO, build=not args.no_build)
    records += rhs_records

    text, ratio_records = tables(ours, scipy_index(scipy_records), variants)
    text = extra_tables(ours, scipy_records, heyoka_records, rhs_records, sweep_records) + "\n" + text
    records += ratio_records
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with args.out.open("w") as f:
        for r in records:
            f.write(json.dumps(r) + "\n")
    print(text)
    log(f"records in {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
