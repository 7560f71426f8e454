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


def test_fast_signals_are_read_by_their_means_and_windows_keep_their_stretches(tmp_path: Path) -> None:
    manifest = _log(tmp_path)
    manifest.write_text(manifest.read_text() + "[[keep]]\nfrom = 10\nto = 100\n[[keep]]\nfrom = 200\n")
    model = leeway.Model.load(FERRY)
    log = leeway.read_log(model, manifest)
    assert list(log.experiments) == ["ferry/1", "ferry/2"]
    spans = log.pieces[["from", "to"]].values.tolist()
    assert spans[0] == [10.0, 100.0]
    assert spans[1][0] == 200.0 and 399.0 < spans[1][1] < 400.0
    # The 4 s hole lies outside the windows: no gap splits them.
    assert log.gaps.empty
    on_grid = dict(zip(log.signals["signal"], log.signals["on_grid"]))
    # The heading at 20 Hz on a 0.1 s grid: its centred mean; the forces at
    # the grid's rate: held at the grid time.
    assert on_grid["psi"].startswith("centred mean over the step of")
    assert on_grid["tau_x"] == "held at the grid time"
    assert log.stalls.empty


RAW_FERRY = """model RawFerry {
    step 1.0
    state u, v, r
    input tau_x, tau_y, tau_n
    heading psi integrates r
    delay tau_x 1.0 s
    delay tau_y 1.0 s
    delay tau_n 1.0 s
    der u = X_u*u + X_uu*u*|u| + X_vr*v*r + X_t*tau_x
    der v = Y_v*v + Y_vv*v*|v| + Y_ur*u*r + Y_t*tau_y
    der r = N_r*r + N_rr*r*|r| + N_uv*u*v + N_t*tau_n
    nominal { X_u = -0.02, X_uu = -0.02, X_vr = 0.2, X_t = 2e-5,
              Y_v = -0.05, Y_vv = -0.1, Y_ur = -0.3, Y_t = 2e-5,
              N_r = -0.1, N_rr = -0.3, N_uv = 0.005, N_t = 6e-6 }
}
"""


def _raw_topics(folder: Path, seconds: float = 600.0, dp: tuple[float, float] = (250.0, 340.0)) -> None:
    """Raw topics: forces at 50 Hz (held levels, a 3.7 Hz ripple, noise from
    cycle to cycle), velocities at 5 Hz with noise, the heading as an ENU
    quaternion at 5 Hz, a DP mode flag at 1 Hz."""
    rng = np.random.default_rng(7)
    jitter = lambda rate: np.cumsum(1.0 / rate * (1 + 0.2 * rng.uniform(-1, 1, int(seconds * rate * 1.3))))  # noqa: E731
    publish = np.concatenate([[0.0], jitter(50.0)])
    publish = publish[publish <= seconds]
    span = np.array([3000.0, 2500.0, 1500.0])
    changes = np.arange(0.0, seconds + 30.0, 20.0)
    levels = rng.uniform(-1, 1, (len(changes), 3)) * span
    base = levels[np.searchsorted(changes, publish, side="right") - 1]
    ripple = 0.3 * np.sin(2 * np.pi * 3.7 * publish[:, None] + np.arange(3))
    forces = base + span * (ripple + 0.25 * rng.standard_normal((len(publish), 3)))
    h = 0.01
    n = int(seconds / h) + 1
    x = np.zeros((n, 4))
    x[0] = [1.0, 0.0, 0.0, 0.5]
    acting = np.searchsorted(publish, np.arange(n) * h - 1.0 + 1e-9, side="right") - 1
    for k in range(n - 1):
        u, v, r, _ = x[k]
        f = forces[acting[k]] if acting[k] >= 0 else np.zeros(3)
        x[k + 1] = x[k] + h * np.array([
            -0.02 * u - 0.02 * u * abs(u) + 0.2 * v * r + 2e-5 * f[0],
            -0.05 * v - 0.1 * v * abs(v) - 0.3 * u * r + 2e-5 * f[1],
            -0.1 * r - 0.3 * r * abs(r) + 0.005 * u * v + 6e-6 * f[2],
            r,
        ])
    nav = np.concatenate([[0.0], jitter(5.0)])
    nav = nav[nav <= seconds]
    at = np.minimum(np.round(nav / h).astype(int), n - 1)
    noise = rng.standard_normal((len(nav), 4)) * [0.03, 0.03, 0.004, 0.01]
    _topic(folder / "nav.csv", nav, {"u": x[at, 0] + noise[:, 0], "v": x[at, 1] + noise[:, 1], "r": x[at, 2] + noise[:, 2]})
    yaw = np.pi / 2 - (x[at, 3] + noise[:, 3])
    _topic(folder / "imu.csv", nav, {
        "orientation.x": 0.0 * yaw, "orientation.y": 0.0 * yaw,
        "orientation.z": np.sin(yaw / 2), "orientation.w": np.cos(yaw / 2),
    })
    _topic(folder / "tau.csv", publish, {"Fx": forces[:, 0], "Fy": forces[:, 1], "Mz": forces[:, 2]})
    flags = np.arange(0.0, seconds + 0.5, 1.0)
    _topic(folder / "mode.csv", flags, {"dp": ((flags >= dp[0]) & (flags < dp[1])).astype(int)})
    (folder / "raw.som").write_text(RAW_FERRY)
    sources = "".join(f'[sources.{s}]\nfile = "{s}.csv"\ntime = ["secs", "nsecs"]\n' for s in ["nav", "imu", "tau", "mode"])
    (folder / "raw.toml").write_text(
        'experiment = "raw"\n' + sources + "[signals]\n"
        'u = "nav:u"\nv = "nav:v"\nr = "nav:r"\n'
        'psi = { from = "imu:orientation", as = "yaw", frame = "enu" }\n'
        'tau_x = "tau:Fx"\ntau_y = "tau:Fy"\ntau_n = "tau:Mz"\n'
        '[[keep]]\nwhen = "mode:dp"\nequals = 0\n'
    )


