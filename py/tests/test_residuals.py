"""Residual analysis from Python (``leeway.residuals``, ``leeway.predict``):
on data simulated by the model itself with white measurement noise the
true model's simulation errors are that noise and pass independence of the
input (the verdict) and whiteness; with process noise they are coloured
yet still independent; with a wrong θ or a missing term they fail. Fixed
seeds. The analysis is the one ``leeway validate --resid --json`` prints."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

import leeway

# Discrete-time on purpose: `next` is the one-step map itself, so the data
# are x(k+1) = a·x(k) + c·x(k)|x(k)| + b·τ(k) + w(k) written in numpy.
BOAT = """
model Boat {
    state u
    input tau
    next u = a*u + c*u*|u| + b*tau
    nominal { a = 0.9, c = -0.02, b = 0.1 }
}
"""
LINEAR = """
model Boat {
    state u
    input tau
    next u = a*u + b*tau
}
"""
THETA = {"a": 0.9, "c": -0.02, "b": 0.1}


def boat_data(n: int, seed: int, sd: float = 0.01, process: float = 0.0) -> pd.DataFrame:
    """The boat's true response to a random staircase, plus white
    measurement noise of deviation ``sd`` and white process noise of
    deviation ``process``."""
    rng = np.random.default_rng(seed)
    tau = np.repeat(rng.uniform(0.0, 2.0, n // 20 + 1), 20)[:n]
    u = np.zeros(n)
    for k in range(n - 1):
        u[k + 1] = 0.9 * u[k] - 0.02 * u[k] * abs(u[k]) + 0.1 * tau[k] + process * rng.standard_normal()
    measured = u + sd * rng.standard_normal(n)
    return pd.DataFrame({"time": np.arange(n) * 0.1, "u": measured, "tau": tau})


@pytest.fixture(scope="module")
def boat() -> leeway.Model:
    return leeway.Model.from_str(BOAT)


def test_the_true_model_leaves_its_measurement_noise(boat) -> None:  # type: ignore[no-untyped-def]
    data = {"run1": boat_data(3000, 1), "run2": boat_data(2000, 2)}
    r = leeway.residuals(boat, THETA, data)
    assert r.samples == 2999 + 1999 and r.lags == 25
    assert r.band == pytest.approx(2.5758 / np.sqrt(4998), rel=1e-4)
    assert r.independent and r.white, str(r)
    assert r.document["errors"] == "simulation" and r.diverged == []
    assert r.tests.loc["u", "std"] == pytest.approx(0.01, rel=0.1)
    # Errors per experiment, the first sample of each without one.
    assert list(r.residuals.index.get_level_values("experiment").unique()) == ["run1", "run2"]
    first = r.residuals.xs(0, level="sample")
    assert first["u"].isna().all()
    # e(k) = x(k) − x̂(k), x̂ the free run from the first measurement.
    run = data["run1"]
    free = np.zeros(len(run))
    free[0] = run["u"].iloc[0]
    for k in range(len(run) - 1):
        free[k + 1] = 0.9 * free[k] - 0.02 * free[k] * abs(free[k]) + 0.1 * run["tau"].iloc[k]
    np.testing.assert_allclose(r.simulated.loc["run1", "u"].to_numpy(), free, rtol=1e-12)
    np.testing.assert_allclose(
        r.residuals.loc["run1", "u"].to_numpy()[1:], run["u"].to_numpy()[1:] - free[1:], rtol=1e-12, atol=1e-15
    )
    assert r.autocorrelation.shape == (25, 1) and r.cross_correlation.shape == (51, 1)
    assert "verdict: independent" in str(r)


def test_process_noise_colours_the_error_but_not_the_verdict(boat) -> None:  # type: ignore[no-untyped-def]
    r = leeway.residuals(boat, THETA, boat_data(3000, 8, process=0.01))
    assert not r.white and r.independent, str(r)
    assert r.input_tests.loc[("u", "tau"), "band"] > r.input_band


def test_a_wrong_theta_fails(boat) -> None:  # type: ignore[no-untyped-def]
    r = leeway.residuals(boat, {"a": 0.8, "c": -0.02, "b": 0.1}, boat_data(3000, 3))
    assert not r.independent, str(r)
    assert len(r.input_tests.loc[("u", "tau"), "outside"]) > 0


def test_a_missing_term_fails() -> None:
    linear = leeway.Model.from_str(LINEAR)
    data = boat_data(3000, 4)
    # The least-squares fit of the linear model: its residual still holds the drag.
    x, y = data[["u", "tau"]].to_numpy()[:-1], data["u"].to_numpy()[1:]
    a, b = np.linalg.lstsq(x, y, rcond=None)[0]
    r = leeway.residuals(linear, {"a": a, "b": b}, data)
    assert not r.independent, str(r)


def test_predict_is_one_step_and_refuses_more(boat) -> None:  # type: ignore[no-untyped-def]
    data = boat_data(200, 5)
    p = leeway.predict(boat, THETA, data)
    assert list(p.columns) == ["time", "u"] and np.isnan(p["u"].iloc[0])
    # x̂(k+1|k) is the model's one step from the measured x(k).
    u, tau = data["u"].to_numpy(), data["tau"].to_numpy()
    np.testing.assert_allclose(p["u"].to_numpy()[1:], (0.9 * u - 0.02 * u * np.abs(u) + 0.1 * tau)[:-1], rtol=1e-12)
    with pytest.raises(leeway.OptionError, match="only one-step"):
        leeway.predict(boat, THETA, data, k=2)
    with pytest.raises(leeway.OptionError, match="lags"):
        leeway.residuals(boat, THETA, data.head(20), lags=25)


def test_the_cli_prints_the_same_analysis(boat, tmp_path) -> None:  # type: ignore[no-untyped-def]
    from conftest import run_leeway

    data = boat_data(1000, 6)
    (tmp_path / "boat.som").write_text(BOAT)
    data.to_csv(tmp_path / "val.csv", index=False)
    (tmp_path / "theta.json").write_text(json.dumps(THETA))
    o = run_leeway("validate", str(tmp_path / "boat.som"), "--params", str(tmp_path / "theta.json"),
                   "--data", str(tmp_path / "val.csv"), "--resid", "--json")
    cli = json.loads(o.stdout)
    ours = leeway.residuals(boat, THETA, data).document
    assert cli["residuals"][0]["tests"] == json.loads(json.dumps(ours))
