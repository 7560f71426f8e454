# %% [markdown]
# # From a `.som` file to a validated model, with pandas
#
# The paper's ship (`examples/models/ship.som`): a 3-DOF manoeuvring model
# whose water-relative terms feel an unmeasured current and whose
# air-relative terms feel a wind measured by an anemometer. We check that its
# parameters are identifiable, make data by simulating a "true" ship with
# leeway itself, estimate with IV3, look at the estimate, and validate it on
# a held-out zigzag it never saw.
#
# Run it as a script (`python examples/python/ship_walkthrough.py`, a few
# seconds) or cell by cell in any editor that knows `# %%` cells (VS Code,
# Spyder, PyCharm, Jupyter through jupytext). Everything leeway computes here
# is what the `leeway` command computes: `est.to_json()` is the document of
# `leeway estimate --json`, `leeway.simulate` writes what `leeway simulate`
# writes, `leeway.validate` reports the fits of `leeway validate`.

# %% Setup
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

import leeway

try:
    ROOT = Path(__file__).resolve().parents[2]
except NameError:  # inside a notebook: run from the repository's root
    ROOT = Path.cwd()
pd.set_option("display.width", 120)
pd.set_option("display.max_columns", 12)
rng = np.random.default_rng(2024)

# %% 1. The model
model = leeway.Model.load(ROOT / "examples" / "models" / "ship.som")
print(model)
print("states:", model.states, " inputs:", model.inputs)
print("parameters:", model.parameters)

# %% 2. Is θ identifiable, and from which experiments?
# The structure compiler answers exactly (no data yet): the regressors of each
# equation, the nuisance parameters the unmeasured current brings in, and the
# smallest set of experiments (sign patterns of the velocities relative to the
# water) that identifies θ.
check = model.check()
print("identifiable:", check.identifiable, f"({check.verdict})")
print("experiments needed:", check.required_sign_patterns)
print(check.regressors.head(8).to_string(index=False))
print("nuisance parameters:", check.nuisance["before"], "->", check.nuisance["after"])

# %% 3. Data: a true ship, simulated by leeway
# θ0 of the paper's table plays the true ship. The input design is the study's
# (scenarios/src/study.rs): a thrust offset that holds a steady turn, plus
# smoothed pulses of random width on every thruster. A current of (0.2, 0.2)
# m/s pushes the ship (unmeasured: the estimator must account for it); the
# wind is measured. Measurement noise is added afterwards, as a logger would.
TRUE = dict(zip(model.parameters, [
    -0.05, 1.0, -0.05, -0.0005, 0.02, -0.2, -0.65, -0.2, -0.1, -0.0015, 0.02,
    -0.1, -0.0015, -0.001, -0.04, -0.00003, 0.0003,
]))
CURRENT = {"current.north": 0.2, "current.east": 0.2}


def pulses(n: int, amplitude: float) -> np.ndarray:
    """Smoothed pulses of random width (20-80 s) and amplitude."""
    out, level, k = np.empty(n), 0.0, 0
    while k < n:
        width = int(rng.integers(20, 81))
        target = rng.uniform(-amplitude, amplitude)
        for j in range(k, min(n, k + width)):
            level += 0.15 * (target - level)
            out[j] = level
        k += width
    return out


def turning_run(n: int, wind: float) -> pd.DataFrame:
    yaw = pulses(n, 150.0)
    return pd.DataFrame({
        "time": np.arange(n, dtype=float),
        "tau1": 50.0 + pulses(n, 30.0),
        "tau2": 169.0 + pulses(n, 40.0) + 0.25 * yaw,
        "tau3": 235.0 + yaw,
        "wind_n": wind + rng.normal(0.0, 0.03, n),
        "wind_e": wind + rng.normal(0.0, 0.03, n),
    })


def measured(trajectory: pd.DataFrame) -> pd.DataFrame:
    noisy = trajectory.copy()
    for column, sd in [("u", 0.014), ("v", 0.014), ("r", 0.014), ("psi", 0.01)]:
        noisy[column] += rng.normal(0.0, sd, len(noisy))
    return noisy


STEADY_TURN = {"u": 5.0, "v": 3.3, "r": 0.15, "psi": 0.0}
runs = {}
for name, wind in [("light-wind", 1.0), ("breeze", 3.0)]:
    truth = leeway.simulate(model, TRUE, turning_run(2000, wind), x0=STEADY_TURN, disturbances=CURRENT)
    runs[name] = measured(truth)
