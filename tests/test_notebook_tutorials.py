"""The notebook tutorials of docs/notebooks/ run (issue 33): each is executed top to bottom in
a fresh Jupyter kernel (nbclient; ``pytest --nbmake docs/notebooks`` runs them the same way),
with no error; a result shows as its summary table (``_repr_html_``, hydroarm.display), the
sweep shows its progress bar (tqdm.auto, hydroarm.io.progress), each draws a figure. The
notebooks are kept in git without outputs."""

import json
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")
pytest.importorskip("ipykernel")
pytest.importorskip("tqdm")
pytest.importorskip("xarray")

NOTEBOOKS = Path(__file__).resolve().parents[1] / "docs" / "notebooks"
# each notebook and the results it shows as tables
RESULTS = {
    "reproduce_paper.ipynb": ("SimulationResult",),
    "own_servo.ipynb": ("ServoResult", "FitResult"),
    "design_tolerance.ipynb": ("SensitivityResult",),
}
NAMES = tuple(RESULTS)
CELL_TIMEOUT_S = 600  # a cold numba cache compiles the kernels in the first cells


def test_the_three_tutorials_are_there_without_outputs():
    assert sorted(p.name for p in NOTEBOOKS.glob("*.ipynb")) == sorted(NAMES)
    for name in NAMES:
        nb = json.loads((NOTEBOOKS / name).read_text())
        code = [c for c in nb["cells"] if c["cell_type"] == "code"]
        assert code and all(not c["outputs"] and c["execution_count"] is None for c in code), name


def _run(name):
    nb = nbformat.read(NOTEBOOKS / name, as_version=4)
    client = nbclient.NotebookClient(
        nb,
        timeout=CELL_TIMEOUT_S,
        kernel_name="python3",
        resources={"metadata": {"path": str(NOTEBOOKS)}},
    )
    client.execute()  # a cell's error raises CellExecutionError, with the cell and traceback
    return [o for c in nb.cells if c.cell_type == "code" for o in c.outputs]


def _html_tables(outputs) -> list[str]:
    return [
        o["data"]["text/html"]
        for o in outputs
        if o.get("output_type") in ("execute_result", "display_data")
        and "<table" in o.get("data", {}).get("text/html", "")
    ]


@pytest.mark.slow  # 10 to 20 s each on a loaded 2-core machine, most of it the kernel's start
@pytest.mark.parametrize("name", NAMES)
def test_notebook_runs(name, monkeypatch):
    # the kernel inherits this process's environment: no Agg from an earlier hydroarm main()
    # (the CLI sets MPLBACKEND), so that figures show inline as in Jupyter
    monkeypatch.delenv("MPLBACKEND", raising=False)
    outputs = _run(name)
    assert not [o for o in outputs if o.get("output_type") == "error"]
    tables = _html_tables(outputs)
    for result in RESULTS[name]:
        assert any(f"<strong>{result}</strong>" in t for t in tables), result
    assert any("image/png" in o.get("data", {}) for o in outputs), "a figure"
    if name == "reproduce_paper.ipynb":
        assert any("table_III_mm_s" in t for t in tables)
    if name == "design_tolerance.ipynb":
        # run_sweep's own bar (no progress= given): tqdm.auto, a widget where ipywidgets is
        # installed, else its text bar on stderr
        widget = any(
            "application/vnd.jupyter.widget-view+json" in o.get("data", {}) for o in outputs
        )
        text = "".join(o.get("text", "") for o in outputs if o.get("name") == "stderr")
        assert widget or "sweep: 100%" in text, text[-500:]
        assert any("xarray.Dataset" in str(o.get("data", {})) for o in outputs)
