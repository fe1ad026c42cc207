"""The notebooks execute, top to bottom, on the reduced settings CI uses
(``RLD_NOTEBOOK_QUICK=1``). Committed notebooks carry no outputs."""

from __future__ import annotations

from pathlib import Path

import nbformat
import pytest

from rld.tracks import find_dataset_dir

NOTEBOOKS = Path(__file__).resolve().parents[1] / "notebooks"


@pytest.mark.parametrize("name", ["quickstart", "solver_comparison"])
def test_notebook_executes(name, monkeypatch):
    from nbclient import NotebookClient

    monkeypatch.setenv("RLD_NOTEBOOK_QUICK", "1")
    monkeypatch.setenv("MPLBACKEND", "Agg")
    folder = find_dataset_dir()
    if folder is not None:
        monkeypatch.setenv("RLD_DATASET_DIR", str(folder))
    nb = nbformat.read(NOTEBOOKS / f"{name}.ipynb", as_version=4)
    assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code"), \
        f"{name}.ipynb is committed with outputs; clear them"
    NotebookClient(nb, timeout=600, kernel_name="python3",
                   resources={"metadata": {"path": str(NOTEBOOKS)}}).execute()
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs
              if o.output_type == "error"]
    assert not errors
    if name == "solver_comparison":  # the kernel saw the reduced settings
        text = "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code"
                       for o in c.outputs)
        assert "quick settings" in text
