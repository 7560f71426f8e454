"""What Python hands over is read exactly or refused, located:
no datetime, duration, complex, boolean, text or categorical value column is
coerced to numbers; a datetime or duration time column is read as seconds
since its first stamp (the Parquet reader's rule), so that it gives the
float-seconds estimate with or without a model `step`; missing values
(pd.NA, None, NaT), integers beyond ±2⁵³ and missing experiment labels are
errors at their row; a Series or a column MultiIndex is refused with a
hint. A time index (DatetimeIndex, TimedeltaIndex, or named as the time
column) is read as the time column; any other index that is not positions,
on a frame without a time column, is refused rather than ignored."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pandas as pd
import pytest

import leeway
from conftest import SHIP


@pytest.fixture(scope="module")
def ship() -> leeway.Model:
    return leeway.Model.load(SHIP)


@pytest.fixture(scope="module")
def ship_unstepped() -> leeway.Model:
    """The ship without `step`: its sample time comes from the time column."""
    source = SHIP.read_text()
    line = "    step 1.0                  // sample time h; der x = f gives x+ = x + h f\n"
    assert line in source
    return leeway.Model.from_str(source.replace(line, ""), file="ship-unstepped.som")


def quiet_estimate(model: leeway.Model, data, **options) -> leeway.Estimate:  # type: ignore[no-untyped-def]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", leeway.LeewayWarning)
        return leeway.estimate(model, data, **options)


def refused(model: leeway.Model, frame, *, column: str | None = None, row: int | None = None,
            name: str = "data", match: str | None = None) -> leeway.DataError:  # type: ignore[no-untyped-def]
    with pytest.raises(leeway.DataError) as e:
        quiet_estimate(model, frame if name == "data" else {name: frame})
    err = e.value
    assert err.location is not None and err.location.startswith(name), err.location
    if column is not None:
        assert f"column `{column}`" in err.location, err.location
    if row is not None:
        assert f"row {row}," in err.location, err.location
    if match is not None:
        assert match in str(err), str(err)
    assert err.hint, err
    return err


@pytest.mark.parametrize("make, match", [
    (lambda s: pd.to_datetime(s, unit="s"), "date-times"),
    (lambda s: pd.to_datetime(s, unit="s").dt.tz_localize("Europe/Oslo"), "date-times"),
    (lambda s: pd.to_timedelta(s, unit="s"), "durations"),
    (lambda s: s + 1j, "complex"),
    (lambda s: s > s.mean(), "boolean"),
    (lambda s: s.map(str), "text"),
    (lambda s: s.map(str).astype(object), "Python objects"),
    (lambda s: s.astype("category"), "categorical"),
    (lambda s: s.map(lambda v: f"{v:.3f}").astype("category"), "categorical"),
])
def test_a_value_column_that_is_not_numbers_is_refused(ship, ship_frame, make, match) -> None:  # type: ignore[no-untyped-def]
    frame = ship_frame.copy()
    frame["tau1"] = make(frame["tau1"])
    err = refused(ship, frame, column="tau1", name="run7", match=match)
    assert err.code == "data"


def test_numeric_strings_are_refused_not_parsed(ship, ship_frame) -> None:  # type: ignore[no-untyped-def]
    frame = ship_frame.copy()
    frame["u"] = frame["u"].map(repr)  # "5.0123…": exactly the numbers, as text
    err = refused(ship, frame, column="u", match="text")
    assert "pd.to_numeric" in (err.hint or "")


@pytest.mark.parametrize("unit", ["s", "ms", "us", "ns"])
def test_a_datetime_time_column_gives_the_float_seconds_estimate(ship, ship_unstepped, ship_frame, unit) -> None:  # type: ignore[no-untyped-def]
    epoch = np.datetime64("2024-03-01T12:00:00", unit)
    for model in (ship, ship_unstepped):
        reference = quiet_estimate(model, ship_frame).to_json()
        for stamps in (
            epoch + (ship_frame["time"].to_numpy() * {"s": 1, "ms": 1e3, "us": 1e6, "ns": 1e9}[unit]).astype(np.int64),
        ):
            naive = ship_frame.assign(time=pd.Series(stamps))
            aware = naive.assign(time=naive["time"].dt.tz_localize("America/New_York"))
            span = naive.assign(time=naive["time"] - naive["time"].iloc[0] + pd.Timedelta(hours=5))
            for frame in (naive, aware, span):
                assert quiet_estimate(model, frame).to_json() == reference, (model.file, unit, frame["time"].dtype)


def test_datetime_time_from_arrow_is_seconds_too(ship_unstepped, ship_frame) -> None:  # type: ignore[no-untyped-def]
    import pyarrow as pa

    stamps = pd.Timestamp("2025-01-01") + pd.to_timedelta(ship_frame["time"], unit="s")
    table = pa.Table.from_pandas(ship_frame.assign(time=stamps), preserve_index=False)
    reference = quiet_estimate(ship_unstepped, ship_frame)
    ours = quiet_estimate(ship_unstepped, table)
    assert ours.to_json() == reference.to_json()
    x_tau = ours.params.loc["X_tau", "estimate"]
    assert 0.01 < x_tau < 0.03, x_tau  # not 2e-8: the stamps are seconds, not microseconds


def test_a_missing_time_stamp_is_located(ship, ship_frame) -> None:  # type: ignore[no-untyped-def]
    frame = ship_frame.assign(time=pd.Timestamp("2025-01-01") + pd.to_timedelta(ship_frame["time"], unit="s"))
    frame.loc[12, "time"] = pd.NaT
    refused(ship, frame, column="time", row=12, match="missing")


@pytest.mark.parametrize("dtype", ["Float64", "Int64"])
def test_a_nullable_na_is_an_error_at_its_row(ship, ship_frame, dtype) -> None:  # type: ignore[no-untyped-def]
    frame = ship_frame.copy()
    column = "tau2"
    values = frame[column].round() if dtype == "Int64" else frame[column]
    frame[column] = values.astype(dtype)
    frame.loc[33, column] = pd.NA
    refused(ship, frame, column=column, row=33, name="logged", match="missing")


def test_nullable_numbers_without_na_are_read_exactly(ship, ship_frame) -> None:  # type: ignore[no-untyped-def]
    import pyarrow as pa

    reference = quiet_estimate(ship, ship_frame).to_json()
    nullable = ship_frame.astype({c: "Float64" for c in ship_frame.columns})
    arrow = ship_frame.astype({c: pd.ArrowDtype(pa.float64()) for c in ship_frame.columns})
    assert quiet_estimate(ship, nullable).to_json() == reference
    assert quiet_estimate(ship, arrow).to_json() == reference
    # Integers are read as the floats they are: time as int64, Int64 and uint32.
    for dtype in ("int64", "Int64", "uint32", "uint64"):
        ints = ship_frame.assign(time=ship_frame["time"].astype(dtype))
        assert quiet_estimate(ship, ints).to_json() == reference, dtype


@pytest.mark.parametrize("value, dtype", [(2**53 + 1, "int64"), (-(2**53) - 1, "int64"), (2**64 - 40, "uint64"),
                                          (2**53 + 1, "Int64")])
def test_integers_beyond_2_53_are_refused(ship, ship_frame, value, dtype) -> None:  # type: ignore[no-untyped-def]
    frame = ship_frame.copy()
    frame["tau3"] = frame["tau3"].round().astype("int64").astype(dtype)
    frame["tau3"] = frame["tau3"].astype(object).where(frame.index != 9, value).astype(dtype)
    refused(ship, frame, column="tau3", row=9, match="2⁵³")


def test_exactly_2_53_is_accepted_as_a_number(ship, ship_frame) -> None:  # type: ignore[no-untyped-def]
    frame = ship_frame.copy()
    frame["tau1"] = np.int64(2**53)
    # Read (as the Parquet reader reads it); the estimate then refuses or
    # warns about a constant input on its own terms, not here.
    try:
        quiet_estimate(ship, frame, method="ls")
    except leeway.LeewayError as e:
        assert "2⁵³" not in str(e)


@pytest.mark.parametrize("missing", [np.nan, None])
def test_a_missing_experiment_label_is_located(ship, ship_frame, missing) -> None:  # type: ignore[no-untyped-def]
    frame = ship_frame.assign(experiment=["a"] * 700 + ["b"] * (len(ship_frame) - 700))
    frame["experiment"] = frame["experiment"].astype(object)
    frame.loc[701, "experiment"] = missing
    refused(ship, frame, column="experiment", row=701, name="fleet", match="missing experiment label")


def test_a_series_is_refused_with_a_hint(ship, ship_frame) -> None:  # type: ignore[no-untyped-def]
    err = refused(ship, ship_frame["u"], match="Series")
    assert "to_frame" in (err.hint or "")


def test_a_column_multiindex_is_refused_with_a_hint(ship, ship_frame) -> None:  # type: ignore[no-untyped-def]
    frame = ship_frame.copy()
    frame.columns = pd.MultiIndex.from_tuples([("ship", c) for c in frame.columns])
    err = refused(ship, frame, match="MultiIndex")
    assert "columns" in (err.hint or "")


@pytest.mark.parametrize("index", ["named", "datetime", "datetime-tz", "timedelta"])
def test_time_as_the_index_is_read_as_the_time_column(ship, ship_frame, index) -> None:  # type: ignore[no-untyped-def]
    frame = ship_frame.set_index("time")
    seconds = pd.to_timedelta(frame.index, unit="s")
    if index == "datetime":
        frame.index = pd.DatetimeIndex(pd.Timestamp("2025-01-01") + seconds, name="stamp")
    elif index == "datetime-tz":
        frame.index = pd.DatetimeIndex(pd.Timestamp("2025-01-01", tz="Europe/Oslo") + seconds)
    elif index == "timedelta":
        frame.index = pd.TimedeltaIndex(seconds, name="elapsed")
    assert "time" not in frame.columns
    # The same estimate as with the column (times from the first stamp).
    assert quiet_estimate(ship, frame).to_json() == quiet_estimate(ship, ship_frame).to_json()


def test_an_index_that_is_not_positions_and_no_time_column_is_refused(ship, ship_frame) -> None:  # type: ignore[no-untyped-def]
    # The reported case: time as an unnamed index, sampled at 7 s, while
    # the model's step is 1 s — once read as if the index were positions.
    frame = ship_frame.drop(columns="time")
    frame.index = pd.Index(ship_frame["time"].to_numpy() * 7.0)
    err = refused(ship, frame, match="index that is not positions")
    assert "reset_index(drop=True)" in (err.hint or "") and "rename_axis('time')" in (err.hint or "")
    # A filtered frame (gaps in an integer index) says something too.
    gappy = ship_frame.drop(columns="time").iloc[::2]
    refused(ship, gappy, match="Index")
    # Positions are fine: a default RangeIndex, or a slice of one.
    quiet_estimate(ship, ship_frame.drop(columns="time"))
    quiet_estimate(ship, ship_frame.drop(columns="time").iloc[10:])


def test_a_multiindex_without_a_time_column_is_refused(ship, ship_frame) -> None:  # type: ignore[no-untyped-def]
    frame = ship_frame.assign(run="a").set_index(["run", "time"])
    err = refused(ship, frame, match="MultiIndex")
    assert "reset_index()" in (err.hint or "")


def test_simulate_and_validate_refuse_the_same_columns(ship, ship_frame) -> None:  # type: ignore[no-untyped-def]
    frame = ship_frame.copy()
    frame["tau1"] = frame["tau1"] > 50
    theta = ship.nominal
    with pytest.raises(leeway.DataError) as e:
        leeway.simulate(ship, theta, frame)
    assert e.value.location == "inputs: column `tau1`"
    with pytest.raises(leeway.DataError) as e:
        leeway.validate(ship, theta, {"held": frame})
    assert e.value.location == "held: column `tau1`"


def test_a_datetime_time_column_simulates_from_zero(ship, ship_frame) -> None:  # type: ignore[no-untyped-def]
    theta = dict(json.loads(json.dumps(ship.nominal)))
    frame = ship_frame.head(50)
    stamped = frame.assign(time=pd.Timestamp("2025-01-01", tz="UTC") + pd.to_timedelta(frame["time"], unit="s"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", leeway.LeewayWarning)
        a = leeway.simulate(ship, theta, frame)
        b = leeway.simulate(ship, theta, stamped)
    assert b["time"].iloc[0] == 0.0
    assert (a.drop(columns="time").to_numpy() == b.drop(columns="time").to_numpy()).all()


@pytest.mark.parametrize("unit", ["ms", "us", "ns"])
def test_a_datetime_time_column_is_read_as_the_parquet_reader_reads_it(ship, ship_frame, tmp_path, unit) -> None:  # type: ignore[no-untyped-def]
    from conftest import run_leeway

    stamps = (pd.Timestamp("2024-06-30 23:59:58.123", tz="UTC")
              + pd.to_timedelta(ship_frame["time"], unit="s")).astype(f"datetime64[{unit}, UTC]")
    frame = ship_frame.assign(time=stamps)
    path = tmp_path / "stamped.parquet"
    frame.to_parquet(path)
    o = run_leeway("estimate", str(SHIP), "--data", str(path), "--json")
    cli = json.loads(o.stdout)
    assert cli["errors"] == [], o.stdout
    ours = json.loads(quiet_estimate(ship, {"stamped": frame}).to_json())
    drop = ("file", "data", "data_files")
    assert json.dumps({k: v for k, v in ours.items() if k not in drop}) == json.dumps(
        {k: v for k, v in cli.items() if k not in drop})


def test_dev_zero_as_a_model_or_a_plan_is_an_error_in_bounded_memory() -> None:
    # Read whole, a file without end was all memory; now 1 MiB and a
    # located error, as the CLI.
    with pytest.raises(leeway.ModelError, match="larger than 1 MiB") as e:
        leeway.Model.load("/dev/zero")
    assert e.value.location == "/dev/zero"
    boat = leeway.Model.from_str("model M { state u\ninput t\nder u = a*u + b*t\nnominal { a = -1, b = 1 } }")
    with pytest.raises(leeway.PlanError, match="larger than 1 MiB"):
        leeway.design(boat, "/dev/zero")
