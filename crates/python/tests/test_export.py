"""`lagrange export --to python`: the module needs only numpy, and under
scipy's solve_ivp (vectorized rhs, and Radau with the exported jac) it
reproduces `lagrange simulate`; jac agrees with differences of rhs; p as a
dict changes one parameter as `--set` does and refuses unknown names; inputs
are taken in t or as given (u as a function, dict or sequence) and B is
∂f/∂u; a constrained model moves with its multipliers."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from conftest import EXAMPLES, cli, cli_json


def exported(model: Path, tmp_path: Path, name: str):
    out = tmp_path / f"{name}.py"
    cli("export", model, "--to", "python", "-o", out)
    spec = importlib.util.spec_from_file_location(name, out)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def simulated(model: Path, until: float, *set_: str) -> np.ndarray:
    args = ["simulate", model, "--until", until, "--rtol", "1e-12", "--summary", "json"]
    for s in set_:
        args += ["--set", s]
    final = cli_json(*args)["final"]
    names = cli_json("derive", model, "--format", "json")["coordinates"]
    return np.array([final[c] for c in names] + [final[c + "'"] for c in names])


def test_the_double_pendulum_under_solve_ivp_moves_as_simulate_says(tmp_path):
    dp = exported(EXAMPLES / "double_pendulum.toml", tmp_path, "dp_export")
    assert dp.COORDINATES == ["a", "b"]
    assert dp.PARAMETERS == {"mA": 1.0, "mB": 1.0, "lA": 1.0, "lB": 1.0, "g": 9.81}
    y0 = [2.0, 2.5, 0.0, 0.0]
    sol = solve_ivp(dp.rhs, (0, 2), y0, method="DOP853", rtol=1e-12, atol=1e-12, vectorized=True)
    assert np.allclose(sol.y[:, -1], simulated(EXAMPLES / "double_pendulum.toml", 2), rtol=0, atol=1e-8)
    moon = solve_ivp(dp.rhs, (0, 2), y0, method="DOP853", rtol=1e-12, atol=1e-12, args=({"g": 1.62},))
    assert np.allclose(moon.y[:, -1], simulated(EXAMPLES / "double_pendulum.toml", 2, "g=1.62"), rtol=0, atol=1e-8)
    with pytest.raises(KeyError, match="'gg' is not a parameter"):
        dp.rhs(0, y0, {"gg": 1.0})


def test_radau_with_the_exported_jacobian_needs_no_differences(tmp_path):
    kepler = exported(EXAMPLES / "kepler.toml", tmp_path, "kepler_export")
    y0 = [1.0, 0.0, 0.0, 1.2]
    sol = solve_ivp(kepler.rhs, (0, 5), y0, method="Radau", jac=kepler.jac, rtol=1e-10, atol=1e-12)
    assert sol.status == 0
    assert np.allclose(sol.y[:, -1], simulated(EXAMPLES / "kepler.toml", 5), rtol=0, atol=1e-6)
    # jac against central differences of rhs at a state away from rest.
    dp = exported(EXAMPLES / "double_pendulum.toml", tmp_path, "dp_jac")
    y = np.array([0.3, -1.1, 0.7, 1.9])
    h = 1e-6
    numeric = np.column_stack([(dp.rhs(0, y + h * e) - dp.rhs(0, y - h * e)) / (2 * h) for e in np.eye(4)])
    assert np.allclose(dp.jac(0, y), numeric, rtol=1e-6, atol=1e-6)


def test_the_mass_matrix_and_the_energy_are_the_derivation_s(tmp_path):
    dp = exported(EXAMPLES / "double_pendulum.toml", tmp_path, "dp_m")
    y = np.array([2.0, 2.5, 0.0, 0.0])
    c = np.cos(2.0 - 2.5)
    assert np.allclose(dp.mass_matrix(0, y), [[2.0, c], [c, 1.0]], rtol=1e-14)
    u = -9.81 * (2 * np.cos(2.0) + np.cos(2.5))
    assert dp.hamiltonian(0, y) == pytest.approx(u, rel=1e-14)
    assert dp.energy(0, y) == pytest.approx(u, rel=1e-14)
    # Several states at once: one column each.
    ys = np.column_stack([y, [0.1, 0.2, 0.3, 0.4]])
    assert dp.rhs(0, ys).shape == (4, 2)
    assert np.allclose(dp.rhs(0, ys)[:, 1], dp.rhs(0, ys[:, 1]), rtol=1e-14)


def test_a_model_with_abs_is_refused_for_its_jacobian(tmp_path):
    model = tmp_path / "friction.toml"
    model.write_text('name = "friction"\ncoordinates = ["x"]\nlagrangian = "x\'^2/2 - abs(x)"\n')
    out = tmp_path / "friction.py"
    r = cli("export", model, "--to", "python", "-o", out, check=False)
    assert r.returncode == 2, r.stderr
    assert "abs()" in r.stderr and not out.exists()


def test_the_cart_pendulum_takes_its_inputs_in_t_or_as_given(tmp_path):
    cart = exported(EXAMPLES / "cart_pendulum.toml", tmp_path, "cart_export")
    assert list(cart.INPUTS) == ["F", "tau"]
    y0 = [0.0, 0.2, 0.0, 0.0]
    kw = dict(method="DOP853", rtol=1e-12, atol=1e-12)
    # u=None: the inputs' values in t, as a run takes them.
    sol = solve_ivp(cart.rhs, (0, 3), y0, vectorized=True, **kw)
    assert np.allclose(sol.y[:, -1], simulated(EXAMPLES / "cart_pendulum.toml", 3), rtol=0, atol=1e-8)
    # u as a function of (t, y), as a dict of those to change, and as a sequence.
    want = simulated(EXAMPLES / "cart_pendulum.toml", 3, "F0=3")
    for u in (
        lambda t, y: {"F": 3 * np.sin(2 * t)},
        lambda t, y: [3 * np.sin(2 * t), 0.0],
    ):
        sol = solve_ivp(cart.rhs, (0, 3), y0, args=(None, u), **kw)
        assert np.allclose(sol.y[:, -1], want, rtol=0, atol=1e-8)
    # B = ∂f/∂u: f(u) − f(0) = B u; jac holds u and agrees with differences.
    y = np.array([0.1, 0.7, 0.3, -0.2])
    u = np.array([1.5, -0.25])
    f_u, f_0 = cart.forcing(0.4, y, None, u), cart.forcing(0.4, y, None, [0.0, 0.0])
    assert np.allclose(f_u - f_0, cart.input_matrix(0.4, y) @ u, rtol=1e-13, atol=1e-13)
    h = 1e-6
    numeric = np.column_stack([(cart.rhs(0.4, y + h * e, None, u) - cart.rhs(0.4, y - h * e, None, u)) / (2 * h) for e in np.eye(4)])
    assert np.allclose(cart.jac(0.4, y, None, u), numeric, rtol=1e-6, atol=1e-6)
    with pytest.raises(KeyError, match="'G' is not an input"):
        cart.rhs(0, y0, None, {"G": 1.0})


def test_a_constrained_model_moves_with_its_multipliers(tmp_path):
    model = EXAMPLES / "constraints" / "pendulum_cartesian.toml"
    pend = exported(model, tmp_path, "cartesian_export")
    assert pend.CONSTRAINTS == ["rod"]
    y0 = [np.sin(1), -np.cos(1), 0.5 * np.cos(1), 0.5 * np.sin(1)]
    sol = solve_ivp(pend.rhs, (0, 2), y0, method="DOP853", rtol=1e-12, atol=1e-12, vectorized=True)
    end = sol.y[:, -1]
    assert np.allclose(end, simulated(model, 2), rtol=0, atol=1e-8)
    assert abs(pend.constraint_residuals(2, end)[0]) < 1e-9
    assert abs(pend.constraint_rates(2, end)[0]) < 1e-9
    assert np.allclose(pend.constraint_jacobian(2, end), [2 * end[:2]], rtol=1e-14)
    # λ against the run's lambda_rod at its last row.
    csv = tmp_path / "run.csv"
    cli("simulate", model, "--until", 2, "--rtol", "1e-12", "--out", csv)
    rows = [line for line in csv.read_text().splitlines() if not line.startswith("#")]
    header, last = rows[0].split(","), rows[-1].split(",")
    assert pend.multipliers(2, end)[0] == pytest.approx(float(last[header.index("lambda_rod")]), rel=1e-7)
    # Radau with the exported Jacobian of the saddle-point system.
    stiff = solve_ivp(pend.rhs, (0, 2), y0, method="Radau", jac=pend.jac, rtol=1e-10, atol=1e-12)
    assert np.allclose(stiff.y[:, -1], end, rtol=0, atol=1e-6)
    h = 1e-6
    numeric = np.column_stack([(pend.rhs(0, end + h * e) - pend.rhs(0, end - h * e)) / (2 * h) for e in np.eye(4)])
    assert np.allclose(pend.jac(0, end), numeric, rtol=1e-6, atol=1e-6)


def test_model_export_writes_what_the_cli_writes(tmp_path):
    import lagrange

    cart = lagrange.load(EXAMPLES / "cart_pendulum.toml")
    for to, suffix in (("c", "c"), ("python", "py")):
        mine, theirs = tmp_path / f"mine.{suffix}", tmp_path / f"theirs.{suffix}"
        cart.export(to, mine)
        cli("export", EXAMPLES / "cart_pendulum.toml", "--to", to, "-o", theirs)
        assert mine.read_text() == theirs.read_text()
    module = exported(EXAMPLES / "cart_pendulum.toml", tmp_path, "cart_again")
    assert list(module.INPUTS) == ["F", "tau"]
    with pytest.raises(ValueError, match='the targets are "c", "python" and "fmu"'):
        cart.export("fortran", tmp_path / "cart.f")
    kink = lagrange.load(Path(__file__).resolve().parents[2] / "cli" / "tests" / "bad_export" / "kink_for_jacobian.toml")
    kept = tmp_path / "kept.py"
    kept.write_text("# an earlier export\n")
    with pytest.raises(lagrange.ModelError, match="abs()") as e:
        kink.export("python", kept)
    assert e.value.kind == "unsupported"
    assert kept.read_text() == "# an earlier export\n"


def test_an_export_never_replaces_the_model_it_comes_from(tmp_path):
    import lagrange

    model = tmp_path / "pendulum.toml"
    text = (EXAMPLES / "pendulum.toml").read_text()
    model.write_text(text)
    link = tmp_path / "link.c"
    link.symlink_to(model)
    pendulum = lagrange.load(model)
    for path in (model, tmp_path / "." / "pendulum.toml", link):
        with pytest.raises(ValueError, match="the model's own file"):
            pendulum.export("c", path)
    assert model.read_text() == text
    pendulum.export("c", tmp_path / "pendulum.c")
    assert "lagrange_rhs" in (tmp_path / "pendulum.c").read_text()


def test_a_model_with_impacts_is_refused(tmp_path):
    import lagrange

    ball = lagrange.load(EXAMPLES / "impacts" / "bouncing_ball.toml")
    for to in ("c", "python", "fmu"):
        with pytest.raises(lagrange.ModelError, match="impact 'floor' cannot be exported"):
            ball.export(to, tmp_path / f"ball.{to}")
        assert not (tmp_path / f"ball.{to}").exists()
