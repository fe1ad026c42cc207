"""The notebooks are committed with their outputs, executed top to bottom and clean: small, every
code cell run in order, no errors, no stderr, no warnings, no progress-bar debris. A fresh copy
executes, top to bottom, on the reduced settings CI uses (``RLD_NOTEBOOK_QUICK=1``)."""

from __future__ import annotations

from pathlib import Path

import nbformat
import pytest

from rld.tracks import find_dataset_dir

NOTEBOOKS = Path(__file__).resolve().parents[1] / "notebooks"
NAMES = ["quickstart", "solver_comparison"]
#: Largest committed notebook, bytes (outputs included: keep figures small).
MAX_BYTES = 800_000


def _code_cells(nb) -> list:
    return [c for c in nb.cells if c.cell_type == "code"]


def _output_texts(output) -> list[str]:
    """Every text an output carries: a stream's text, a result's or display's text data."""
    if output.output_type == "stream":
        return [output.get("text", "")]
    if output.output_type == "error":
        return [output.get("ename", ""), output.get("evalue", ""), *output.get("traceback", [])]
    data = output.get("data", {})
    return [v for k, v in data.items() if k.startswith("text/") and isinstance(v, str)]


@pytest.mark.parametrize("name", NAMES)
def test_committed_notebook_is_executed_and_clean(name):
    path = NOTEBOOKS / f"{name}.ipynb"
    size = path.stat().st_size
    assert size < MAX_BYTES, f"{name}.ipynb is {size / 1000:.0f} kB; shrink its figures"
    nb = nbformat.read(path, as_version=4)
    nbformat.validate(nb)
    code = _code_cells(nb)
    counts = [c.get("execution_count") for c in code]
    assert counts == list(range(1, len(code) + 1)), (
        f"{name}.ipynb: execution counts {counts}; run every cell once, top to bottom, in a "
        "fresh kernel and save with the outputs")
    problems = []
    for i, cell in enumerate(code):
        for out in cell.get("outputs", []):
            where = f"code cell {i + 1}"
            if out.output_type == "error":
                problems.append(f"{where}: error {out.get('ename')}: {out.get('evalue')}")
            if out.output_type == "stream" and out.get("name") == "stderr":
                problems.append(f"{where}: stderr output {out.get('text', '')[:120]!r}")
            for text in _output_texts(out):
                if "Warning" in text:
                    problems.append(f"{where}: a warning in the output {text[:120]!r}")
                if "\r" in text:
                    problems.append(f"{where}: a carriage return (progress-bar debris)")
    assert not problems, f"{name}.ipynb:\n" + "\n".join(problems)
    if name == "solver_comparison":  # the saved outputs say which settings produced them
        text = "".join(t for c in code for o in c.get("outputs", []) for t in _output_texts(o))
        assert "quick settings" in text or "full settings" in text


@pytest.mark.parametrize("name", NAMES)
def test_notebook_executes(name, monkeypatch):
    from nbclient import NotebookClient

    monkeypatch.setenv("RLD_NOTEBOOK_QUICK", "1")
    monkeypatch.setenv("MPLBACKEND", "Agg")
    folder = find_dataset_dir()
    if folder is not None:
        monkeypatch.setenv("RLD_DATASET_DIR", str(folder))
    nb = nbformat.read(NOTEBOOKS / f"{name}.ipynb", as_version=4)
    for cell in _code_cells(nb):  # a fresh copy: the committed outputs do not count
        cell.outputs, cell.execution_count = [], None
    NotebookClient(nb, timeout=600, kernel_name="python3",
                   resources={"metadata": {"path": str(NOTEBOOKS)}}).execute()
    errors = [o for c in _code_cells(nb) for o in c.outputs if o.output_type == "error"]
    assert not errors
    if name == "solver_comparison":  # the kernel saw the reduced settings
        text = "".join(o.get("text", "") for c in _code_cells(nb) for o in c.outputs)
        assert "quick settings" in text
