"""`lagrange export --to fmu` checked by a real FMI client, FMPy: the FMU
passes `fmpy.validation.validate_fmu`, and `fmpy.simulate_fmu` in Model
Exchange (FMPy's CVode) and in Co-Simulation (the FMU's own integrator) moves
as `lagrange simulate` does: the double pendulum (its states started through
FMPy's start values, g set through them as `--set g=` does), the heavy top,
and the cart pendulum with its input F left to its expression in t or driven
from FMPy."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

from conftest import EXAMPLES, cli, cli_binary

fmpy = pytest.importorskip("fmpy")
from fmpy import read_model_description, simulate_fmu  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

UNTIL = 10.0
STEP = 0.01
# Model Exchange: FMPy's CVode at this tolerance; Co-Simulation: the FMU's own
# Dormand–Prince at this one (its parameter solver.tolerance).
MODES = [
    ("ModelExchange", dict(relative_tolerance=1e-11), {}),
    ("CoSimulation", {}, {"solver.tolerance": 1e-12}),
]


def exported(model: Path, tmp_path: Path, name: str) -> Path:
    out = tmp_path / f"{name}.fmu"
    cli("export", model, "--to", "fmu", "-o", out)
    assert validate_fmu(str(out)) == []
    return out


def reference(model: Path, tmp_path: Path, *set_: str) -> np.ndarray:
    """`lagrange simulate` sampled every STEP up to UNTIL, at a tight tolerance."""
    csv = tmp_path / "reference.csv"
    args = ["simulate", model, "--until", UNTIL, "--rtol", "1e-12", "--samples", int(round(UNTIL / STEP)) + 1, "--out", csv]
    for s in set_:
        args += ["--set", s]
    cli(*args)
    return np.genfromtxt(csv, delimiter=",", names=True, deletechars="")


def agree(result, ref, names, tol):
    for name in names:
        want = np.interp(result["time"], ref["t"], ref[name])
        assert np.max(np.abs(result[name] - want)) < tol, name


def with_initial(model: Path, tmp_path: Path, initial: dict) -> Path:
    """A copy of `model` whose [initial] section is `initial`."""
    text = model.read_text().split("[initial]")[0]
    lines = "".join(f'"{k}" = {v!r}\n' for k, v in initial.items())
    copy = tmp_path / model.name
    copy.write_text(f"{text}[initial]\n{lines}")
    return copy


def test_the_double_pendulum_moves_as_simulate_says_in_both_modes(tmp_path):
    fmu = exported(EXAMPLES / "double_pendulum.toml", tmp_path, "double_pendulum")
    names = {v.name for v in read_model_description(str(fmu)).modelVariables}
    assert {"a", "b", "a'", "b'", "der(a)", "der(b')", "g", "h", "E", "solver.tolerance"} <= names
    # A start of regular motion (the file's start is chaotic), set through FMPy.
    start = {"a": 0.4, "b": 0.2, "a'": 0.0, "b'": 0.3}
    model = with_initial(EXAMPLES / "double_pendulum.toml", tmp_path, start)
    for set_ in ([], ["g=1.62"]):
        ref = reference(model, tmp_path, *set_)
        values = {**start, **{k: float(v) for k, v in (s.split("=") for s in set_)}}
        for mode, options, extra in MODES:
            result = simulate_fmu(
                str(fmu), fmi_type=mode, stop_time=UNTIL, output_interval=STEP,
                output=["a", "b", "h", "E"], start_values={**values, **extra}, **options,
            )
            agree(result, ref, ["a", "b"], 1e-5)
            assert np.max(np.abs(result["h"] - ref["H"])) < 1e-5
            assert np.allclose(result["h"], result["E"], rtol=0, atol=1e-12)


def test_the_heavy_top_moves_as_simulate_says_in_both_modes(tmp_path):
    model = EXAMPLES / "tops" / "heavy_top.toml"
    fmu = exported(model, tmp_path, "heavy_top")
    ref = reference(model, tmp_path)
    for mode, options, extra in MODES:
        result = simulate_fmu(
            str(fmu), fmi_type=mode, stop_time=UNTIL, output_interval=STEP,
            output=["al", "be", "ga"], start_values=extra, **options,
        )
        agree(result, ref, ["al", "be", "ga"], 1e-5)


def test_the_cart_pendulum_takes_its_input_in_t_or_from_fmpy(tmp_path):
    model = EXAMPLES / "cart_pendulum.toml"
    fmu = exported(model, tmp_path, "cart_pendulum")
    variables = {v.name: v for v in read_model_description(str(fmu)).modelVariables}
    assert variables["F"].causality == "input"
    # Not connected: F takes its expression in t, F0 sin 2t, as the run does.
    ref = reference(model, tmp_path)
    for mode, options, extra in MODES:
        result = simulate_fmu(
            str(fmu), fmi_type=mode, stop_time=UNTIL, output_interval=STEP,
            output=["x", "th", "F"], start_values=extra, **options,
        )
        agree(result, ref, ["x", "th"], 1e-5)
    # Driven from FMPy: a constant F = 1.5, against a run whose F is F0 = 1.5.
    constant = model.read_text().replace('F = "F0*sin(2*t)"', 'F = "F0"')
    assert constant != model.read_text()
    (tmp_path / "cart_constant.toml").write_text(constant)
    ref = reference(tmp_path / "cart_constant.toml", tmp_path, "F0=1.5")
    signal = np.array([(0.0, 1.5, 0.0), (UNTIL, 1.5, 0.0)], dtype=[("time", float), ("F", float), ("tau", float)])
    for mode, options, extra in MODES:
        result = simulate_fmu(
            str(fmu), fmi_type=mode, stop_time=UNTIL, output_interval=STEP,
            output=["x", "th", "F"], start_values=extra, input=signal, **options,
        )
        assert np.allclose(result["F"], 1.5, rtol=0, atol=1e-12)
        agree(result, ref, ["x", "th"], 1e-5)


def test_a_failed_fmu_export_keeps_an_existing_file(tmp_path):
    out = tmp_path / "kept.fmu"
    out.write_bytes(b"an earlier export")
    r = subprocess.run(
        [str(cli_binary()), "export", str(EXAMPLES / "double_pendulum.toml"), "--to", "fmu", "-o", str(out)],
        capture_output=True, text=True, env={**os.environ, "LAGRANGE_CC": "/nonexistent/cc"},
    )
    assert r.returncode == 2, r.stderr
    assert "needs a C compiler" in r.stderr
    assert out.read_bytes() == b"an earlier export"


def test_model_export_writes_an_fmu_fmpy_runs(tmp_path):
    import lagrange

    out = tmp_path / "kepler.fmu"
    lagrange.load(EXAMPLES / "kepler.toml").export("fmu", out)
    assert validate_fmu(str(out)) == []
    ref = reference(EXAMPLES / "kepler.toml", tmp_path)
    names = lagrange.load(EXAMPLES / "kepler.toml").coordinates
    for mode, options, extra in MODES:
        result = simulate_fmu(
            str(out), fmi_type=mode, stop_time=UNTIL, output_interval=STEP,
            output=names, start_values=extra, **options,
        )
        agree(result, ref, names, 1e-5)