print(runs["light-wind"].head())

# The held-out experiment: a zigzag (sway and yaw thrust switched every 50 s,
# the thrust stepped every 120 s), from rest in sway and yaw, in the same
# current and a light wind.
n = 600
k = np.arange(n)
zig = np.where((k // 50) % 2 == 0, 1.0, -1.0)
zigzag = pd.DataFrame({
    "time": k.astype(float),
    "tau1": np.where((k // 120) % 2 == 0, 70.0, 45.0),
    "tau2": 40.0 * zig,
    "tau3": 150.0 * zig,
    "wind_n": 1.0 + rng.normal(0.0, 0.03, n),
    "wind_e": 1.0 + rng.normal(0.0, 0.03, n),
})
held_out = measured(leeway.simulate(
    model, TRUE, zigzag, x0={"u": 5.0, "v": 0.0, "r": 0.0, "psi": 0.0}, disturbances=CURRENT
))

# %% 4. Estimate with IV3
# A dict of DataFrames: one experiment each, named by its key (a single frame
# with an `experiment` column works as well).
est = leeway.estimate(model, runs, method="iv3")
print(est)
print(est.diagnostics["predictor"], "predictor; rank", est.diagnostics["rank"],
      "of", est.diagnostics["estimated"], "estimated columns;",
      est.diagnostics["refinements"], "refinements, converged:", est.diagnostics["converged"])

# %% 5. Look at the estimate: θ, its covariance, the disturbances
params = est.params[["estimate", "std_error", "status"]].assign(true=pd.Series(TRUE))
params["error / se"] = (params["estimate"] - params["true"]) / params["std_error"]
print(params.to_string(float_format="{:.4g}".format))

# The covariance of θ (NaN where a parameter was not estimated); its diagonal
# is the squared standard error. As correlations:
sd = np.sqrt(np.diag(est.cov))
correlation = est.cov / np.outer(sd, sd)
print(correlation.loc[["X_u", "X_uu", "X_tau"], ["X_u", "X_uu", "X_tau"]].round(3))

# The means of the unmeasured current (paper Corollary 1): the truth is (0.2, 0.2).
print(est.disturbances)

# %% 6. Simulate the estimated model and validate it on the held-out zigzag
# The estimated current drives the simulation, as the truth's current drove
# the data.
current = {f"current.{c}": m for (_, c), m in est.disturbances["mean"].items()}
simulated = leeway.simulate(model, est, held_out, disturbances=current)
print(simulated[["time", "u", "v", "r", "psi"]].tail(3))

fits = leeway.validate(
    model, {"iv3": est, "nominal": model.nominal, "true": TRUE}, {"zigzag": held_out},
    disturbances=current,
)
print("fit in % (100 is perfect):")
print(fits.xs("zigzag", level="experiment")[["u", "v", "r", "psi"]].round(1))
assert fits.loc[("iv3", "zigzag"), ["u", "v", "r"]].min() > 80.0

# %% Past one machine: Dask
# A fleet logs for months: far more samples than one process should hold. The
# estimator makes a handful of passes over the data; `leeway.dask` maps every
# pass over the log files on the workers of a Dask cluster (each task opens
# its own file: the data never pass through this process) and combines the
# experiments' small moment summaries here, in experiment order, so the result
# is the local estimate bit for bit (docs/distributed.md).
#
# The campaign: turning runs in varying wind, one Parquet file per run. Its
# size is `LEEWAY_CAMPAIGN_SAMPLES` (default 2·10⁵, seconds; the measured run
# in docs/distributed.md used 10⁸ in 100 files of 10⁶).
import os
import resource
import subprocess
import sys
import tempfile
import time

from dask.distributed import Client

import leeway.dask
import leeway.mapreduce

SAMPLES = int(os.environ.get("LEEWAY_CAMPAIGN_SAMPLES", "200000"))
PER_FILE = min(SAMPLES, 1_000_000)
# A directory of our own is removed when the walk-through ends (an 18 MB
# campaign per run otherwise stays in /tmp); one given is kept.
if os.environ.get("LEEWAY_CAMPAIGN_DIR"):
    campaign = Path(os.environ["LEEWAY_CAMPAIGN_DIR"])
else:
    _scratch = tempfile.TemporaryDirectory(prefix="leeway-campaign-")
    campaign = Path(_scratch.name)
campaign.mkdir(parents=True, exist_ok=True)


def fast_pulses(n: int, amplitude: float, seed: int) -> np.ndarray:
    """`pulses`, vectorised: random widths and levels, smoothed exponentially."""
    r = np.random.default_rng(seed)
    widths = r.integers(20, 81, n // 20 + 1)
    levels = np.repeat(r.uniform(-amplitude, amplitude, len(widths)), widths)[:n]
    return pd.Series(levels).ewm(alpha=0.15, adjust=False).mean().to_numpy()


files = []
for i in range(SAMPLES // PER_FILE):
    path = campaign / f"run{i:04}.parquet"
    files.append(path)
    if path.exists():
        continue
    r = np.random.default_rng(10_000 + i)
    wind = float(r.uniform(1.0, 8.0))
    yaw = fast_pulses(PER_FILE, 150.0, 3 * i)
    inputs = pd.DataFrame({
        "time": np.arange(PER_FILE, dtype=float),
        "tau1": 50.0 + fast_pulses(PER_FILE, 30.0, 3 * i + 1),
        "tau2": 169.0 + fast_pulses(PER_FILE, 40.0, 3 * i + 2) + 0.25 * yaw,
        "tau3": 235.0 + yaw,
        "wind_n": wind + r.normal(0.0, 0.03, PER_FILE),
        "wind_e": wind + r.normal(0.0, 0.03, PER_FILE),
    })
    log = measured(leeway.simulate(model, TRUE, inputs, x0=STEADY_TURN, disturbances=CURRENT))
    log.to_parquet(path, index=False)
print(f"campaign: {len(files)} files of {PER_FILE:,} samples in {campaign}")


def peak_mib() -> float:
    """This process's peak resident memory (Linux reports KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


# A cluster as on several machines: a scheduler and two worker processes
# (`dask scheduler`, `dask worker`; on a real cluster each on its own
# machine), and this process connected to it as a client.
scheduler_file = campaign / "scheduler.json"
scheduler_file.unlink(missing_ok=True)
cluster = [subprocess.Popen(
    [sys.executable, "-m", "distributed.cli.dask_scheduler", "--scheduler-file", str(scheduler_file),
     "--port", "0", "--dashboard-address", ":0"],
    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
)]
cluster += [subprocess.Popen(
    [sys.executable, "-m", "distributed.cli.dask_worker", "--scheduler-file", str(scheduler_file),
     "--nthreads", "1", "--dashboard-address", ":0"],
    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
) for _ in range(2)]
try:
    with Client(scheduler_file=str(scheduler_file), timeout=60) as client:
        client.wait_for_workers(2, timeout=60)
        start = time.perf_counter()
        spread = leeway.dask.estimate(model, files, client, method="iv3")
        spread_wall = time.perf_counter() - start
        worker_peaks = client.run(peak_mib)
finally:
    for p in cluster:
        p.terminate()
    for p in cluster:
        p.wait(timeout=30)

# The same estimate in this process: the same two halves, run in a loop.
start = time.perf_counter()
opts = leeway.mapreduce.options(model, method="iv3")
datasets = [leeway.mapreduce.open_file(model, f, opts) for f in files]
offsets = np.cumsum([0] + [len(d) for d in datasets])[:-1]
here = leeway.mapreduce.estimate(
    model, [str(f) for f in files], [d.summary() for d in datasets],
    lambda q: [b for d in datasets for b in d.facts(q)],
    lambda q: [b for d, o in zip(datasets, offsets) for b in d.run(int(o), q)],
    opts,
)
local_wall = time.perf_counter() - start
del datasets

assert spread.to_json() == here.to_json(), "distributed and local estimates differ"
print(f"{SAMPLES:,} samples: distributed {spread_wall:.1f} s on 2 workers "
      f"(peak {', '.join(f'{m:.0f}' for m in worker_peaks.values())} MiB per worker), "
      f"local {local_wall:.1f} s (peak {peak_mib():.0f} MiB, this process): bit-identical")
print(spread.params.loc[["X_u", "X_uu", "X_tau", "Y_v", "N_r"], ["estimate", "std_error"]])
