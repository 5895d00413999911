#!/usr/bin/env python3
"""Benchmark `lagrange derive` against the SymPy and SymEngine anchors, in one run.

What it does, in order:

1. writes model files into a temporary folder: the planar N-link pendulum built from
   particles (coordinates th1..thN, masses m1..mN, lengths l1..lN, gravity g;
   x_k = sum_{i<=k} l_i sin th_i, y_k = -sum_{i<=k} l_i cos th_i) and the chain of N
   masses and N+1 springs between fixed walls given as a `lagrangian` string -- exactly
   the systems of ../shared/bench/README.md;
2. times `target/release/lagrange derive FILE --format json` on each (median of
   --repeats runs; wall clock, and CPU time of the child from os.wait4), building the
   binary with `cargo build --release` first (a no-op when it is fresh);
3. runs the anchors ../shared/bench/sympy_derive.py and symengine_derive.py on the same
   sizes (installing their pinned requirements into a venv under ${TMPDIR:-/tmp} if the
   current Python cannot import them);
4. prints a Markdown table (N, lagrange, SymPy, SymEngine, ratios) and writes every
   record (ours, the anchors', and the ratios) as JSON lines to --out.

An anchor that fails, times out or cannot be installed shows as n/a; ours still runs.
Standard library only. `--quick` runs small sizes once (about a minute).

What is compared: SymPy's `lagrangian` + `equations` steps (L, LagrangesMethod, M and f,
without lambdify) in CPU seconds; SymEngine's L + M, f (wall seconds: that script reports
no CPU time) against our whole `derive` process in CPU seconds (process start, parsing,
L, momenta, equations, M, f, H, Hamilton's equations and the JSON output).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
DEFAULT_ANCHORS = REPO.parent / "shared" / "bench"
BENCH = "lagrange_derive"
VENV_MODULES = ("sympy", "mpmath", "numpy", "scipy", "symengine")


def log(message: str) -> None:
    print(f"[derive.py] {message}", file=sys.stderr, flush=True)


# ------------------------------------------------------------------ model files


def pendulum_model(n: int) -> str:
    """The planar N-link pendulum from particles, as a lagrange model file."""
    coords = [f"th{i}" for i in range(1, n + 1)]
    lines = [
        f'name = "{n}-link planar pendulum"',
        "coordinates = [" + ", ".join(f'"{q}"' for q in coords) + "]",
        'gravity = "g"',
        "",
        "[parameters]",
    ]
    lines += [f"m{i} = 1.0" for i in range(1, n + 1)]
    lines += [f"l{i} = 1.0" for i in range(1, n + 1)]
    lines += ["g = 9.81", ""]
    for k in range(1, n + 1):
        x = " + ".join(f"l{i}*sin(th{i})" for i in range(1, k + 1))
        y = " - ".join(f"l{i}*cos(th{i})" for i in range(1, k + 1))
        lines += ["[[particles]]", f'mass = "m{k}"', f'position = ["{x}", "-{y}"]', ""]
    lines.append("[initial]")
    for i, q in enumerate(coords, start=1):
        lines += [f"{q} = {0.1 * i:.1f}", f"\"{q}'\" = 0.0"]
    return "\n".join(lines) + "\n"


def chain_lagrangian(n: int) -> str:
    """The anchors' chain Lagrangian text (bench_common.chain_lagrangian_string), with x' and ^."""
    kinetic = " + ".join(f"m{i}*x{i}'^2/2" for i in range(1, n + 1))
    springs = []
    for j in range(1, n + 2):
        left = f"x{j - 1}" if j > 1 else "0"
        right = f"x{j}" if j <= n else "0"
        springs.append(f"k{j}*({right} - {left})^2/2")
    return f"{kinetic} - ({' + '.join(springs)})"


def chain_model(n: int) -> str:
    """N masses between fixed walls, all m = k = 1, x1 = 1 and everything else 0."""
    lines = [
        f'name = "chain of {n} masses and springs"',
        "coordinates = [" + ", ".join(f'"x{i}"' for i in range(1, n + 1)) + "]",
        f'lagrangian = "{chain_lagrangian(n)}"',
        "",
        "[parameters]",
    ]
    lines += [f"m{i} = 1.0" for i in range(1, n + 1)]
    lines += [f"k{j} = 1.0" for j in range(1, n + 2)]
    lines += ["", "[initial]"]
    for i in range(1, n + 1):
        lines += [f"x{i} = {1.0 if i == 1 else 0.0}", f"\"x{i}'\" = 0.0"]
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------------ our side


def ensure_binary(binary: Path, build: bool) -> bool:
    # Cargo does nothing when the binary is fresh; a stale one would measure old code.
    if binary.exists() and not build:
        return True
    if not build:
        log(f"{binary} is missing (and --no-build was given)")
        return False
    log("building: cargo build --release --bin lagrange")
    result = subprocess.run(["cargo", "build", "--release", "--bin", "lagrange"], cwd=REPO)
    if result.returncode != 0 or not binary.exists():
        log(f"cargo build failed (exit {result.returncode})")
        return False
    return True


def run_once(binary: Path, model: Path, timeout: float) -> dict:
    """One `derive` run: wall and CPU seconds of the child, exit code, output size."""
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        start = time.perf_counter()
        proc = subprocess.Popen(
            [str(binary), "derive", str(model), "--format", "json"],
            stdin=subprocess.DEVNULL,
            stdout=out,
            stderr=err,
        )
        killer = threading.Timer(timeout, proc.kill)
        killer.start()
        try:
            _, status, usage = os.wait4(proc.pid, 0)
        finally:
            killer.cancel()
        wall = time.perf_counter() - start
        proc.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        stdout = out.read()
        size = len(stdout)
        try:
            parsed = json.loads(stdout)
            derive_s = parsed.get("derive_seconds")
            equations_s = parsed.get("equations_seconds")
        except (ValueError, AttributeError):
            derive_s = equations_s = None
        err.seek(0)
        stderr = err.read().decode("utf-8", "replace")
    return {
        "wall_s": wall,
        "cpu_s": usage.ru_utime + usage.ru_stime,
        "max_rss_kb": usage.ru_maxrss,
        "derive_s": derive_s,
        "equations_s": equations_s,
        "exit_code": proc.returncode,
        "output_bytes": size,
        "timed_out": wall >= timeout,
        "stderr": stderr[-2000:],
    }


def measure_ours(binary: Path, models: list[tuple[str, int, Path]], repeats: int, timeout: float):
    records = []
    for system, n, path in models:
        runs = []
        for _ in range(repeats):
            run = run_once(binary, path, timeout)
            runs.append(run)
            if run["exit_code"] != 0 or run["wall_s"] > 10.0:
                break  # a failure or a slow size: one sample is enough
        ok = [r for r in runs if r["exit_code"] == 0]
        record = {
            "bench": BENCH,
            "record": "result",
            "tool": "lagrange",
            "system": system,
            "n": n,
            "wall_s": statistics.median(r["wall_s"] for r in ok) if ok else None,
            "cpu_s": statistics.median(r["cpu_s"] for r in ok) if ok else None,
            "derive_s": statistics.median(r["derive_s"] for r in ok if r["derive_s"] is not None)
            if any(r["derive_s"] is not None for r in ok) else None,
            "equations_s": statistics.median(r["equations_s"] for r in ok if r["equations_s"] is not None)
            if any(r["equations_s"] is not None for r in ok) else None,
            "max_rss_kb": max(r["max_rss_kb"] for r in runs),
            "output_bytes": runs[-1]["output_bytes"],
            "repeats": len(runs),
            "samples_wall_s": [r["wall_s"] for r in runs],
            "samples_cpu_s": [r["cpu_s"] for r in runs],
            "exit_code": runs[-1]["exit_code"],
            "error": None if ok else (runs[-1]["stderr"] or f"exit {runs[-1]['exit_code']}"),
            "timed_out": any(r["timed_out"] for r in runs),
        }
        log(
            f"lagrange {system} N={n}: cpu={fmt_s(record['cpu_s'])} wall={fmt_s(record['wall_s'])} "
            f"exit={record['exit_code']}"
        )
        records.append(record)
    return records


# ------------------------------------------------------------------ anchors


def can_import(python: str, modules) -> bool:
    code = "; ".join(f"import {m}" for m in modules)
    try:
        return subprocess.run([python, "-c", code], capture_output=True, timeout=120).returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        return False


def pinned(anchors: Path, modules) -> list[str]:
    """`name==version` for `modules`, from the anchors' requirements files."""
    pins = {}
    for name in ("requirements.txt", "requirements-strong.txt"):
        path = anchors / name
        if not path.exists():
            continue
        for line in path.read_text().splitlines():
            line = line.split("#", 1)[0].strip()
            if "==" in line:
                pins.setdefault(line.split("==")[0].strip().lower(), line)
    return [pins.get(m, m) for m in modules]


