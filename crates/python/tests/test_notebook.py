"""The example notebook runs top to bottom (its cells assert the notes' results)."""

from __future__ import annotations

import pytest

from conftest import EXAMPLES

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")


def test_notes_tour_runs():
    nb = nbformat.read(EXAMPLES / "notes_tour.ipynb", as_version=4)
    client = nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                                     resources={"metadata": {"path": str(EXAMPLES)}})
    client.execute()
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])]
    assert not [o for o in outputs if o.get("output_type") == "error"]
    # The derivation displayed as LaTeX, the run as its SVG plot.
    kinds = {k for o in outputs for k in o.get("data", {})}
    assert "text/latex" in kinds and "image/svg+xml" in kinds
