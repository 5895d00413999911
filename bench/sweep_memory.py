#!/usr/bin/env python3
"""Peak memory of `lagrange sweep` as the grid grows: a sweep streams its rows to --out in
grid order through a bounded window, so its peak resident memory must not depend on the
number of runs. The target (issue #15): a sweep of 10^6 runs peaks under 100 MB.

    python3 bench/sweep_memory.py                  # 10^4 and 10^6 runs (a minute or two)
    python3 bench/sweep_memory.py --sides 100,300,1000,3000

Each case runs `target/release/lagrange sweep examples/double_pendulum.toml --until 1
--grid "a=-3:3:N,b=-3:3:N" --no-lyapunov --out TMP.csv` (N×N runs; the binary is built
with `cargo build --release` if it is missing), measures the child's wall time and its
peak resident set size (`ru_maxrss` of `os.wait4`: the kernel's own accounting of the
finished process; run under GNU `/usr/bin/time -f %M` where it exists, since a child forked
from Python counts the interpreter's pages in its peak until it execs), checks that the
CSV holds every row in grid order (read line by line, then deleted), and prints one line per case with the peak against the target. Every
record goes as JSON lines to --out (default ${TMPDIR:-/tmp}/lagrange-sweep-memory.jsonl).
Standard library only. Exits 1 when a case fails or a peak exceeds the target.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

sys.dont_write_bytecode = True  # importing derive.py must not leave bench/__pycache__
sys.path.insert(0, str(Path(__file__).resolve().parent))

import derive as derive_bench  # noqa: E402  (ensure_binary)

REPO = Path(__file__).resolve().parent.parent
BENCH = "lagrange_sweep_memory"
TARGET_MB = 100.0
GNU_TIME = "/usr/bin/time"
PEAK_MARK = "lagrange-sweep-peak-kib"


def log(message: str) -> None:
    print(f"[sweep_memory.py] {message}", file=sys.stderr, flush=True)


def rows_in_order(csv: Path) -> int | None:
    """The number of rows after the two header lines, or None if a row is out of order."""
    with csv.open("rb") as f:
        f.readline()
        f.readline()
        count = 0
        for line in f:
            if not line.startswith(f"{count},".encode()):
                return None
            count += 1
        return count


def measure(binary: Path, side: int, until: float, threads: int | None, timeout: float) -> dict:
    grid = f"a=-3:3:{side},b=-3:3:{side}"
    with tempfile.TemporaryDirectory() as folder:
        csv = Path(folder) / "sweep.csv"
        args = [str(binary), "sweep", "examples/double_pendulum.toml", "--until", repr(until), "--grid", grid,
                "--no-lyapunov", "--out", str(csv)]
        if threads:
            args += ["--threads", str(threads)]
        # GNU time forks from a small process: its %M is the sweep's own peak.
        timed = Path(GNU_TIME).exists()
        if timed:
            args = [GNU_TIME, "-f", f"{PEAK_MARK} %M"] + args
        start = time.perf_counter()
        with tempfile.TemporaryFile() as err:
            proc = subprocess.Popen(args, cwd=REPO, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=err)
            killer = threading.Timer(timeout, proc.kill)
            killer.start()
            try:
                _, status, usage = os.wait4(proc.pid, 0)
            finally:
                killer.cancel()
            wall = time.perf_counter() - start
            proc.returncode = os.waitstatus_to_exitcode(status)
            err.seek(0)
            stderr = err.read().decode(errors="replace").strip()
        peak_kib = usage.ru_maxrss
        if timed:
            marks = [line for line in stderr.splitlines() if line.startswith(PEAK_MARK)]
            stderr = "\n".join(line for line in stderr.splitlines() if not line.startswith(PEAK_MARK))
            peak_kib = int(marks[-1].split()[-1]) if marks else None
        rows = rows_in_order(csv) if proc.returncode == 0 else None
        csv_bytes = csv.stat().st_size if csv.exists() else 0
    error = None
    if proc.returncode != 0:
        error = f"exit {proc.returncode}: {stderr[-300:]}"
    elif rows != side * side:
        error = f"the CSV has {rows} rows in grid order, not {side * side}"
    return {
        "bench": BENCH,
        "record": "sweep",
        "tool": "lagrange",
        "runs": side * side,
        "grid": grid,
        "until": until,
        "threads": threads,
        "wall_s": wall,
        # Both are in KiB on Linux.
        "peak_rss_mb": None if peak_kib is None else peak_kib * 1024 / 1e6,
        "peak_from": "GNU time %M" if timed else "os.wait4 ru_maxrss (includes the Python interpreter's pages)",
        "csv_mb": csv_bytes / 1e6,
        "target_mb": TARGET_MB,
        "error": error,
        "stderr": stderr[-300:],
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sides", default="100,1000", help="comma-separated N: N×N runs each (default 100,1000)")
    parser.add_argument("--until", type=float, default=1.0, help="end time of every run (default 1)")
    parser.add_argument("--threads", type=int, default=None, help="worker threads (default: one per core)")
    parser.add_argument("--timeout", type=float, default=1800.0, help="seconds per case")
    parser.add_argument("--binary", default=None, help="the lagrange binary (default target/release/lagrange)")
    parser.add_argument("--no-build", action="store_true", help="never run cargo")
    parser.add_argument("--no-install", action="store_true", help="accepted for bench/all.py; nothing is installed")
    parser.add_argument("--out", default=str(Path(tempfile.gettempdir()) / "lagrange-sweep-memory.jsonl"))
    args = parser.parse_args(argv)

    binary = Path(args.binary) if args.binary else REPO / "target" / "release" / "lagrange"
    if not derive_bench.ensure_binary(binary, not args.no_build):
        return 1
    records = [{"bench": BENCH, "record": "machine", "platform": platform.platform(), "cpus": os.cpu_count()}]
    status = 0
    print("| runs | wall (s) | peak RSS (MB) | CSV (MB) | target (MB) | |")
    print("| ---: | ---: | ---: | ---: | ---: | --- |")
    for side in (int(s) for s in args.sides.split(",") if s.strip()):
        log(f"sweep of {side}x{side} runs")
        r = measure(binary, side, args.until, args.threads, args.timeout)
        records.append(r)
        peak = r["peak_rss_mb"]
        if peak is None and not r["error"]:
            r["error"] = "no peak reported"
        verdict = r["error"] or ("under the target" if peak < TARGET_MB else "OVER THE TARGET")
        if r["error"] or peak >= TARGET_MB:
            status = 1
        shown = "n/a" if peak is None else f"{peak:.1f}"
        print(f"| {r['runs']} | {r['wall_s']:.1f} | {shown} | {r['csv_mb']:.0f} | {TARGET_MB:.0f} | {verdict} |",
              flush=True)
    with open(args.out, "w") as f:
        for r in records:
            f.write(json.dumps(r) + "\n")
    log(f"records in {args.out}")
    return status


if __name__ == "__main__":
    sys.exit(main())