def anchor_python(anchors: Path, modules, allow_install: bool) -> str | None:
    """A Python that imports `modules`: this one, the venv, or the venv after installing."""
    if can_import(sys.executable, modules):
        return sys.executable
    venv = Path(os.environ.get("TMPDIR") or "/tmp") / "lagrange-bench-venv"
    python = venv / "bin" / "python"
    if python.exists() and can_import(str(python), modules):
        return str(python)
    if not allow_install:
        log(f"no Python imports {', '.join(modules)} (and --no-install was given)")
        return None
    try:
        if not python.exists():
            log(f"creating {venv}")
            subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
        packages = pinned(anchors, VENV_MODULES)
        log(f"installing {' '.join(packages)} into {venv}")
        subprocess.run(
            [str(python), "-m", "pip", "install", "--quiet", *packages],
            check=True,
            timeout=900,
        )
    except (OSError, subprocess.SubprocessError) as err:
        log(f"cannot set up {venv}: {err}")
    if python.exists() and can_import(str(python), modules):
        return str(python)
    return None


def run_anchor(python: str, script: Path, args: list[str], timeout: float) -> tuple[list[dict], str | None]:
    """Runs an anchor script; its JSON lines and an error (or None). Progress goes to stderr."""
    log(f"running {script.name} {' '.join(args)}")
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    try:
        proc = subprocess.run(
            [python, str(script), *args],
            cwd=script.parent,
            stdout=subprocess.PIPE,
            stderr=None,
            text=True,
            timeout=timeout,
            env=env,
        )
        stdout, error = proc.stdout, None if proc.returncode == 0 else f"exit {proc.returncode}"
    except subprocess.TimeoutExpired as err:
        stdout = err.stdout.decode() if isinstance(err.stdout, bytes) else (err.stdout or "")
        error = f"timed out after {timeout:.0f} s"
    except OSError as err:
        return [], str(err)
    records = []
    for line in stdout.splitlines():
        try:
            records.append(json.loads(line))
        except json.JSONDecodeError:
            pass
    return records, error


