"""Options are type-checked: bools are not numbers, numbers are
not text, signs and ranges are checked, nominal values and θ are finite
numbers — each an `OptionError` naming the option, with a hint, never a
bare TypeError from the native half. numpy scalars are numbers."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest

import leeway
import leeway.mapreduce as mr
from conftest import SHIP


@pytest.fixture(scope="module")
def ship() -> leeway.Model:
    return leeway.Model.load(SHIP)


BAD_OPTIONS = [
    ("max_refinements", True), ("max_refinements", -1), ("max_refinements", 2.0), ("max_refinements", "8"),
    ("max_refinements", 10**30), ("lags", True), ("lags", "2"), ("lags", 0), ("lags", -3), ("lags", 1.5),
    ("lags", None), ("step", True), ("step", "0.1"), ("step", float("nan")), ("step", float("inf")),
    ("step", 1j), ("resample", False), ("resample", "1"), ("time_tolerance", None), ("time_tolerance", "0.05"),
    ("time_tolerance", np.bool_(True)), ("method", 3), ("method", None), ("centring", 1), ("combine", b"summed"),
    ("aggregate", 1), ("aggregate", "yes"), ("strict", None), ("runaway_guard", 0), ("instruments", ["simulated"]),
    ("initial", None), ("refine_subsample", 0), ("refine_subsample", 1.5), ("refine_subsample", "0.1"),
    ("refine_subsample", True), ("refine_subsample", float("nan")),
]


@pytest.mark.parametrize("option, value", BAD_OPTIONS)
def test_a_wrong_option_is_an_option_error_naming_it(ship, ship_frame, option, value) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(leeway.OptionError) as e:
        leeway.estimate(ship, ship_frame, **{option: value})
    assert e.value.code == "invalid-option"
    assert option in e.value.message, e.value.message
    assert e.value.hint
    # The same check through the engine-neutral options (and so leeway.dask).
    with pytest.raises(leeway.OptionError) as e:
        mr.options(ship, **{option: value})
    assert option in e.value.message


def test_numpy_scalars_are_numbers(ship, ship_frame) -> None:  # type: ignore[no-untyped-def]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", leeway.LeewayWarning)
        plain = leeway.estimate(ship, ship_frame, method="ls", lags=2, max_refinements=3, step=1.0,
                                time_tolerance=0.05, aggregate=False)
        numpy = leeway.estimate(ship, ship_frame, method=np.str_("ls"), lags=np.int64(2),
                                max_refinements=np.int32(3), step=np.float64(1.0),
                                time_tolerance=np.float32(0.05).item(), aggregate=np.bool_(False),
                                nominal={p: np.float64(v) for p, v in ship.nominal.items()})
    assert numpy.to_json() == plain.to_json()


@pytest.mark.parametrize("value", [float("nan"), float("inf"), -float("inf"), True, "0.1", None, 1j, [1.0]])
def test_a_bad_nominal_value_names_the_parameter(ship, ship_frame, value) -> None:  # type: ignore[no-untyped-def]
    nominal = {**ship.nominal, "Y_ur": value}
    with pytest.raises(leeway.OptionError) as e:
        leeway.estimate(ship, ship_frame, nominal=nominal)
    assert e.value.code == "invalid-nominal"
    assert "Y_ur" in e.value.message


def test_nominal_must_be_a_mapping(ship, ship_frame) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(leeway.OptionError) as e:
        leeway.estimate(ship, ship_frame, nominal=list(ship.nominal.values()))
    assert e.value.code == "invalid-nominal"


@pytest.mark.parametrize("value", [float("nan"), float("inf"), True, "1", None])
def test_a_bad_theta_value_names_the_parameter(ship, ship_frame, value) -> None:  # type: ignore[no-untyped-def]
    theta = {**ship.nominal, "N_r": value}
    with pytest.raises(leeway.OptionError) as e:
        leeway.simulate(ship, theta, ship_frame.head(20))
    assert e.value.code == "invalid-params" and "N_r" in e.value.message
    with pytest.raises(leeway.OptionError) as e:
        leeway.validate(ship, {"mine": theta}, ship_frame)
    assert e.value.code == "invalid-params" and "N_r" in e.value.message
    values = [theta[p] for p in ship.parameters]
    with pytest.raises(leeway.OptionError) as e:
        leeway.simulate(ship, values, ship_frame.head(20))
    assert "N_r" in e.value.message


@pytest.mark.parametrize("what", ["x0", "disturbances"])
@pytest.mark.parametrize("value", [float("nan"), float("inf"), True, "5", None])
def test_bad_initial_values_and_disturbances_are_option_errors(ship, ship_frame, what, value) -> None:  # type: ignore[no-untyped-def]
    key = "u" if what == "x0" else "current.north"
    with pytest.raises(leeway.OptionError) as e:
        leeway.simulate(ship, ship.nominal, ship_frame.head(20), **{what: {key: value}})
    assert key in e.value.message and e.value.code == "invalid-option"


@pytest.mark.parametrize("option, value", [("step", "1"), ("step", True), ("time_tolerance", None),
                                           ("resample", float("nan")), ("disturbances", [0.2])])
def test_validate_checks_its_options(ship, ship_frame, option, value) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(leeway.OptionError) as e:
        leeway.validate(ship, ship.nominal, ship_frame, **{option: value})
    assert option in e.value.message


def test_simulate_checks_its_step(ship, ship_frame) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(leeway.OptionError, match="step"):
        leeway.simulate(ship, ship.nominal, ship_frame.head(20), step=True)


def test_options_edited_on_their_way_are_checked_again(ship, ship_frame) -> None:  # type: ignore[no-untyped-def]
    options = mr.options(ship, method="ls")
    with pytest.raises(leeway.OptionError, match="lags"):
        mr.open_frame(ship, ship_frame, {**options, "lags": True})
    with pytest.raises(leeway.OptionError, match="nominal"):
        mr.open_frame(ship, ship_frame, {**options, "nominal": [float("nan")] * len(ship.parameters)})
    with pytest.raises(leeway.OptionError, match="mapreduce.options"):
        mr.open_frame(ship, ship_frame, {"method": "ls"})
    with pytest.raises(leeway.OptionError, match="not a path"):
        mr.open_file(ship, 3, options)  # type: ignore[arg-type]
    assert pd.DataFrame is not None


def test_refining_on_a_subsample_is_reported_and_lands_near_the_plain_estimate(ship, tmp_path) -> None:  # type: ignore[no-untyped-def]
    from conftest import ship_data

    frame = ship_data(tmp_path, 12000, 10.0, 11)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", leeway.LeewayWarning)
        plain = leeway.estimate(ship, frame, aggregate=True)
        first = leeway.estimate(ship, frame, aggregate=True, refine_subsample=np.float64(0.25))
    sub = first.diagnostics["subsample"]
    assert sub == {"fraction": 0.25, "samples": 3000, "refinements": sub["refinements"], "used": True}
    assert "subsample" not in plain.diagnostics
    assert first.diagnostics["converged"]
    for name, se in plain.document["std_errors"].items():
        if se is not None:
            assert abs(first.document["estimates"][name] - plain.document["estimates"][name]) <= 0.01 * se, name
    assert any("refined first on 0.25 of every experiment" in line for line in first.summary().diagnostics)
