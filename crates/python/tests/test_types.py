"""The package's annotations and stubs, checked by mypy --strict: the package
itself, and a user's script, whose arrays and expressions mypy must see as
arrays and expressions rather than Any."""

from __future__ import annotations

import subprocess
import sys
import pytest

pytest.importorskip("mypy")

USER = '''
import numpy as np
import lagrange

model = lagrange.load("model.toml")
run = model.simulate(until=1.0)
f = model.rhs()
reveal_type(run.t)
reveal_type(f(0.0, np.zeros(2)))
reveal_type(model.jac()(0.0, np.zeros(2)))
h = model.derive().hamiltonian
assert h is not None
reveal_type(h(ph=0.0))
reveal_type(model.derive().conserved_quantities)
reveal_type(lagrange.grid(0.0, 1.0, 3))
reveal_type(model.linearize())
'''


def mypy(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mypy", "--strict", "--no-incremental", *args],
                          capture_output=True, text=True)


def test_the_package_passes_mypy_strict():
    r = mypy("-p", "lagrange")
    assert r.returncode == 0, r.stdout + r.stderr


def test_a_user_s_script_sees_arrays_and_expressions(tmp_path):
    script = tmp_path / "user.py"
    script.write_text(USER)
    r = mypy(str(script))
    revealed = [line.split("Revealed type is ", 1)[1] for line in r.stdout.splitlines() if "Revealed type is" in line]
    assert r.returncode == 0 and len(revealed) == 7, r.stdout
    assert all(t != '"Any"' for t in revealed), revealed
    assert "ndarray" in revealed[0] and "ndarray" in revealed[1] and "ndarray" in revealed[2]
    assert "float" in revealed[3] and "ndarray" in revealed[3]
    assert "lagrange.expr.Expr]" in revealed[4] and revealed[4].lower().startswith('"dict[')
    assert "Linspace" in revealed[5] and "Report" in revealed[6]
