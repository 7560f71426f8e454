"""The notebook-style example (examples/python/) runs end to end as a plain
script, so it cannot rot: every cell executes against the built package, and
the script's own assertion holds (the estimate fits the held-out zigzag)."""

from __future__ import annotations

import subprocess
import sys

from conftest import ROOT

EXAMPLE = ROOT / "examples" / "python" / "ship_walkthrough.py"


def test_the_example_runs_as_a_script() -> None:
    o = subprocess.run(
        [sys.executable, str(EXAMPLE)], capture_output=True, text=True, cwd=ROOT, timeout=300, check=False
    )
    assert o.returncode == 0, o.stdout[-3000:] + o.stderr[-3000:]
    assert "identifiable: True" in o.stdout
    assert "fit in %" in o.stdout


def test_the_example_keeps_its_cells_and_the_dask_section() -> None:
    text = EXAMPLE.read_text()
    cells = [line for line in text.splitlines() if line.startswith("# %%")]
    assert len(cells) >= 8, cells
    # The section of the distributed estimate (`leeway.dask`).
    assert "# %% Past one machine: Dask" in cells
