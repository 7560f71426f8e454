"""leeway.estimate: the API, bit-identity with `leeway estimate --json`,
warnings, data handed over from pandas/Arrow, and every error class from a
real failing input."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import leeway
from conftest import ROOT, SHIP, SHIP_IV2, TRUE, run_leeway, ship_data, ticks_during


@pytest.fixture(scope="module")
def ship() -> leeway.Model:
    return leeway.Model.load(SHIP)


def cli_json(tmp: Path, frame: pd.DataFrame, *args: str, name: str = "data") -> dict:
    path = tmp / f"{name}.csv"
    frame.to_csv(path, index=False)
    o = run_leeway("estimate", str(SHIP), "--data", str(path), "--json", *args)
    return json.loads(o.stdout)


def provenance_free(document: dict) -> dict:
    """The document without what names the input files (a frame has none)."""
    return {k: v for k, v in document.items() if k not in ("file", "data", "data_files")}


def test_estimate_recovers_theta_with_standard_errors(ship: leeway.Model, ship_frame: pd.DataFrame) -> None:
    # One steady turn in a light wind: the wind terms are not separately
    # excited, and the estimator says so.
    with pytest.warns(leeway.LeewayWarning, match="W_uu is not separately excited"):
        est = leeway.estimate(ship, ship_frame)
    assert est.method == "iv3"
    assert list(est.params.index) == ship.parameters
    assert list(est.params.columns) == ["kind", "estimate", "std_error", "status", "estimates", "aggregate"]
    assert est.params["estimate"].dtype == np.float64
    x_tau = est.params.loc["X_tau"]
    assert x_tau["status"] == "estimated"
    assert abs(x_tau["estimate"] - TRUE["X_tau"]) < 5 * x_tau["std_error"]
    assert (est.nuisance["kind"] != "theta").all()
    assert set(est.disturbances.index) == {("current", "north"), ("current", "east")}
    assert est.diagnostics["predictor"] == "measured"
    assert est.theta["X_tau"] == x_tau["estimate"]


def test_to_json_is_bit_identical_to_the_cli(ship: leeway.Model, ship_frame: pd.DataFrame, tmp_path: Path) -> None:
    for args, kwargs in [((), {}), (("--method", "ls"), {"method": "ls"}),
                         (("--combine", "stacked", "--lags", "3", "--centring", "pooled"),
                          {"combine": "stacked", "lags": 3, "centring": "pooled"})]:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", leeway.LeewayWarning)
            ours = json.loads(leeway.estimate(ship, ship_frame, **kwargs).to_json())
        cli = cli_json(tmp_path, ship_frame, *args)
        assert cli["errors"] == []
        # Floats compare by their shortest round-trip text: equal text, equal bits.
        assert json.dumps(provenance_free(ours)) == json.dumps(provenance_free(cli)), args
        assert ours["file"] == cli["file"] == str(SHIP)


def test_an_experiment_column_splits_a_frame_like_the_cli(ship: leeway.Model, tmp_path: Path) -> None:
    a = ship_data(tmp_path, 400, 1.0, 1).assign(experiment="a")
    b = ship_data(tmp_path, 400, 1.0, 2).assign(experiment="b")
    both = pd.concat([a, b], ignore_index=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", leeway.LeewayWarning)
        ours = json.loads(leeway.estimate(ship, both).to_json())
        as_dict = json.loads(leeway.estimate(ship, {"a": a.drop(columns="experiment"), "b": b.drop(columns="experiment")}).to_json())
    cli = cli_json(tmp_path, both)
    assert [e["name"] for e in ours["experiments"]] == ["a", "b"]
    assert json.dumps(provenance_free(ours)) == json.dumps(provenance_free(cli))
    # A dict names the experiments by its keys: the same estimate.
    assert as_dict["estimates"] == ours["estimates"]


def test_arrow_tables_and_other_dtypes_give_the_same_estimate(ship: leeway.Model, ship_frame: pd.DataFrame) -> None:
    import pyarrow as pa

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", leeway.LeewayWarning)
        reference = leeway.estimate(ship, ship_frame).theta
        table = leeway.estimate(ship, pa.Table.from_pandas(ship_frame)).theta
        # float32 columns are widened; a Fortran-ordered block is made contiguous.
        fortran = pd.DataFrame(np.asfortranarray(ship_frame.to_numpy()), columns=ship_frame.columns)
        assert leeway.estimate(ship, fortran).theta == reference
    assert table == reference


def test_warnings_are_leeway_warnings(ship: leeway.Model, ship_frame: pd.DataFrame) -> None:
    frame = ship_frame.copy()
    frame["psi"] = np.degrees(frame["psi"])  # the heading logged in degrees
    with pytest.warns(leeway.LeewayWarning, match="does not integrate"):
        est = leeway.estimate(ship, frame, method="ls")
    assert any("gain" in w for w in est.warnings)


def test_a_missing_column_is_a_located_data_error(ship: leeway.Model, ship_frame: pd.DataFrame) -> None:
    with pytest.raises(leeway.DataError) as e:
        leeway.estimate(ship, ship_frame.drop(columns="tau2"))
    assert e.value.code == "data" and "tau2" in e.value.message
    assert isinstance(e.value, ValueError)


def test_a_non_finite_value_names_its_row_and_column(ship: leeway.Model, ship_frame: pd.DataFrame) -> None:
    frame = ship_frame.copy()
    frame.loc[17, "v"] = np.nan
    with pytest.raises(leeway.DataError) as e:
        leeway.estimate(ship, {"run1": frame})
    assert e.value.location == "run1: row 17, column `v`", e.value.location


def test_a_text_column_is_a_data_error(ship: leeway.Model, ship_frame: pd.DataFrame) -> None:
    frame = ship_frame.copy()
    frame["u"] = "fast"
    with pytest.raises(leeway.DataError, match="not numeric"):
        leeway.estimate(ship, frame)


def test_too_few_samples_is_a_data_error(ship: leeway.Model, ship_frame: pd.DataFrame) -> None:
    with pytest.raises(leeway.DataError) as e:
        leeway.estimate(ship, ship_frame.head(5))
    assert e.value.location is not None


def test_unidentifiable(ship_frame: pd.DataFrame) -> None:
    with pytest.raises(leeway.Unidentifiable) as e:
        leeway.estimate(leeway.Model.load(SHIP_IV2), ship_frame)
    assert e.value.code == "unidentifiable" and "aggregate" in (e.value.hint or "")
    assert isinstance(e.value, leeway.EstimateError)


def test_rank_deficient(ship: leeway.Model) -> None:
    zeros = pd.DataFrame({c: np.zeros(200) for c in ship.columns})
    zeros["time"] = np.arange(200.0)
    with pytest.raises(leeway.RankDeficient) as e:
        leeway.estimate(ship, zeros, method="ls", aggregate=True)
    assert e.value.code == "rank-deficient"


def test_sign_violation_under_strict(tmp_path: Path) -> None:
    windy = ship_data(tmp_path, 1500, 10.0, 500, "windy")
    model = leeway.Model.load(SHIP)
    with pytest.raises(leeway.SignViolation) as e:
        leeway.estimate(model, windy, method="iv2", aggregate=True, strict=True)
    assert e.value.code == "sign-violation"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        leeway.estimate(model, windy, method="iv2", aggregate=True)
    assert any(issubclass(w.category, leeway.LeewayWarning) and "has sign" in str(w.message) for w in caught)


def test_options_are_checked(ship: leeway.Model, ship_frame: pd.DataFrame) -> None:
    with pytest.raises(leeway.OptionError, match="method"):
        leeway.estimate(ship, ship_frame, method="iv4")
    with pytest.raises(leeway.OptionError, match="lags"):
        leeway.estimate(ship, ship_frame, lags=0)
    with pytest.raises(leeway.OptionError, match="missing"):
        leeway.estimate(ship, ship_frame, nominal={"X_u": -0.1})
    with pytest.raises(leeway.OptionError, match="conflicts"):
        leeway.estimate(ship, ship_frame, step=0.5)


def test_the_gil_is_released_while_estimating(ship: leeway.Model, ship_frame: pd.DataFrame) -> None:
    def work() -> None:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", leeway.LeewayWarning)
            leeway.estimate(ship, ship_frame)

    ticks, elapsed = ticks_during(work)
    # A thread that could not run while Rust held the GIL would tick only
    # before and after; it ticks throughout instead.
    assert ticks > 0.3 * elapsed / 0.0011, (ticks, elapsed)


def thruster_data(n: int = 1200) -> pd.DataFrame:
    """The fixture `tests/models/thruster.som` (dead times of 10 and 3
    samples) simulated on held levels of either sign, measured with noise."""
    rng = np.random.default_rng(5)

    def telegraph(scale: float) -> np.ndarray:
        out: list[float] = []
        while len(out) < n:
            out += [scale * rng.normal()] * int(rng.integers(5, 61))
        return np.array(out[:n])

    model = leeway.Model.load(ROOT / "tests/models/thruster.som")
    inputs = pd.DataFrame({"time": np.arange(n) * 0.1, "tau_x": telegraph(20.0), "tau_n": telegraph(10.0)})
    truth = {"X_u": -0.2, "X_uu": -0.05, "X_tau": 0.05, "N_r": -0.3, "N_tau": 0.02}
    return leeway.simulate(model, truth, inputs, x0={"u": 0.0, "r": 0.0}, noise={"u": 0.02, "r": 0.005}, seed=1)


def test_scan_delay_finds_the_dead_time_as_the_cli_does() -> None:
    model = leeway.Model.load(ROOT / "tests/models/thruster.som")
    data = thruster_data()
    # The simulation starts at the longest dead time: 10 samples, 1 s in.
    assert len(data) == 1200 - 10 and data["time"].iloc[0] == pytest.approx(1.0)
    est = leeway.estimate(model, data, scan_delay="tau_x=0..15")
    assert est.delay_scan is not None
    assert est.delay_scan["samples"] == 10 and est.delay_scan["by"] == "fit"
    assert [p["samples"] for p in est.delay_scan["curve"]] == list(range(16))
    assert est.theta["X_tau"] == pytest.approx(0.05, rel=0.05)
    assert est.diagnostics["dropped_at_start"][0]["equations"] == 11
    assert leeway.estimate(model, data).delay_scan is None
    with pytest.raises(leeway.OptionError, match="scan_delay"):
        leeway.estimate(model, data, scan_delay="tau_x")