def _read(folder: Path, name: str) -> tuple[np.ndarray, pd.DataFrame]:
    frame = pd.read_csv(folder / name)
    return (frame["secs"] - EPOCH + frame["nsecs"] / 1e9).to_numpy(), frame


def _integral(t: np.ndarray, y: np.ndarray, lo: float, hi: float, held: bool) -> float:
    """The integral over [lo, hi] of the samples (t, y), held or linear."""
    inside = t[(t > lo) & (t < hi)]
    points = np.concatenate([[lo], inside, [hi]])
    if held:
        values = y[np.searchsorted(t, points[:-1], side="right") - 1]
        return float(np.sum(values * np.diff(points)))
    values = np.interp(points, t, y)
    return float(np.sum(0.5 * (values[1:] + values[:-1]) * np.diff(points)))


def _by_hand(folder: Path) -> dict[str, pd.DataFrame]:
    """The raw topics pre-processed as a careful engineer would, in numpy:
    the mode's open-loop stretches kept; on a 1 s grid, each force its mean
    over [t, t + 1), each velocity and the heading a mean centred on t."""
    t_nav, nav = _read(folder, "nav.csv")
    _, imu = _read(folder, "imu.csv")
    t_tau, tau = _read(folder, "tau.csv")
    t_mode, mode = _read(folder, "mode.csv")
    q = imu[["orientation.x", "orientation.y", "orientation.z", "orientation.w"]].to_numpy()
    yaw = np.arctan2(2 * (q[:, 3] * q[:, 2] + q[:, 0] * q[:, 1]), 1 - 2 * (q[:, 1] ** 2 + q[:, 2] ** 2))
    psi = np.unwrap(np.pi / 2 - yaw)
    first, last = max(t_nav[0], t_tau[0]), min(t_nav[-1], t_tau[-1])
    open_loop = mode["dp"].to_numpy() == 0
    stretches, start = [], None
    for k, on in enumerate(open_loop):
        if on and start is None:
            start = t_mode[k]
        if not on and start is not None:
            stretches.append((start, t_mode[k] - 1e-9))
            start = None
    if start is not None:
        stretches.append((start, t_mode[-1]))
    frames = {}
    for j, (a, b) in enumerate(stretches):
        a, b = max(a, first), min(b, last)
        grid = a + np.arange(int(np.floor((b - a) * (1 + 1e-12))) + 1)
        grid = grid[grid <= b]
        columns = {"time": grid - grid[0]}
        for name in ["u", "v", "r"]:
            y = nav[name].to_numpy()
            half = np.minimum(0.5, np.minimum(grid - max(a, t_nav[0]), min(b, t_nav[-1]) - grid))
            columns[name] = [
                _integral(t_nav, y, g - w, g + w, held=False) / (2 * w) if w > 0 else float(np.interp(g, t_nav, y))
                for g, w in zip(grid, half)
            ]
        half = np.minimum(0.5, np.minimum(grid - max(a, t_nav[0]), min(b, t_nav[-1]) - grid))
        columns["psi"] = [
            _integral(t_nav, psi, g - w, g + w, held=False) / (2 * w) if w > 0 else float(np.interp(g, t_nav, psi))
            for g, w in zip(grid, half)
        ]
        for name, col in [("tau_x", "Fx"), ("tau_y", "Fy"), ("tau_n", "Mz")]:
            y = tau[col].to_numpy()
            hi = np.minimum(grid + 1.0, b)
            columns[name] = [
                _integral(t_tau, y, g, e, held=True) / (e - g) if e > g else float(y[np.searchsorted(t_tau, g, side="right") - 1])
                for g, e in zip(grid, hi)
            ]
        frames[f"raw/{j + 1}"] = pd.DataFrame(columns)
    return frames


def test_a_manifest_alone_equals_a_hand_preprocessing_of_the_raw_topics(tmp_path: Path) -> None:
    _raw_topics(tmp_path)
    model = leeway.Model.load(tmp_path / "raw.som")
    log = leeway.read_log(model, tmp_path / "raw.toml")
    hand = _by_hand(tmp_path)
    assert list(log.experiments) == list(hand) == ["raw/1", "raw/2"]
    for name in hand:
        assert len(log.experiments[name]) == len(hand[name])
    by_manifest = leeway.estimate(model, log.experiments, method="ls")
    by_hand = leeway.estimate(model, hand, method="ls")
    for p, value in by_manifest.theta.items():
        assert value == pytest.approx(by_hand.theta[p], rel=1e-6), p
    fits = leeway.validate(model, {"manifest": by_manifest, "hand": by_hand}, log.experiments)
    mean = fits.xs("mean", level="experiment")
    assert abs(mean.loc["manifest", "u"] - mean.loc["hand", "u"]) < 1.0
    assert abs(mean.loc["manifest", "r"] - mean.loc["hand", "r"]) < 1.0