def sympy_time(record: dict) -> float | None:
    """SymPy's derivation (build L + LagrangesMethod, M, f) in CPU seconds, without lambdify."""
    if record.get("error"):
        return None
    parts = [record.get("lagrangian_cpu_s"), record.get("equations_cpu_s")]
    return sum(parts) if all(p is not None for p in parts) else None


def symengine_time(record: dict) -> float | None:
    """SymEngine's derivation (L + M, f) in wall seconds (it reports no CPU time)."""
    if record.get("error") or record.get("skipped"):
        return None
    return record.get("wall_s")


# ------------------------------------------------------------------ report


def fmt_s(seconds: float | None) -> str:
    if seconds is None:
        return "n/a"
    if seconds < 1.0:
        return f"{seconds * 1e3:.2f} ms"
    return f"{seconds:.2f} s"


def fmt_ratio(anchor: float | None, ours: float | None) -> str:
    if anchor is None or ours is None or ours <= 0.0:
        return "n/a"
    ratio = anchor / ours
    return f"{ratio:.1f}x" if ratio >= 1.0 else f"{ratio:.2g}x"


def table(ours: list[dict], sympy: dict, symengine: dict) -> tuple[str, list[dict]]:
    rows = [
        "| system | N | lagrange process (CPU) | lagrange in-process: all | lagrange in-process: L, M, f "
        "| SymPy (CPU) | SymEngine (wall) | SymPy / lagrange process | SymEngine / lagrange all "
        "| SymEngine / lagrange L, M, f |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    ratios = []
    for record in ours:
        key = (record["system"], record["n"])
        mine = record["cpu_s"]
        sp_t = sympy.get(key)
        se_t = symengine.get(key)
        inproc = record.get("derive_s")
        eqs = record.get("equations_s")
        rows.append(
            f"| {key[0]} | {key[1]} | {fmt_s(mine)} | {fmt_s(inproc)} | {fmt_s(eqs)} | {fmt_s(sp_t)} "
            f"| {fmt_s(se_t)} | {fmt_ratio(sp_t, mine)} | {fmt_ratio(se_t, inproc)} | {fmt_ratio(se_t, eqs)} |"
        )
        ratios.append(
            {
                "bench": BENCH,
                "record": "ratio",
                "system": key[0],
                "n": key[1],
                "lagrange_cpu_s": mine,
                "sympy_cpu_s": sp_t,
                "symengine_wall_s": se_t,
                "sympy_over_lagrange": sp_t / mine if sp_t and mine else None,
                "symengine_over_lagrange": se_t / mine if se_t and mine else None,
                "lagrange_in_process_s": inproc,
                "symengine_over_lagrange_in_process": se_t / inproc if se_t and inproc else None,
                "lagrange_equations_s": eqs,
                "symengine_over_lagrange_equations": se_t / eqs if se_t and eqs else None,
            }
        )
    return "\n".join(rows), ratios


def fit_exponent(points: list[tuple[int, float]]) -> float | None:
    """Least-squares slope of log(value) against log(N)."""
    pts = [(n, v) for n, v in points if v and v > 0]
    if len(pts) < 2:
        return None
    xs = [math.log(n) for n, _ in pts]
    ys = [math.log(v) for _, v in pts]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    sxx = sum((x - mx) ** 2 for x in xs)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx if sxx > 0 else None


def scaling_fits(ours: list[dict], sympy: dict, symengine: dict, n_min: int = 4) -> list[dict]:
    """Fitted growth exponents on the N-link pendulum for N >= n_min (small N is start-up)."""
    series = {
        "lagrange in-process, all": [(r["n"], r.get("derive_s")) for r in ours if r["system"] == "pendulum"],
        "lagrange in-process, L, M, f": [(r["n"], r.get("equations_s")) for r in ours if r["system"] == "pendulum"],
        "lagrange output size (bytes)": [(r["n"], r.get("output_bytes")) for r in ours if r["system"] == "pendulum"],
        "SymPy": [(n, t) for (system, n), t in sympy.items() if system == "pendulum"],
        "SymEngine": [(n, t) for (system, n), t in symengine.items() if system == "pendulum"],
    }
    fits = []
    for what, points in series.items():
        pts = sorted((n, v) for n, v in points if n >= n_min and v)
        exponent = fit_exponent(pts)
        if exponent is not None:
            fits.append({"bench": BENCH, "record": "scaling", "what": what, "exponent": exponent,
                         "sizes": [n for n, _ in pts]})
    return fits


# ------------------------------------------------------------------ main


def sizes(text: str) -> list[int]:
    return [int(x) for x in text.replace(",", " ").split() if x]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true",
                        help="small sizes, one repeat, short anchor timeouts (about a minute)")
    parser.add_argument("--pendulum-sizes", type=sizes, default=None,
                        help="comma-separated N of the N-link pendulum (default 1..10; up to 64)")
    parser.add_argument("--chain-sizes", type=sizes, default=None,
                        help="comma-separated N of the spring chain (default 10,50; 100, 1000 optional)")
    parser.add_argument("--repeats", type=int, default=None, help="runs per size of ours (default 5; quick 3)")
    parser.add_argument("--anchor-repeats", type=int, default=None,
                        help="fresh-process repeats per size of the anchors (default 3; quick 1)")
    parser.add_argument("--step-timeout", type=float, default=None,
                        help="seconds one anchor step may take before larger N are skipped (default 60; quick 15)")
    parser.add_argument("--anchor-timeout", type=float, default=None,
                        help="seconds for one whole anchor script (default 1200; quick 300)")
    parser.add_argument("--timeout", type=float, default=None,
                        help="seconds for one run of ours (default 300; quick 60)")
    parser.add_argument("--no-sympy", action="store_true", help="skip the SymPy anchor")
    parser.add_argument("--no-symengine", action="store_true", help="skip the SymEngine anchor")
    parser.add_argument("--no-install", action="store_true", help="never create or fill the anchors' venv")
    parser.add_argument("--no-build", action="store_true", help="never run cargo build")
    parser.add_argument("--binary", type=Path, default=REPO / "target" / "release" / "lagrange")
    parser.add_argument("--anchors", type=Path, default=DEFAULT_ANCHORS,
                        help="folder of sympy_derive.py and symengine_derive.py (default $REPO/../shared/bench)")
    parser.add_argument("--models", type=Path, default=None,
                        help="write the model files here and keep them (default: a temporary folder)")
    parser.add_argument("--out", type=Path, default=None,
                        help="JSON lines file (default ${TMPDIR:-/tmp}/lagrange-derive-bench.jsonl)")
    args = parser.parse_args(argv)

    quick = args.quick
    pendulum_sizes = args.pendulum_sizes or ([1, 2, 3, 4] if quick else list(range(1, 11)))
    chain_sizes = args.chain_sizes if args.chain_sizes is not None else ([10] if quick else [10, 50])
    repeats = args.repeats or (3 if quick else 5)
    anchor_repeats = args.anchor_repeats or (1 if quick else 3)
    step_timeout = args.step_timeout or (15.0 if quick else 60.0)
    anchor_timeout = args.anchor_timeout or (300.0 if quick else 1200.0)
    timeout = args.timeout or (60.0 if quick else 300.0)
    out_path = args.out or Path(os.environ.get("TMPDIR") or "/tmp") / "lagrange-derive-bench.jsonl"
    if max(pendulum_sizes, default=0) > 64:
        parser.error("pendulum sizes go up to 64")

    machine = {
        "bench": BENCH,
        "record": "machine",
        "nproc": os.cpu_count(),
        "platform": platform.platform(),
        "python": platform.python_version(),
        "binary": str(args.binary),
        "load_avg": os.getloadavg(),
        "argv": sys.argv[1:],
    }
    records: list[dict] = [machine]

    # 1. model files
    model_dir = args.models or Path(tempfile.mkdtemp(prefix="lagrange-derive-bench-"))
    model_dir.mkdir(parents=True, exist_ok=True)
    models = []
    for n in pendulum_sizes:
        path = model_dir / f"pendulum_{n}.toml"
        path.write_text(pendulum_model(n))
        models.append(("pendulum", n, path))
    for n in chain_sizes:
        path = model_dir / f"chain_{n}.toml"
        path.write_text(chain_model(n))
        models.append(("chain", n, path))
    log(f"{len(models)} model files in {model_dir}")

    # 2. ours
    ours = []
    if ensure_binary(args.binary, not args.no_build):
        ours = measure_ours(args.binary, models, repeats, timeout)
    else:
        ours = [
            {"bench": BENCH, "record": "result", "tool": "lagrange", "system": s, "n": n,
             "wall_s": None, "cpu_s": None, "error": "no binary"}
            for s, n, _ in models
        ]
    records += ours

    # 3. anchors
    sympy_times: dict = {}
    symengine_times: dict = {}
    anchors = args.anchors.resolve()
    if not args.no_sympy:
        script = anchors / "sympy_derive.py"
        python = anchor_python(anchors, ("sympy", "numpy", "scipy"), not args.no_install) if script.exists() else None
        if python is None:
            log(f"SymPy anchor n/a ({script} missing or no Python with sympy, numpy and scipy)")
            records.append({"bench": BENCH, "record": "anchor_error", "anchor": "sympy_derive",
                            "error": "not available"})
        else:
            anchor_args = ["--system", "all", "--repeats", str(anchor_repeats),
                           "--step-timeout", str(step_timeout), "--no-count-ops", "--no-cse"]
            anchor_args += ["--pendulum-sizes", ",".join(map(str, pendulum_sizes))]
            # The script runs its default chain sizes when given none: pass ours (or skip).
            if chain_sizes:
                anchor_args += ["--chain-sizes", ",".join(map(str, chain_sizes))]
            else:
                anchor_args[1] = "pendulum"
            found, error = run_anchor(python, script, anchor_args, anchor_timeout)
            for record in found:
                record["source"] = "sympy_derive"
                if record.get("record") == "result" and record.get("style", "expr") in ("expr", "string"):
                    sympy_times[(record.get("system"), record.get("n"))] = sympy_time(record)
            records += found
            if error:
                log(f"SymPy anchor: {error}")
                records.append({"bench": BENCH, "record": "anchor_error", "anchor": "sympy_derive",
                                "error": error})
    if not args.no_symengine:
        script = anchors / "symengine_derive.py"
        python = anchor_python(anchors, ("sympy", "symengine"), not args.no_install) if script.exists() else None
        if python is None:
            log(f"SymEngine anchor n/a ({script} missing or no Python with symengine)")
            records.append({"bench": BENCH, "record": "anchor_error", "anchor": "symengine_derive",
                            "error": "not available"})
        else:
            anchor_args = ["--sizes", *map(str, pendulum_sizes), "--variants", "raw",
                           "--repeats", str(anchor_repeats), "--step-timeout", str(step_timeout),
                           "--no-extras", "--no-lambdify"]
            found, error = run_anchor(python, script, anchor_args, anchor_timeout)
            for record in found:
                record["source"] = "symengine_derive"
                if record.get("record") == "result" and record.get("variant") == "raw":
                    symengine_times[("pendulum", record.get("n"))] = symengine_time(record)
            records += found
            if error:
                log(f"SymEngine anchor: {error}")
                records.append({"bench": BENCH, "record": "anchor_error", "anchor": "symengine_derive",
                                "error": error})

    # 4. report
    text, ratios = table(ours, sympy_times, symengine_times)
    records += ratios
    scaling = scaling_fits(ours, sympy_times, symengine_times)
    records += scaling
    out_path.parent.mkdir(parents=True, exist_ok=True)
    with out_path.open("w") as handle:
        for record in records:
            handle.write(json.dumps(record, default=str) + "\n")
    print(text)
    print()
    for fit in scaling:
        print(f"- {fit['what']}: time ~ N^{fit['exponent']:.2f} over N = {fit['sizes']}")
    print()
    print(
        "lagrange process: whole `derive --format json` process, CPU seconds (median); lagrange in-process: "
        "parse + derivation (M, f, momenta, H, Hamilton's equations, verdicts) inside the process, wall "
        "seconds (the JSON field derive_seconds); L, M, f: parse + L, M and f only, the steps the SymEngine "
        "script times (the JSON field equations_seconds). SymPy: build L + "
        "LagrangesMethod M, f (no lambdify), CPU seconds. SymEngine: L + M, f, wall seconds. "
        f"Same machine, same run. JSON lines: {out_path}"
    )
    if args.models is None:
        shutil.rmtree(model_dir, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
