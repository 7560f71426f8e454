"""Robot logs read as written: leeway.read_log joins per-topic files on the
model's grid as ``leeway estimate --data log.toml`` does, bit for bit."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import leeway

ROOT = Path(__file__).resolve().parents[2]
FERRY = ROOT / "examples" / "models" / "ferry.som"
EPOCH = 1_778_745_600


def _topic(path: Path, t: np.ndarray, columns: dict[str, np.ndarray]) -> None:
    ns = np.round(t * 1e9).astype(np.int64)
    frame = pd.DataFrame({"secs": EPOCH + ns // 1_000_000_000, "nsecs": ns % 1_000_000_000, **columns})
    frame.to_csv(path, index=False)


def _log(folder: Path) -> Path:
    """A ferry log: velocities at 8 Hz with a 4 s hole, heading at 20 Hz,
    forces at 10 Hz, from an Euler simulation of the nominal model."""
    rng = np.random.default_rng(3)
    h, n = 0.01, 40_000
    levels = rng.uniform(-1, 1, size=(n // 500 + 1, 3)) * [3000.0, 2500.0, 1500.0]
    tau = np.repeat(levels, 500, axis=0)[:n]
    x = np.zeros((n, 4))
    x[0] = [0.5, 0.0, 0.0, 0.3]
    for k in range(n - 1):
        u, v, r, _ = x[k]
        f = tau[k]
        x[k + 1] = x[k] + h * np.array([
            -0.05 * u - 0.05 * u * abs(u) + 0.4 * v * r + 6.7e-5 * f[0],
            -0.15 * v - 0.3 * v * abs(v) - 0.5 * u * r + 6e-5 * f[1],
            -0.3 * r - 0.6 * r * abs(r) + 0.02 * u * v + 2e-5 * f[2],
            r,
        ])
    t = np.arange(n) * h
    at = lambda s: np.searchsorted(t, s - 1e-9)  # noqa: E731
    twist = np.arange(0.0, t[-1], 0.125)
    twist = twist[(twist < 150.0) | (twist > 154.0)]
    k = at(twist)
    _topic(folder / "twist.csv", twist, {"u": x[k, 0], "v": x[k, 1], "r": x[k, 2]})
    heading = np.arange(0.0, t[-1], 0.05)
    _topic(folder / "heading.csv", heading, {"psi": np.angle(np.exp(1j * x[at(heading), 3]))})
    forces = np.arange(0.0, t[-1], 0.1)
    k = at(forces)
    _topic(folder / "tau.csv", forces, {"Fx": tau[k, 0], "Fy": tau[k, 1], "Mz": tau[k, 2]})
    manifest = folder / "ferry.toml"
    sources = "".join(
        f'[sources.{s}]\nfile = "{s}.csv"\ntime = ["secs", "nsecs"]\n' for s in ["twist", "heading", "tau"]
    )
    manifest.write_text(
        'experiment = "ferry"\n' + sources + "[signals]\n"
        'u = "twist:u"\nv = "twist:v"\nr = "twist:r"\npsi = "heading:psi"\n'
        'tau_x = "tau:Fx"\ntau_y = "tau:Fy"\ntau_n = "tau:Mz"\n'
    )
    return manifest


def test_a_log_is_split_at_its_hole_and_estimates_as_the_cli(tmp_path: Path) -> None:
    manifest = _log(tmp_path)
    model = leeway.Model.load(FERRY)
    log = leeway.read_log(model, manifest)
    assert list(log.experiments) == ["ferry/1", "ferry/2"]
    assert log.gaps["signal"].tolist() == ["u, v, r"]
    assert log.gaps["from"][0] < 150.0 < 154.0 < log.gaps["to"][0]
    assert list(log.experiments["ferry/1"].columns) == ["time", "u", "v", "r", "psi", "tau_x", "tau_y", "tau_n"]
    est = leeway.estimate(model, log.experiments, method="iv3")
    cli = os.environ.get("LEEWAY_BIN", "leeway")
    out = subprocess.run(
        [cli, "estimate", str(FERRY), "--data", str(manifest), "--json"], capture_output=True, check=True
    )
    document = json.loads(out.stdout)
    by_cli = {p["name"]: p["value"] for p in document["parameters"]}
    assert dict(est.theta) == by_cli


def test_a_malformed_log_raises_a_located_data_error(tmp_path: Path) -> None:
    manifest = _log(tmp_path)
    manifest.write_text(manifest.read_text().replace('"twist:u"', '"twist:surge"'))
    with pytest.raises(leeway.DataError) as e:
        leeway.read_log(leeway.Model.load(FERRY), manifest)
    assert "no column `surge`" in str(e.value)
    with pytest.raises(leeway.OptionError):
        leeway.read_log(leeway.Model.load(FERRY), manifest, max_gap=-1.0)
