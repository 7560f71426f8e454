"""Estimate.cov, leeway.simulate and leeway.validate: the covariance against
the standard errors, simulation and validation bit-identical to `leeway
simulate` and `leeway validate --json`, and bad input raising the right
exception with its location."""

from __future__ import annotations

import csv
import io
import json
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import leeway
from conftest import SHIP, TRUE, run_leeway, ship_data, ticks_during


@pytest.fixture(scope="module")
def ship() -> leeway.Model:
    return leeway.Model.load(SHIP)


@pytest.fixture(scope="module")
def est(ship: leeway.Model, ship_frame: pd.DataFrame) -> leeway.Estimate:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", leeway.LeewayWarning)
        return leeway.estimate(ship, ship_frame)


def inputs(n: int, seed: int = 3) -> pd.DataFrame:
    """A zigzag of the ship's thrusters in a measured wind, with a time column."""
    rng = np.random.default_rng(seed)
    k = np.arange(n)
    zig = np.where((k // 50) % 2 == 0, 1.0, -1.0)
    return pd.DataFrame({
        "time": 10.0 + k,
        "tau1": 60 + rng.normal(0, 3, n),
        "tau2": 169 + 40 * zig,
        "tau3": 235 + 150 * zig,
        "wind_n": 1 + rng.normal(0, 0.03, n),
        "wind_e": 1 + rng.normal(0, 0.03, n),
    })


def same_bits(a: pd.DataFrame, b: pd.DataFrame) -> None:
    assert list(a.columns) == list(b.columns)
    for c in a.columns:
        x, y = a[c].to_numpy(np.float64), b[c].to_numpy(np.float64)
        assert np.array_equal(x.view(np.int64), y.view(np.int64)), c


def read_cli_csv(text: str) -> pd.DataFrame:
    # The CLI writes shortest round-trip text; Python's float() reads it back
    # exactly (pandas' own parser need not).
    rows = list(csv.reader(io.StringIO(text)))
    return pd.DataFrame([[float(v) for v in r] for r in rows[1:]], columns=rows[0])


# --- Estimate.cov ---------------------------------------------------------


def test_cov_is_labelled_symmetric_and_its_diagonal_gives_the_standard_errors(
    ship: leeway.Model, est: leeway.Estimate
) -> None:
    cov = est.cov
    assert list(cov.index) == list(cov.columns) == ship.parameters
    assert cov.index.name == cov.columns.name == "parameter"
    assert cov.dtypes.eq(np.float64).all()
    m = cov.to_numpy()
    assert np.array_equal(m, m.T, equal_nan=True)  # exactly, not within round-off
    se = est.params["std_error"].to_numpy()
    # Estimated alone or as an aggregate with a held parameter.
    estimated = est.params["status"].isin(["estimated", "aggregate"]).to_numpy()
    assert estimated.any() and not estimated.all()  # this light-wind turn holds W_uu
    diag = np.diag(m)
    # The standard error is √diag, computed once in Rust: equal bits.
    assert np.array_equal(np.sqrt(diag[estimated]), se[estimated])
    # So diag = se² as exactly as floats allow (√ rounds once, squaring once).
    np.testing.assert_allclose(diag[estimated], se[estimated] ** 2, rtol=4 * np.finfo(float).eps)
    # NaN in the row and column of every parameter that was not estimated.
    held = ~estimated
    assert np.isnan(m[held, :]).all() and np.isnan(m[:, held]).all()
    assert not np.isnan(m[np.ix_(estimated, estimated)]).any()
    # A covariance matrix: positive semidefinite over the estimated block.
    block = m[np.ix_(estimated, estimated)]
    assert np.linalg.eigvalsh(block).min() > -1e-12 * np.abs(block).max()


def test_cov_is_in_the_cli_document(est: leeway.Estimate) -> None:
    d = json.loads(est.to_json())
    assert list(d["covariance"]) == list(d["estimates"])
    assert d["covariance"]["X_tau"]["X_tau"] == est.cov.loc["X_tau", "X_tau"]


# --- leeway.simulate ------------------------------------------------------


def cli_simulate(tmp: Path, frame: pd.DataFrame, params: str, *args: str) -> pd.DataFrame:
    frame.to_csv(tmp / "in.csv", index=False)
    (tmp / "theta.json").write_text(params)
    o = run_leeway(
        "simulate", str(SHIP), "--params", str(tmp / "theta.json"), "--input", str(tmp / "in.csv"), *args
    )
    assert o.returncode == 0, o.stderr
    return read_cli_csv(o.stdout)


def test_simulate_is_bit_identical_to_the_cli(ship: leeway.Model, tmp_path: Path) -> None:
    u = inputs(300)
    ours = leeway.simulate(
        ship, TRUE, u, x0={"u": 5, "v": 3.3, "r": 0.15, "psi": 0},
        disturbances={"current.north": 0.2, "east": 0.2},
    )
    cli = cli_simulate(
        tmp_path, u, json.dumps(TRUE), "--x0", "u=5,v=3.3,r=0.15,psi=0",
        "--disturbance", "current.north=0.2,current.east=0.2",
    )
    assert list(ours.columns) == ["time", "u", "v", "r", "psi", "tau1", "tau2", "tau3", "wind_n", "wind_e"]
    assert len(ours) == 300 and ours["time"].iloc[0] == 10.0
    assert ours.attrs["diverged"] is False
    same_bits(ours, cli)
    # θ in the model's order is the same θ.
    same_bits(leeway.simulate(ship, list(TRUE.values()), u, x0={"u": 5, "v": 3.3, "r": 0.15, "psi": 0},
                              disturbances={"current.north": 0.2, "current.east": 0.2}), ours)


def test_a_noisy_simulation_is_bit_identical_to_the_cli(ship: leeway.Model, tmp_path: Path) -> None:
    u = inputs(400)
    x0 = {"u": 5, "v": 3.3, "r": 0.15, "psi": 0}
    noisy = {
        "disturbance_std": {"current": 0.05, "wind.wind_n": 0.3},
        "correlation_time": {"current.north": 60.0},
        "noise": {"u": 0.01, "psi": 0.005, "wind": 0.1},
    }
    ours = leeway.simulate(ship, TRUE, u, x0=x0, disturbances={"north": 0.2, "east": -0.1}, seed=7, **noisy)
    cli = cli_simulate(
        tmp_path, u, json.dumps(TRUE), "--x0", "u=5,v=3.3,r=0.15,psi=0",
        "--disturbance", "current.north=0.2,current.east=-0.1",
        "--disturbance-std", "current=0.05,wind.wind_n=0.3", "--correlation-time", "current.north=60",
        "--noise", "u=0.01,psi=0.005,wind=0.1", "--seed", "7",
    )
    same_bits(ours, cli)
    plain = leeway.simulate(ship, TRUE, u, x0=x0, disturbances={"north": 0.2, "east": -0.1})
    assert not np.array_equal(ours["u"].to_numpy(), plain["u"].to_numpy())
    assert not np.array_equal(ours["wind_n"].to_numpy(), u["wind_n"].to_numpy())
    assert np.array_equal(ours["tau1"].to_numpy(), plain["tau1"].to_numpy())
    other = leeway.simulate(ship, TRUE, u, x0=x0, disturbances={"north": 0.2, "east": -0.1}, seed=8, **noisy)
    assert not np.array_equal(ours["u"].to_numpy(), other["u"].to_numpy())


def test_noise_keywords_are_checked(ship: leeway.Model) -> None:
    x0 = {"u": 5, "v": 0, "r": 0, "psi": 0}
    u = inputs(20)
    with pytest.raises(leeway.OptionError) as e:
        leeway.simulate(ship, TRUE, u, x0=x0, noise={"w": 0.1})
    assert e.value.message == 'noise["w"]: `w` is not a state, the heading or a measured disturbance of model `Ship`'
    assert (e.value.hint or "").startswith("the measured signals are u, v, r, psi")
    with pytest.raises(leeway.OptionError, match="negative"):
        leeway.simulate(ship, TRUE, u, x0=x0, disturbance_std={"current": -0.1})
    with pytest.raises(leeway.OptionError, match="no standard deviation given"):
        leeway.simulate(ship, TRUE, u, x0=x0, correlation_time={"current": 60})
    with pytest.raises(leeway.OptionError, match="seed"):
        leeway.simulate(ship, TRUE, u, x0=x0, seed=-1)


def test_simulate_with_an_estimate_and_initial_values_from_the_first_row(
    ship: leeway.Model, est: leeway.Estimate, tmp_path: Path
) -> None:
    u = inputs(200).assign(u=np.nan, v=np.nan, r=np.nan, psi=np.nan)
    u.loc[0, ["u", "v", "r", "psi"]] = [5.0, 3.0, 0.1, 0.3]
    ours = leeway.simulate(ship, est, u, x0={"psi": 0.0})
    cli = cli_simulate(tmp_path, u, est.to_json(), "--x0", "psi=0")
    same_bits(ours, cli)
    assert ours["u"].iloc[0] == 5.0 and ours["psi"].iloc[0] == 0.0


def test_a_diverging_simulation_warns_and_returns_the_rows_before(ship: leeway.Model) -> None:
    unstable = {**TRUE, "X_u": 5.0, "X_uu": 5.0}
    with pytest.warns(leeway.LeewayWarning, match="diverged at sample"):
        frame = leeway.simulate(ship, unstable, inputs(300), x0={"u": 5, "v": 0, "r": 0, "psi": 0})
    assert frame.attrs["diverged"] is True
    assert 0 < len(frame) < 300 and np.isfinite(frame[["u", "v", "r"]].to_numpy()).all()


def test_simulate_errors_are_located(ship: leeway.Model) -> None:
    x0 = {"u": 5, "v": 0, "r": 0, "psi": 0}
    with pytest.raises(leeway.DataError) as e:
        leeway.simulate(ship, TRUE, inputs(20).drop(columns="tau3"), x0=x0)
    assert e.value.code == "data" and "missing column `tau3`" in e.value.message
    assert e.value.location == "inputs: header"
    with pytest.raises(leeway.DataError) as e:
        leeway.simulate(ship, TRUE, inputs(20), x0={"u": 5, "v": 0, "r": 0})
    assert "no initial value for `psi`" in e.value.message and 'x0={"psi": VALUE}' in (e.value.hint or "")
    bad = inputs(20)
    bad.loc[7, "tau2"] = np.inf
    with pytest.raises(leeway.DataError) as e:
        leeway.simulate(ship, TRUE, bad, x0=x0)
    assert e.value.location == "inputs: row 7, column `tau2`", e.value.location
    jumpy = inputs(20)
    jumpy.loc[12:, "time"] += 1.0
    with pytest.raises(leeway.DataError, match="inconsistent sample time") as e:
        leeway.simulate(ship, TRUE, jumpy, x0=x0)
    assert e.value.location == "inputs: row 12, column `time`"


def test_simulate_options_are_checked(ship: leeway.Model) -> None:
    x0 = {"u": 5, "v": 0, "r": 0, "psi": 0}
    u = inputs(20)
    with pytest.raises(leeway.OptionError, match="missing: N_tau") as e:
        leeway.simulate(ship, {k: v for k, v in TRUE.items() if k != "N_tau"}, u, x0=x0)
    assert e.value.code == "invalid-params"
    with pytest.raises(leeway.OptionError, match="16 values") as e:
        leeway.simulate(ship, list(TRUE.values())[:-1], u, x0=x0)
    assert e.value.code == "invalid-params"
    with pytest.raises(leeway.OptionError, match="not a finite number"):
        leeway.simulate(ship, {**TRUE, "X_u": float("nan")}, u, x0=x0)
    with pytest.raises(leeway.OptionError, match="not a state or the heading"):
        leeway.simulate(ship, TRUE, u, x0={**x0, "w": 1.0})
    with pytest.raises(leeway.OptionError, match="is measured"):
        leeway.simulate(ship, TRUE, u, x0=x0, disturbances={"wind.wind_n": 1.0})
    with pytest.raises(leeway.OptionError, match="not a disturbance component"):
        leeway.simulate(ship, TRUE, u, x0=x0, disturbances={"current.up": 1.0})
    with pytest.raises(leeway.OptionError, match="given twice"):
        leeway.simulate(ship, TRUE, u, x0=x0, disturbances={"north": 0.1, "current.north": 0.2})
    with pytest.raises(leeway.OptionError, match="conflicts"):
        leeway.simulate(ship, TRUE, u, x0=x0, step=0.5)
    with pytest.raises(leeway.OptionError, match="x0"):
        leeway.simulate(ship, TRUE, u, x0={**x0, "u": 1e13})


# --- leeway.validate ------------------------------------------------------


def test_validate_is_bit_identical_to_the_cli(
    ship: leeway.Model, est: leeway.Estimate, tmp_path: Path
) -> None:
    a = ship_data(tmp_path, 300, 1.0, 11).assign(experiment="a")
    b = ship_data(tmp_path, 250, 1.0, 12).assign(experiment="b")
    held_out = pd.concat([a, b], ignore_index=True)
    held_out.to_csv(tmp_path / "val.csv", index=False)
    (tmp_path / "iv3.json").write_text(est.to_json())
    (tmp_path / "truth.json").write_text(json.dumps(TRUE))
    o = run_leeway(
        "validate", str(SHIP), "--params", str(tmp_path / "iv3.json"), "--params", str(tmp_path / "truth.json"),
        "--data", str(tmp_path / "val.csv"), "--disturbance", "current.north=0.2,current.east=0.2", "--json",
    )
    assert o.returncode == 0, o.stderr
    cli = json.loads(o.stdout)
    fits = leeway.validate(
        ship, {"iv3": est, "truth": TRUE}, held_out, disturbances={"current.north": 0.2, "current.east": 0.2}
    )
    outputs = ["u", "v", "r", "psi"]
    assert list(fits.columns) == ["samples", "diverged", *outputs]
    assert list(fits.index) == [(m, e) for m in ("iv3", "truth") for e in ("a", "b", "mean")]
    for name, model in zip(("iv3", "truth"), cli["models"]):
        for e in model["experiments"]:
            row = fits.loc[(name, e["name"])]
            assert row["samples"] == e["samples"] and row["diverged"] == e["diverged"]
            expected = [*e["fit"].values(), e["heading_fit"]]
            assert [row[o] for o in outputs] == expected, (name, e["name"])
        assert [fits.loc[(name, "mean"), o] for o in outputs] == list(model["mean"].values())
    # The true θ fits its own undisturbed simulation up to the measurement noise.
    assert (fits.xs("mean", level="experiment").loc["truth", ["u", "v", "r"]] > 50).all()


def test_validate_names_thetas_and_takes_one(ship: leeway.Model, est: leeway.Estimate, ship_frame: pd.DataFrame) -> None:
    val = ship_frame.head(300)
    one = leeway.validate(ship, est, val)
    assert list(one.index) == [("iv3", "data"), ("iv3", "mean")]
    both = leeway.validate(ship, [TRUE, list(TRUE.values())], val)
    assert list(both.index.get_level_values("model").unique()) == ["theta[0]", "theta[1]"]
    a, b = both.xs("theta[0]"), both.xs("theta[1]")
    assert a.equals(b)


def test_validate_holds_the_disturbance_means_of_an_estimate(
    ship: leeway.Model, est: leeway.Estimate, ship_frame: pd.DataFrame, tmp_path: Path
) -> None:
    val = ship_frame.head(400)
    means = {f"{d}.{c}": m for (d, c), m in est.disturbances["mean"].items()}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        held = leeway.validate(ship, est, val)
    assert not [w for w in caught if "taken as zero" in str(w.message)]
    assert held.attrs["disturbances"] == {
        "iv3": {n: {"value": v, "from": "estimate"} for n, v in means.items()}
    }
    # The means given by hand: the same fits, bit for bit.
    by_hand = leeway.validate(ship, est, val, disturbances=means)
    assert held.equals(by_hand)
    # As the CLI does with the estimate's document as --params, without options.
    (tmp_path / "iv3.json").write_text(est.to_json())
    val.to_csv(tmp_path / "val.csv", index=False)
    o = run_leeway("validate", str(SHIP), "--params", str(tmp_path / "iv3.json"),
                   "--data", str(tmp_path / "val.csv"), "--json")
    assert o.returncode == 0, o.stderr
    assert [held.loc[("iv3", "mean"), s] for s in ("u", "v", "r", "psi")] == list(
        json.loads(o.stdout)["mean"].values()
    )
    # θ without means: zero, with a warning in Python's words; "zero" asks for it.
    with pytest.warns(leeway.LeewayWarning, match='taken as zero.*disturbances="zero"') as caught:
        plain = leeway.validate(ship, est.theta, val)
    assert not any("--" in str(w.message) for w in caught)
    assert plain.attrs["disturbances"]["theta"]["current.north"] == {"value": 0.0, "from": "default"}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        zero = leeway.validate(ship, est.theta, val, disturbances="zero")
    assert not [w for w in caught if "taken as zero" in str(w.message)]
    assert zero[["u", "v", "r"]].equals(plain[["u", "v", "r"]])
    with pytest.raises(leeway.OptionError, match='"zero"'):
        leeway.validate(ship, est, val, disturbances="calm")


def test_simulate_holds_the_estimates_means(ship: leeway.Model, est: leeway.Estimate, ship_frame: pd.DataFrame) -> None:
    inputs = ship_frame.head(50)
    frame = leeway.simulate(ship, est, inputs)
    assert {v["from"] for v in frame.attrs["disturbances"].values()} == {"estimate"}
    with pytest.warns(leeway.LeewayWarning, match="`current` taken as zero"):
        leeway.simulate(ship, est.theta, inputs)


def test_validate_errors(ship: leeway.Model, ship_frame: pd.DataFrame) -> None:
    with pytest.raises(leeway.DataError) as e:
        leeway.validate(ship, TRUE, {"val": ship_frame.drop(columns="tau1")})
    assert "tau1" in e.value.message and e.value.location is not None
    with pytest.raises(leeway.OptionError) as e:
        leeway.validate(ship, {"a": TRUE, "b": {"X_u": 1.0}}, ship_frame)
    assert e.value.code == "invalid-params" and "thetas['b']" in e.value.message
    with pytest.raises(leeway.OptionError, match="time_tolerance"):
        leeway.validate(ship, TRUE, ship_frame, time_tolerance=0.7)


def test_validate_warns_when_a_simulation_diverges(ship: leeway.Model, ship_frame: pd.DataFrame) -> None:
    with pytest.warns(leeway.LeewayWarning, match="unstable, experiment `data`: the simulation diverged"):
        fits = leeway.validate(ship, {"unstable": {**TRUE, "X_u": 5.0, "X_uu": 5.0}}, ship_frame.head(300))
    assert fits.loc[("unstable", "data"), "diverged"]
    assert fits.loc[("unstable", "mean"), ["u", "v", "r", "psi"]].isna().all()


def test_the_gil_is_released_while_validating(ship: leeway.Model, tmp_path: Path) -> None:
    # A record long enough that simulating it, which releases the GIL,
    # outweighs reading the frame's columns, which holds it: on 1500 samples
    # the other thread ticked through 29–60 % of the time (flaky against
    # 30 %), on 20 000 through 75–82 %. Holding the GIL throughout would
    # leave it a tick or so between calls.
    frame = ship_data(tmp_path, 20000, 1.0, 7)

    def work() -> None:
        for _ in range(3):
            leeway.validate(ship, TRUE, frame)

    ticks, elapsed = ticks_during(work)
    assert ticks > 0.3 * elapsed / 0.0011, (ticks, elapsed)


def test_validate_says_when_a_fit_is_below_zero(ship: leeway.Model, ship_frame: pd.DataFrame) -> None:
    # A fit far below 0 % (N_tau of the wrong sign) is reported with a warning, as in the CLI.
    wrong = {**TRUE, "N_tau": -TRUE["N_tau"]}
    with pytest.warns(leeway.LeewayWarning, match=r"wrong, experiment `data`: the simulation fits .*worse than the data's mean"):
        fits = leeway.validate(ship, {"wrong": wrong}, ship_frame)
    assert (fits.loc[("wrong", "mean"), ["r"]] < 0).all()
