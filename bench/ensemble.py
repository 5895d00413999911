#!/usr/bin/env python3
"""Ensembles against heyoka, in one run: the double pendulum's chaos map.

Measures, on the same machine and in the same run:

1. heyoka's batch integrator on the map (../shared/bench/heyoka_simulate.py,
   --problems ensemble, its own threads with one and two workers, tolerance 1e-10):
   its wall time per map, its cold compile time, and its accuracy as that script
   measures it (|E(t) - E(0)| / (3 g) at the end, max and median over the map);
2. `lagrange sweep` of the same map (examples/double_pendulum.toml, a, b on
   0..3.1, velocities 0, t = 0..20, rtol = atol = 1e-10, --no-lyapunov):
   - on one and two threads with the system C compiler's code found in the cache
     (a sweep of a small grid fills a fresh cache first), whole process;
   - the compile cost alone (from the sweep's summary line, cold cache);
   - end to end from a cold cache on the small map (default 100x100), against
     heyoka's compile + propagate;
   - cranelift's code (LAGRANGE_CC=off) on one thread, the fallback;
   with the accuracy computed from the CSV's final states as heyoka's script does.

Prints a Markdown table and writes JSON lines (--out). Times are medians of
--repeats whole-process runs (time.perf_counter around the subprocess).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO / "bench"))
import simulate as simulate_bench  # noqa: E402  (the heyoka venv and the anchors' folder)
import derive as derive_bench  # noqa: E402

BENCH = "ensemble"
G = 9.81


def log(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def energy(a: float, b: float, da: float, db: float) -> float:
    """The double pendulum's E with m = l = 1 (the example's parameters)."""
    t = 0.5 * (2 * da * da + db * db + 2 * da * db * math.cos(a - b))
    return t - G * (2 * math.cos(a) + math.cos(b))


def accuracy(csv: Path) -> tuple[float, float]:
    """max and median over the map of |E(T) - E(0)| / (3 g), heyoka's measure."""
    errors = []
    with csv.open() as f:
        header = None
        for line in f:
            if line.startswith("#"):
                continue
            if header is None:
                header = line.strip().split(",")
                at = {name: i for i, name in enumerate(header)}
                continue
            v = line.strip().split(",")
            a0, b0 = float(v[at["a"]]), float(v[at["b"]])
            e0 = energy(a0, b0, 0.0, 0.0)
            e1 = energy(*(float(v[at[c]]) for c in ("final_a", "final_b", "final_a'", "final_b'")))
            errors.append(abs(e1 - e0) / (3 * G))
    return max(errors), statistics.median(errors)


def sweep(binary: Path, grid: int, until: float, threads: int, out: Path, env: dict) -> tuple[float, str]:
    """One `lagrange sweep`: its wall time and its stderr."""
    args = [str(binary), "sweep", "examples/double_pendulum.toml", "--until", repr(until),
            "--grid", f"a=0:3.1:{grid},b=0:3.1:{grid}", "--rtol", "1e-10", "--atol", "1e-10",
            "--threads", str(threads), "--no-lyapunov", "--out", str(out)]
    start = time.perf_counter()
    proc = subprocess.run(args, cwd=REPO, capture_output=True, text=True, env={**os.environ, **env})
    wall = time.perf_counter() - start
    if proc.returncode != 0:
        raise RuntimeError(f"lagrange sweep failed: {proc.stderr.strip()[-400:]}")
    return wall, proc.stderr


def compile_seconds(stderr: str) -> float | None:
    m = re.search(r"compiled by .*? in ([0-9.]+) s", stderr)
    return float(m.group(1)) if m else None


