"""The examples in examples/python run end to end: the two scripts, and the notebook,
executed cell by cell in a fresh kernel (its last cell checks that both loops closed)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "python"

pytest.importorskip("matplotlib")


@pytest.mark.parametrize(
    ("script", "outputs"),
    [
        ("loop.py", ["dc-motor-fixed.toml", "omega.png", "ranking.png", "report/report.html"]),
        ("cloth_loop.py", ["markers.csv", "corner-fixed.toml", "cloth-error.png"]),
    ],
)
def test_example_script_runs(script: str, outputs: list[str], tmp_path: Path):
    done = subprocess.run(
        [sys.executable, str(EXAMPLES / script), str(tmp_path)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    for name in outputs:
        assert (tmp_path / name).exists(), f"{script} did not write {name}:\n{done.stdout}"


@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # jupyter's own path migration notes
def test_notebook_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    # Jupyter's runtime files (connection files) in a scratch folder, not the user's home.
    monkeypatch.setenv("JUPYTER_RUNTIME_DIR", str(tmp_path / "runtime"))
    monkeypatch.setenv("JUPYTER_PLATFORM_DIRS", "1")
    monkeypatch.setenv("MPLBACKEND", "Agg")
    nb = nbformat.read(EXAMPLES / "loop.ipynb", as_version=4)
    client = nbclient.NotebookClient(
        nb,
        timeout=600,
        kernel_name="python3",
        resources={"metadata": {"path": str(EXAMPLES)}},
    )
    client.execute()
    text = "".join(
        out.get("text", "")
        for cell in nb.cells
        if cell.cell_type == "code"
        for out in cell.get("outputs", [])
    )
    assert "both loops closed" in text
    images = sum(
        "image/png" in out.get("data", {})
        for cell in nb.cells
        if cell.cell_type == "code"
        for out in cell.get("outputs", [])
    )
    assert images == 2
