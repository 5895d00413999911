#!/usr/bin/env python3
"""Benchmark lagrange at scale against Pinocchio, in one run: the table of issue 30.

What it does, one process after another in this job (single-core measurements):

1. runs ../shared/bench/pinocchio_rhs.py (with --pinocchio-python, a Python that can
   import `pinocchio`): Pinocchio's `aba` per call on the planar n-link pendulum
   (n = 10, 20, 50, 100 by default) and on example-robot-data robots, and a whole
   SciPy DOP853 integration to t = 10 calling `pin.aba` (rtol = atol = 1e-9);
2. runs ../shared/bench/lagrange_scale.py: `lagrange derive` time for the particle
   chain (the same n-link pendulum) and for a chain of rods written as a body tree,
   and `lagrange simulate --until 10 --method dop853` on the particle chain (whole
   process, and microseconds per right-hand side: the integration alone, i.e. the
   summary's wall_seconds less the compile (setup_seconds - derive_seconds), over
   rhs_evaluations), at the same rtol = atol as the anchor;
3. for each robot Pinocchio loaded from a URDF file: `lagrange import` it, start every
   joint (not a floating base) turning at 0.5 rad/s, then
   `lagrange simulate --until 10 --method dop853` (us per rhs as above);
4. prints every record as JSON lines on stdout (the anchors' own, tagged with `source`;
   then `robot` and `ratio` records), then the Markdown table; ratios are
   lagrange / anchor measured in this run (less than 1 means lagrange is faster).
   Progress goes to stderr.

A derivation that exits 2 at lagrange's work bound shows as "bound", one killed at
--timeout as "timeout". Where Pinocchio cannot be imported the script says so and still
prints lagrange's rows. Standard library only (the anchor needs its own venv:
`python3 -m venv V && V/bin/pip install pin example-robot-data numpy scipy`).

  python3 bench/scale.py --pinocchio-python V/bin/python --quick   # a few minutes
  python3 bench/scale.py --pinocchio-python V/bin/python            # full repeats
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
DEFAULT_ANCHORS = REPO.parent / "shared" / "bench"
BENCH = "lagrange_scale_table"


def log(message: str) -> None:
    print(f"[scale.py] {message}", file=sys.stderr, flush=True)


def emit(record: dict) -> None:
    print(json.dumps({"bench": BENCH, **record}, allow_nan=False), flush=True)


def sizes(text: str) -> list[int]:
    return [int(s) for s in text.split(",") if s.strip()]


def run_lines(argv: list[str], source: str, timeout: float) -> list[dict]:
    """Run one anchor script; re-emit its JSON lines tagged with `source`; return them."""
    log("running " + " ".join(argv))
    try:
        proc = subprocess.run(argv, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired as error:
        emit({"record": "anchor_error", "source": source, "error": f"passed {timeout} s, killed"})
        out = error.stdout.decode() if isinstance(error.stdout, bytes) else (error.stdout or "")
    else:
        out = proc.stdout
        if proc.returncode != 0:
            emit({"record": "anchor_error", "source": source, "exit": proc.returncode, "error": proc.stderr[-2000:]})
            log(f"{source}: exit {proc.returncode}: {proc.stderr.strip().splitlines()[-1:]}")
    records = []
    for line in out.splitlines():
        if line.startswith("{"):
            record = json.loads(line)
            records.append(record)
            print(json.dumps({**record, "source": source}), flush=True)
    return records


def run_timed(argv: list[str], timeout: float):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(argv, capture_output=True, text=True, timeout=timeout)
        code, out, err = proc.returncode, proc.stdout, proc.stderr
    except subprocess.TimeoutExpired:
        code, out, err = None, "", ""
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return code, out, err, wall, cpu


# The imported model starts at rest, where a floating robot only falls (a hundred right-hand
# sides, too few to time); every joint (not the floating base) starts turning at this rate.
ROBOT_JOINT_RATE = 0.5


def set_joint_rates(model: str, rate: float) -> None:
    """Sets the initial velocity of every joint coordinate of an imported model to `rate`."""
    lines = Path(model).read_text().splitlines()
    out, base = [], False
    for line in lines:
        if re.match(r"^[A-Za-z_][A-Za-z0-9_]* = ", line):
            base = "floating base" in line
        velocity = re.match(r'^"([A-Za-z_][A-Za-z0-9_]*)\'" = 0$', line)
        if velocity and not base:
            line = f'"{velocity.group(1)}\'" = {rate}'
        out.append(line)
    Path(model).write_text("\n".join(out) + "\n")


def robot_lagrange(binary: str, name: str, urdf: str, floating: bool, args, folder: str) -> dict:
    """lagrange import + simulate of one URDF robot; one `robot` record."""
    base = {"record": "robot", "system": name, "urdf": urdf, "until": args.robot_until}
    model = os.path.join(folder, f"{name}.toml")
    argv = [binary, "import", urdf, "-o", model] + (["--floating-base"] if floating else [])
    code, _, err, _, _ = run_timed(argv, args.timeout)
    if code != 0:
        return {**base, "stage": "import", "exit": code, "error": err[-2000:], "outcome": outcome(code, err)}
    set_joint_rates(model, ROBOT_JOINT_RATE)
    argv = [binary, "simulate", model, "--until", str(args.robot_until), "--method", "dop853",
            "--rtol", str(args.rtol), "--atol", str(args.rtol), "--summary", "json"]
    code, out, err, wall, cpu = run_timed(argv, args.timeout)
    if code != 0:
        return {**base, "stage": "simulate", "exit": code, "error": err[-2000:], "outcome": outcome(code, err)}
    summary = json.loads(out)
    rhs = summary.get("rhs_evaluations") or 0
    try:  # wall_seconds = compile + integrate; setup_seconds = parse + derive + compile
        integ = summary["wall_seconds"] - (summary["setup_seconds"] - summary["derive_seconds"])
    except (KeyError, TypeError):
        integ = None
    return {
        **base,
        "outcome": "ok",
        "process_wall_s": wall,
        "process_cpu_s": cpu,
        "derive_seconds": summary.get("derive_seconds"),
        "setup_seconds": summary.get("setup_seconds"),
        "wall_seconds": summary.get("wall_seconds"),
        "rhs_evaluations": rhs,
        "us_per_rhs": summary["wall_seconds"] / rhs * 1e6 if rhs and summary.get("wall_seconds") else None,
        "integrate_only_s_est": integ,
        "us_per_rhs_integrate_only_est": integ / rhs * 1e6 if rhs and integ is not None else None,
    }


def outcome(code, err: str) -> str:
    if code is None:
        return "timeout"
    if code == 2 and "bound" in err:
        return "bound"
    return f"exit {code}"


# ------------------------------------------------------------------ table


def fmt(value, unit: str = "") -> str:
    if value is None:
        return "n/a"
    if isinstance(value, str):
        return value
    if unit == "x":
        return f"{value:.2g}x" if value < 10 else f"{value:.0f}x"
    if value >= 100:
        return f"{value:,.0f}"
    if value >= 1:
        return f"{value:.2f}"
    return f"{value:.3g}"


def ratio(ours, anchor):
    if isinstance(ours, (int, float)) and isinstance(anchor, (int, float)) and anchor > 0:
        return ours / anchor
    return None


def table(pin: list[dict], lag: list[dict], robots: list[dict], ns: list[int], pin_note: str | None) -> list[str]:
    def pick(records, **match):
        for r in records:
            if all(r.get(k) == v for k, v in match.items()):
                return r
        return None

    def derive_cell(family, n):
        r = pick(lag, record="derive", system=family, n=n)
        if r is None:  # lagrange_scale.py stops a family at its first bound or timeout
            return "not run"
        if r.get("timeout"):
            return "timeout"
        if r.get("error") is not None:
            return "bound" if "bound" in r["error"] else "error"
        return r["wall_s"]

    rows = {k: [] for k in ("aba", "rhs", "r1", "scipy", "sim", "r2", "dpart", "dbody")}
    for n in ns:
        a = pick(pin, record="rhs", system=f"nlink{n}", algo="aba")
        aba = a["us_per_call"] if a else None
        s = pick(lag, record="simulate", system="nlink", n=n, method_asked="dop853")
        us = s.get("us_per_rhs_integrate_only_est") if s and not s.get("timeout") and s.get("error") is None else None
        whole = s.get("process_wall_s") if us is not None else ("timeout" if s and s.get("timeout") else None)
        i = pick(pin, record="integrate", system=f"nlink{n}")
        scipy_s = i.get("wall_s") if i and "wall_s" in i else ("timeout" if i and i.get("timeout") else None)
        rows["aba"].append(fmt(aba))
        rows["rhs"].append(fmt(us))
        rows["r1"].append(fmt(ratio(us, aba), "x"))
        rows["scipy"].append(fmt(scipy_s))
        rows["sim"].append(fmt(whole))
        rows["r2"].append(fmt(ratio(whole, scipy_s), "x"))
        rows["dpart"].append(fmt(derive_cell("nlink", n)))
        rows["dbody"].append(fmt(derive_cell("bodychain", n)))
    labels = {
        "aba": "Pinocchio aba µs/call",
        "rhs": "lagrange µs/rhs (dop853, integration only)",
        "r1": "ratio lagrange / Pinocchio",
        "scipy": "Pinocchio+SciPy DOP853 whole s",
        "sim": "lagrange simulate dop853 whole s",
        "r2": "ratio lagrange / Pinocchio+SciPy",
        "dpart": "lagrange derive particles s",
        "dbody": "lagrange derive body tree s",
    }
    lines = []
    if pin_note:
        lines.append(f"Pinocchio: {pin_note}")
        lines.append("")
    lines.append("| planar n-link pendulum | " + " | ".join(f"n = {n}" if i == 0 else str(n) for i, n in enumerate(ns)) + " |")
    lines.append("| --- |" + " ---: |" * len(ns))
    for key, label in labels.items():
        lines.append(f"| {label} | " + " | ".join(rows[key]) + " |")
    models = [r for r in pin if r.get("record") == "model" and not str(r.get("system", "")).startswith("nlink")]
    if models:
        lines.append("")
        lines.append("| URDF robot | nq / nv | Pinocchio aba µs/call | lagrange µs/rhs (dop853, integration only) | ratio | lagrange import + simulate |")
        lines.append("| --- | --- | ---: | ---: | ---: | --- |")
        for m in models:
            name = m["system"]
            if m.get("error"):
                lines.append(f"| {name} | – | not loaded | – | – | – |")
                continue
            a = pick(pin, record="rhs", system=name, algo="aba")
            aba = a["us_per_call"] if a else None
            r = pick(robots, system=name)
            us = r.get("us_per_rhs_integrate_only_est") if r else None
            how = "not run" if r is None else (
                f"ok, derive {r['derive_seconds']:.2f} s" if r.get("outcome") == "ok" else f"{r['stage']}: {r['outcome']}")
            lines.append(f"| {name} | {m['nq']} / {m['nv']} | {fmt(aba)} | {fmt(us)} | {fmt(ratio(us, aba), 'x')} | {how} |")
    return lines


# ------------------------------------------------------------------ main


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true",
                        help="fewer repeats and calls, 60 s timeouts, robots panda and ur5 (a few minutes)")
    parser.add_argument("--sizes", type=sizes, default=[10, 20, 50, 100], help="pendulum sizes n (default 10,20,50,100)")
    parser.add_argument("--body-sizes", type=sizes, default=None, help="body-tree chain sizes (default: --sizes)")
    parser.add_argument("--robots", default=None, help="example-robot-data names, '' for none (default panda,ur5,talos; quick panda,ur5)")
    parser.add_argument("--until", type=float, default=10.0, help="t_end of the pendulum simulations (both sides)")
    parser.add_argument("--robot-until", type=float, default=10.0, help="t_end of lagrange's robot simulations")
    parser.add_argument("--rtol", type=float, default=1e-9, help="rtol = atol on both sides (default 1e-9)")
    parser.add_argument("--repeats", type=int, default=None, help="timing samples (default 7 Pinocchio / 3 lagrange; quick 3 / 1)")
    parser.add_argument("--timeout", type=float, default=None, help="kill one lagrange process / abandon one integration after this many s (default 300; quick 60)")
    parser.add_argument("--pinocchio-python", default=os.environ.get("PINOCCHIO_PYTHON", sys.executable),
                        help="a Python that imports pinocchio (default $PINOCCHIO_PYTHON or this one)")
    parser.add_argument("--no-pinocchio", action="store_true", help="skip the anchor")
    parser.add_argument("--no-build", action="store_true", help="never run cargo build")
    parser.add_argument("--binary", default=str(REPO / "target" / "release" / "lagrange"))
    parser.add_argument("--anchors", type=Path, default=DEFAULT_ANCHORS, help="folder of pinocchio_rhs.py, lagrange_scale.py")
    args = parser.parse_args()
    quick = args.quick
    repeats_pin = args.repeats or (3 if quick else 7)
    repeats_lag = args.repeats or (1 if quick else 3)
    args.timeout = args.timeout or (60.0 if quick else 300.0)
    robots = args.robots if args.robots is not None else ("panda,ur5" if quick else "panda,ur5,talos")
    body_sizes = args.body_sizes or args.sizes
    ns = args.sizes

    if not os.path.exists(args.binary):
        if args.no_build:
            parser.error(f"no lagrange binary at {args.binary} (and --no-build)")
        log("building: cargo build --release --bin lagrange")
        if subprocess.run(["cargo", "build", "--release", "--bin", "lagrange"], cwd=REPO).returncode != 0:
            sys.exit("cargo build failed")
    for script in ("pinocchio_rhs.py", "lagrange_scale.py"):
        if not (args.anchors / script).exists():
            parser.error(f"no {script} in {args.anchors} (pass --anchors, the shared bench folder)")
    version = subprocess.run([args.binary, "--version"], capture_output=True, text=True).stdout.strip()
    env_note = {k: "1" for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}
    os.environ.update(env_note)
    emit({"record": "run", "binary": args.binary, "lagrange_version": version, "quick": quick,
          "sizes": ns, "body_sizes": body_sizes, "robots": robots, "rtol": args.rtol, "atol": args.rtol,
          "until": args.until, "timeout_s": args.timeout, "started": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())})

    pin: list[dict] = []
    pin_note = None
    if args.no_pinocchio:
        pin_note = "skipped (--no-pinocchio)"
    else:
        probe = subprocess.run([args.pinocchio_python, "-c", "import pinocchio, numpy"], capture_output=True, text=True)
        has_scipy = subprocess.run([args.pinocchio_python, "-c", "import scipy"], capture_output=True).returncode == 0
        if probe.returncode != 0:
            pin_note = f"not installed for {args.pinocchio_python} (pass --pinocchio-python); only lagrange's rows are measured"
            emit({"record": "anchor_error", "source": "pinocchio_rhs", "error": probe.stderr[-500:]})
            log(pin_note)
        else:
            argv = [args.pinocchio_python, str(args.anchors / "pinocchio_rhs.py"), "--sizes", ",".join(map(str, ns)),
                    "--robots", robots, "--repeats", str(repeats_pin), "--t-end", str(args.until),
                    "--rtol", str(args.rtol), "--integrate-repeats", str(1 if quick else 3),
                    "--run-timeout", str(args.timeout), "--lagrange", args.binary]
            if quick:
                argv += ["--calls", "5000"]
            if not has_scipy:
                argv.append("--no-integrate")
                pin_note = f"SciPy not installed for {args.pinocchio_python}: no Pinocchio+SciPy integration"
                log(pin_note)
            pin = run_lines(argv, "pinocchio_rhs", timeout=args.timeout * (len(ns) + 4) * 4)
            if not pin:
                pin_note = "the anchor printed nothing (see anchor_error)"

    argv = [sys.executable, str(args.anchors / "lagrange_scale.py"), "--lagrange", args.binary,
            "--particle-sizes", ",".join(map(str, ns)), "--body-sizes", ",".join(map(str, body_sizes)),
            "--simulate-sizes", ",".join(map(str, ns)), "--methods", "dop853", "--until", str(args.until),
            "--rtol", str(args.rtol), "--atol", str(args.rtol), "--timeout", str(args.timeout),
            "--repeats", str(repeats_lag)]
    lag = run_lines(argv, "lagrange_scale", timeout=args.timeout * (3 * len(ns) + len(body_sizes)) * (repeats_lag + 1))

    robot_records = []
    with tempfile.TemporaryDirectory(prefix="lagrange-scale-robots-") as folder:
        for m in pin:
            source = str(m.get("source") or "")
            if m.get("record") != "model" or not source.endswith(".urdf"):
                continue
            log(f"lagrange import + simulate {m['system']}")
            r = robot_lagrange(args.binary, m["system"], source, m["nq"] != m["nv"], args, folder)
            emit(r)
            robot_records.append(r)

    for n in ns:
        a = next((r for r in pin if r.get("record") == "rhs" and r.get("system") == f"nlink{n}" and r.get("algo") == "aba"), None)
        i = next((r for r in pin if r.get("record") == "integrate" and r.get("system") == f"nlink{n}" and "wall_s" in r), None)
        s = next((r for r in lag if r.get("record") == "simulate" and r.get("n") == n and r.get("us_per_rhs")), None)
        us = s and s.get("us_per_rhs_integrate_only_est")
        emit({"record": "ratio", "system": f"nlink{n}", "n": n,
              "rhs_lagrange_over_aba": ratio(us, a and a["us_per_call"]),
              "whole_lagrange_over_scipy": ratio(s and s["process_wall_s"], i and i["wall_s"])})

    print()
    print("\n".join(table(pin, lag, robot_records, ns, pin_note)))
    stats = [r for r in pin if r.get("record") == "check"]
    for c in stats:
        if "max_abs_diff" in c:
            print(f"\nAccelerations, lagrange vs Pinocchio at n = {c['n']}: max abs diff {c['max_abs_diff']:.1e}")


if __name__ == "__main__":
    main()