def heyoka(python: str, anchors: Path, grid: int, until: float, repeats: int) -> list[dict]:
    args = ["--problems", "ensemble", "--ensemble-tols", "1e-10", "--ensemble-modes", "threads",
            "--workers", "1", "2", "--ensemble-repeats", str(repeats), "--ensemble-grid", str(grid),
            "--ensemble-t-end", repr(until)]
    records, error = derive_bench.run_anchor(python, anchors / "heyoka_simulate.py", args, 3600)
    if error:
        log(f"heyoka_simulate.py: {error}")
    return [r for r in records if r.get("record") == "ensemble"]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--grid", type=int, default=200, help="points per angle of the map (default 200)")
    parser.add_argument("--small", type=int, default=100, help="the map timed end to end from a cold cache (default 100)")
    parser.add_argument("--until", type=float, default=20.0)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--binary", type=Path, default=REPO / "target" / "release" / "lagrange")
    parser.add_argument("--no-build", action="store_true")
    parser.add_argument("--no-heyoka", action="store_true")
    parser.add_argument("--no-install", action="store_true")
    parser.add_argument("--anchors", type=Path, default=simulate_bench.DEFAULT_ANCHORS)
    parser.add_argument("--out", type=Path, default=Path(tempfile.gettempdir()) / "lagrange-ensemble-bench.jsonl")
    args = parser.parse_args(argv)
    if not derive_bench.ensure_binary(args.binary, build=not args.no_build):
        return 1

    records: list[dict] = [{"bench": BENCH, "record": "machine", "nproc": os.cpu_count()}]
    hey: dict[tuple[int, int], dict] = {}
    if not args.no_heyoka:
        python = simulate_bench.heyoka_python(args.anchors, allow_install=not args.no_install)
        if python is None:
            log("no Python imports heyoka: its rows are n/a")
        else:
            for grid in sorted({args.grid, args.small}):
                for r in heyoka(python, args.anchors, grid, args.until, args.repeats):
                    hey[(grid, r["workers"])] = r
                    records.append({**r, "source": "heyoka_simulate.py"})

    work = Path(tempfile.mkdtemp(prefix="lagrange-ensemble-"))
    out = work / "map.csv"
    ours: dict[str, dict] = {}
    try:
        # Cold: a fresh cache; the compile time from the summary, and the small map end to end.
        cold = []
        for i in range(args.repeats):
            cache = work / f"cold-{i}"
            wall, err = sweep(args.binary, args.small, args.until, 1, out, {"LAGRANGE_CACHE_DIR": str(cache)})
            cold.append((wall, compile_seconds(err)))
            shutil.rmtree(cache, ignore_errors=True)
        ours["cold_small_1"] = {"wall_s": statistics.median(w for w, _ in cold),
                                "compile_s": statistics.median(c for _, c in cold if c is not None) if any(c for _, c in cold) else None,
                                "grid": args.small, "threads": 1}
        warm_env = {"LAGRANGE_CACHE_DIR": str(work / "warm")}
        sweep(args.binary, 4, 1.0, 1, out, warm_env)  # fills the cache
        for key, grid, threads, env in [("warm_small_1", args.small, 1, warm_env), ("warm_1", args.grid, 1, warm_env),
                                        ("warm_2", args.grid, 2, warm_env),
                                        ("cranelift_1", args.grid, 1, {**warm_env, "LAGRANGE_CC": "off"})]:
            walls = []
            for _ in range(args.repeats):
                wall, err = sweep(args.binary, grid, args.until, threads, out, env)
                walls.append(wall)
                log(f"lagrange sweep {grid}x{grid} {key}: {wall:.2f} s")
            worst, median = accuracy(out)
            ours[key] = {"wall_s": statistics.median(walls), "walls_s": walls, "grid": grid, "threads": threads,
                         "energy_max": worst, "energy_median": median, "code": err.strip().splitlines()[-1]}
    finally:
        shutil.rmtree(work, ignore_errors=True)
    for key, r in ours.items():
        records.append({"bench": BENCH, "record": "lagrange", "case": key, **r})

    def ratio(h, o):
        return "n/a" if not h or not o else f"{h / o:.2f}×"

    n = args.grid * args.grid
    lines = [f"| chaos map {args.grid}×{args.grid}, t = 0..{args.until:g}, tol 1e-10 | wall | µs per run | "
             "heyoka / ours | energy error max / median |",
             "| --- | ---: | ---: | ---: | ---: |"]
    for key, label, workers in [("warm_1", "lagrange sweep, C code (cached), 1 thread", 1),
                                ("warm_2", "lagrange sweep, C code (cached), 2 threads", 2),
                                ("cranelift_1", "lagrange sweep, cranelift (LAGRANGE_CC=off), 1 thread", 1)]:
        o = ours[key]
        h = hey.get((args.grid, workers))
        lines.append(f"| {label} | {o['wall_s']:.2f} s | {o['wall_s'] / n * 1e6:.0f} | "
                     f"{ratio(h and h['wall_s'], o['wall_s'])} | {o['energy_max']:.1e} / {o['energy_median']:.1e} |")
    for workers in (1, 2):
        h = hey.get((args.grid, workers))
        if h:
            lines.append(f"| heyoka ensemble, batch {h['batch_size']}, {workers} worker{'s' if workers > 1 else ''} "
                         f"| {h['wall_s']:.2f} s | {h['wall_s'] / n * 1e6:.0f} | | "
                         f"{h['energy_rel_drift']:.1e} / {h['energy_rel_drift_median']:.1e} |")
    c = ours["cold_small_1"]
    hs = hey.get((args.small, 1))
    small = [f"\n| {args.small}×{args.small} map, 1 thread, end to end | ours | heyoka | heyoka / ours |",
             "| --- | ---: | ---: | ---: |",
             f"| compile (cold cache) | {c['compile_s'] or float('nan'):.2f} s | "
             f"{hs['compile_s'] if hs else float('nan'):.2f} s | |",
             f"| whole map from a cold cache (compile included) | {c['wall_s']:.2f} s | "
             f"{(hs['compile_s'] + hs['wall_s']) if hs else float('nan'):.2f} s | "
             f"{ratio(hs and hs['compile_s'] + hs['wall_s'], c['wall_s'])} |",
             f"| whole map, cache warm (heyoka: its compile included) | {ours['warm_small_1']['wall_s']:.2f} s | "
             f"{(hs['compile_s'] + hs['wall_s']) if hs else float('nan'):.2f} s | "
             f"{ratio(hs and hs['compile_s'] + hs['wall_s'], ours['warm_small_1']['wall_s'])} |"]
    text = "\n".join(lines + small)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with args.out.open("w") as f:
        for r in records:
            f.write(json.dumps(r, default=str) + "\n")
    print(text)
    log(f"records in {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
