#!/usr/bin/env python3
"""Every benchmark of `lagrange` against its anchors, in one run: `derive.py` (deriving
the N-link pendulum and the spring chain, against SymPy and SymEngine), `simulate.py`
(model file to first step, one right-hand side, whole runs against SciPy's DOP853 and
heyoka, and the chaos map), `default_method.py` (the default method against every other
on six systems, the long horizon, and its robustness), `sweep_memory.py` (peak memory
of sweeps of 10^4 and 10^6 runs against the 100 MB target), `ensemble.py` (the chaos
map against heyoka's ensemble on one and two threads, the compile cold and warm) and
`python_api.py` (the
Python package against SymPy + SciPy: the whole call and `model.rhs()` in solve_ivp), one
after the other on the same machine, each printing its tables and writing its JSON lines.

    python3 bench/all.py            # derive.py's default sizes, then simulate.py,
                                    # default_method.py, sweep_memory.py, python_api.py
    python3 bench/all.py --quick    # a few minutes: small derive sizes, simulate without
                                    # the chaos map and with 3 repeats, default_method.py
                                    # --quick, sweeps up to 9*10^4 runs, python_api.py
                                    # --quick

Further options go to every script unchanged only where it knows them (`--no-install`,
`--no-build` to all; `--binary` to all but python_api.py, which measures the installed
package); each script has its own `--help`. Standard library only. Exits with the first
non-zero exit code of the six (all always run).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true",
                        help="small derive sizes; simulate with 3 repeats and no chaos map; default_method --quick; "
                             "sweeps up to 9*10^4 runs; python_api --quick")
    parser.add_argument("--no-install", action="store_true", help="never create or fill the anchors' venv")
    parser.add_argument("--no-build", action="store_true", help="never run cargo")
    parser.add_argument("--binary", default=None, help="the lagrange binary (default target/release/lagrange)")
    args = parser.parse_args(argv)

    shared = [flag for flag, on in (("--no-install", args.no_install), ("--no-build", args.no_build)) if on]
    if args.binary:
        shared += ["--binary", args.binary]
    derive = [sys.executable, str(HERE / "derive.py"), *shared] + (["--quick"] if args.quick else [])
    simulate = [sys.executable, str(HERE / "simulate.py"), *shared] + (
        ["--repeats", "3", "--ensemble-grid", "0"] if args.quick else ["--repeats", "7"])
    default = [sys.executable, str(HERE / "default_method.py"), *shared] + (["--quick"] if args.quick else [])
    memory = [sys.executable, str(HERE / "sweep_memory.py"), *shared] + (["--sides", "100,300"] if args.quick else [])
    ensemble = [sys.executable, str(HERE / "ensemble.py"), *shared] + (
        ["--grid", "60", "--small", "40", "--repeats", "1"] if args.quick else [])
    python_flags = [flag for flag in shared if flag in ("--no-install", "--no-build")]
    python_api = [sys.executable, str(HERE / "python_api.py"), *python_flags, "--report"] + (["--quick"] if args.quick else [])
    status = 0
    for command in (derive, simulate, default, memory, ensemble, python_api):
        print(f"[all.py] {' '.join(command[1:])}", file=sys.stderr, flush=True)
        code = subprocess.run(command).returncode
        status = status or code
    return status


if __name__ == "__main__":
    sys.exit(main())
