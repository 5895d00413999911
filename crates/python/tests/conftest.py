"""Shared fixtures: the repository's example models and the CLI binary the
Python results are compared with (``LAGRANGE_BIN``, default target/debug)."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path
from typing import Any, List

import pytest

ROOT = Path(__file__).resolve().parents[3]
EXAMPLES = ROOT / "examples"


def models() -> List[Path]:
    """Every example model file (not body or problem files)."""
    found = sorted(EXAMPLES.glob("*.toml")) + sorted((EXAMPLES / "constraints").glob("*.toml"))
    found += sorted((EXAMPLES / "tops").glob("*.toml"))
    # Body files beside the models they belong to are not models.
    return [p for p in found if "coordinates" in p.read_text()]


def cli_binary() -> Path:
    path = Path(os.environ.get("LAGRANGE_BIN", ROOT / "target" / "debug" / "lagrange"))
    if not path.exists():
        pytest.skip(f"the CLI binary {path} is not built (cargo build -p lagrange-cli)")
    return path


def cli(*args: Any, check: bool = True) -> subprocess.CompletedProcess:
    """Runs the CLI; returns the completed process (stdout as text)."""
    return subprocess.run([str(cli_binary()), *map(str, args)], capture_output=True, text=True, check=check)


def cli_json(*args: Any) -> Any:
    return json.loads(cli(*args).stdout)
