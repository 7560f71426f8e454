"""Shared fixtures: the repository's models, the `leeway` binary, and ship
data simulated by `leeway simulate` (so the Python package and the CLI see
the same experiments)."""

from __future__ import annotations

import io
import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[2]
SHIP = ROOT / "examples" / "models" / "ship.som"
SHIP_IV2 = ROOT / "examples" / "models" / "ship_iv2.som"

# θ0 of the paper's table (scenarios/src/study.rs THETA0), the simulated truth.
TRUE = dict(zip(
    "X_u X_vr X_uu W_uu X_tau Y_v Y_ur Y_vv Y_vr W_vv Y_tau N_r N_uv N_vv N_vr W_uv N_tau".split(),
    [-0.05, 1.0, -0.05, -0.0005, 0.02, -0.2, -0.65, -0.2, -0.1, -0.0015, 0.02, -0.1, -0.0015,
     -0.001, -0.04, -0.00003, 0.0003],
))


def leeway_binary() -> Path:
    path = Path(os.environ.get("LEEWAY_BIN", ROOT / "target" / "debug" / "leeway"))
    if not path.exists():
        pytest.fail(f"the `leeway` binary is not at {path}: run `cargo build -p leeway-cli` or set LEEWAY_BIN")
    return path


def run_leeway(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(leeway_binary()), *args], capture_output=True, text=True, cwd=ROOT, check=False
    )


def ship_data(tmp: Path, n: int, wind: float, seed: int, name: str = "run") -> pd.DataFrame:
    """A steady turn of the ship in a current of (0.2, 0.2) m/s and a wind of
    `wind` m/s, simulated by the CLI, with measurement noise added here."""
    rng = np.random.default_rng(seed)
    k = np.arange(n)
    # The paper's offset input with a slow excitation on top.
    inputs = pd.DataFrame({
        "time": k * 1.0,
        "tau1": 50 + 10 * np.sin(k / 37.0) + rng.normal(0, 5, n),
        "tau2": 169 + 30 * np.sin(k / 23.0) + rng.normal(0, 10, n),
        "tau3": 235 + 40 * np.sin(k / 29.0) + rng.normal(0, 10, n),
        "wind_n": wind + rng.normal(0, 0.03, n),
        "wind_e": wind + rng.normal(0, 0.03, n),
    })
    (tmp / "truth.json").write_text(json.dumps(TRUE))
    inputs.to_csv(tmp / "input.csv", index=False)
    o = run_leeway(
        "simulate", str(SHIP), "--params", str(tmp / "truth.json"), "--input", str(tmp / "input.csv"),
        "--x0", "u=5,v=3.3,r=0.15,psi=0", "--disturbance", "current.north=0.2,current.east=0.2",
    )
    assert o.returncode == 0, o.stderr
    frame = pd.read_csv(io.StringIO(o.stdout))
    for c, sd in [("u", 0.014), ("v", 0.014), ("r", 0.014), ("psi", 0.01)]:
        frame[c] = frame[c] + rng.normal(0, sd, n)
    return frame


@pytest.fixture(scope="session", autouse=True)
def leeway_temporary_files(tmp_path_factory: pytest.TempPathFactory):  # type: ignore[no-untyped-def]
    """leeway's spill files go under pytest's temporary directory, which
    pytest prunes, and not the system's: a Dask worker the fault tests kill
    cannot remove its own."""
    before = os.environ.get("TMPDIR")
    os.environ["TMPDIR"] = str(tmp_path_factory.mktemp("leeway-tmp"))
    yield
    if before is None:
        os.environ.pop("TMPDIR", None)
    else:
        os.environ["TMPDIR"] = before


@pytest.fixture(scope="session")
def ship_frame(tmp_path_factory: pytest.TempPathFactory) -> pd.DataFrame:
    return ship_data(tmp_path_factory.mktemp("ship"), 1500, 1.0, 7)


def ticks_during(work) -> tuple[int, float]:  # type: ignore[no-untyped-def]
    """Runs `work()` while another thread ticks every millisecond: how often
    it ticked, and how long `work` took. A thread that could not run while
    Rust held the GIL would tick only before and after."""
    import threading
    import time

    ticks = 0
    done = threading.Event()

    def tick() -> None:
        nonlocal ticks
        while not done.is_set():
            ticks += 1
            time.sleep(0.001)

    t = threading.Thread(target=tick)
    t.start()
    start = time.perf_counter()
    try:
        work()
    finally:
        elapsed = time.perf_counter() - start
        done.set()
        t.join()
    return ticks, elapsed
