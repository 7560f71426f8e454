"""Data handed to the native half: DataFrames (or Arrow/polars tables)
turned into contiguous float64 columns of the model, with nothing coerced
silently. Date-times and durations in the time column (or a time index)
are read as seconds since the first stamp, as the Parquet reader reads
TIMESTAMP columns; every other column that is not of numbers is refused,
located, with how to convert it."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, Union

import numpy as np
import pandas as pd

from .errors import DataError

if TYPE_CHECKING:
    from ._api import Model

Frame = Any  # a pandas DataFrame, or anything with ``to_pandas()`` / ``__arrow_c_stream__``
Data = Union[Frame, Sequence[Frame], Mapping[str, Frame]]


def _to_pandas(frame: Any, name: str) -> pd.DataFrame:
    if isinstance(frame, pd.DataFrame):
        result = frame
    elif isinstance(frame, pd.Series):
        raise DataError(
            f"a pandas Series (`{frame.name}`) is not a DataFrame",
            code="data",
            location=name,
            hint="pass a DataFrame with a column per signal: series.to_frame(), or pd.DataFrame({...})",
        )
    elif hasattr(frame, "to_pandas") or hasattr(frame, "__arrow_c_stream__"):  # pyarrow, polars
        try:
            if hasattr(frame, "to_pandas"):
                result = frame.to_pandas()
            else:
                import pyarrow as pa

                result = pa.table(frame).to_pandas()
        except Exception as e:  # whatever the library raises, located here
            raise DataError(
                f"the {type(frame).__name__} could not be converted to a DataFrame: {type(e).__name__}: {e}",
                code="data",
                location=name,
                hint="pass a pandas DataFrame of numeric columns",
            ) from None
        if not isinstance(result, pd.DataFrame):
            raise DataError(
                f"{type(frame).__name__}.to_pandas() gave a {type(result).__name__}, not a DataFrame",
                code="data",
                location=name,
                hint="pass a pandas DataFrame, a list or dict of them, or an Arrow/polars table",
            )
    else:
        raise DataError(
            f"{type(frame).__name__} is not a DataFrame",
            code="data",
            location=name,
            hint="pass a pandas DataFrame, a list or dict of them, or an Arrow/polars table",
        )
    if isinstance(result.columns, pd.MultiIndex):
        raise DataError(
            f"the columns are a MultiIndex of {result.columns.nlevels} levels",
            code="data",
            location=name,
            hint="give the frame one level of column names, e.g. "
            "df.columns = ['_'.join(map(str, c)) for c in df.columns], or select a level",
        )
    return result


def _frames(data: Data) -> list[tuple[str, Any]]:
    if isinstance(data, Mapping):
        return [(str(k), v) for k, v in data.items()]
    if isinstance(data, Sequence) and not isinstance(data, (str, bytes)):
        return [(f"data[{i}]", v) for i, v in enumerate(data)]
    return [("data", data)]


# The largest integer every smaller one of which a float64 holds exactly
# (2⁵³): a larger integer is refused, as the Parquet reader refuses it.
_EXACT = 1 << 53

# Units per second of numpy's datetime64/timedelta64 resolutions.
_PER_SECOND = {"s": 1, "ms": 1_000, "us": 1_000_000, "ns": 1_000_000_000}


def _row(name: str, row: int, column: str) -> str:
    """A location as the runtime writes it (positional row, from 0, as ``iloc``)."""
    return f"{name}: row {row}, column `{column}`"


def _refuse(name: str, column: str, what: str, hint: str) -> DataError:
    return DataError(
        f"column `{column}` is not numeric: {what}; leeway reads numbers only and converts nothing silently",
        code="data",
        location=f"{name}: column `{column}`",
        hint=hint,
    )


def _missing(
    name: str,
    series: pd.Series,
    column: str,
    what: str = "missing value",
    hint: str = "leeway does not drop or fill samples: repair or remove the row (every column of every row must hold a number)",
) -> None:
    """A missing value (``pd.NA``, ``None``, ``NaT``) is an error at its row."""
    na = np.asarray(series.isna(), dtype=bool)
    if na.any():
        row = int(np.flatnonzero(na)[0])
        raise DataError(
            f"{what} ({series.iloc[row]!r}) in column `{column}`",
            code="data",
            location=_row(name, row, column),
            hint=hint,
        )


def _stamps(name: str, series: pd.Series, column: str) -> np.ndarray:
    """A datetime64 (naive or tz-aware) or timedelta64 time column as float
    seconds since its first stamp: the differences taken in integers of the
    column's own unit, then divided once by its units per second (the rule
    of the Parquet reader for TIMESTAMP columns), so large epoch values carry
    no rounding into the times."""
    _missing(name, series, column)
    if pd.api.types.is_timedelta64_dtype(series.dtype):
        index: pd.Index = pd.TimedeltaIndex(series)
    else:
        index = pd.DatetimeIndex(series)  # tz-aware: the UTC instants
    unit = str(index.unit)
    ticks = np.asarray(index.asi8, dtype=np.int64)
    if len(ticks) == 0:
        return np.zeros(0)
    lo, hi, first = int(ticks.min()), int(ticks.max()), int(ticks[0])
    if max(hi - first, first - lo) >= 1 << 63:
        raise _refuse(name, column, f"time stamps spanning {hi - lo} {unit}, beyond 64-bit integers", "split the record")
    seconds: np.ndarray = (ticks - ticks[0]).astype(np.float64) / float(_PER_SECOND[unit])
    return seconds


def _integers(name: str, values: np.ndarray, column: str) -> np.ndarray:
    """Integers as float64, refused beyond ±2⁵³ (where a float64 would round them)."""
    if values.dtype.itemsize >= 8 and len(values):
        if values.dtype.kind == "u":
            beyond = values > np.uint64(_EXACT)
        else:
            beyond = (values > _EXACT) | (values < -_EXACT)
        if beyond.any():
            row = int(np.flatnonzero(beyond)[0])
            raise DataError(
                f"{values[row]} is beyond ±2⁵³ (9007199254740992): a 64-bit float cannot hold it exactly",
                code="data",
                location=_row(name, row, column),
                hint="leeway reads every value as a 64-bit float and will not round one silently: "
                "convert the column to float yourself, or to a unit that keeps it within ±2⁵³",
            )
    return values.astype(np.float64)


def _no_stamps_in_unit(name: str, series: pd.Series, column: str, unit: str) -> None:
    """Date-times and durations are read in seconds: a time column the model
    declares in another unit must hold numbers in that unit."""
    types = pd.api.types
    if types.is_datetime64_any_dtype(series.dtype) or types.is_timedelta64_dtype(series.dtype):
        raise _refuse(
            name,
            column,
            f"date-times or durations ({series.dtype}), read in seconds, while the model declares `time` in {unit}",
            "drop the time unit from the model's data { } block, or give the time as numbers in that unit",
        )


def _column(name: str, series: pd.Series, column: str, is_time: bool) -> np.ndarray:
    """One model column as float64: floats as they are (a view where the
    column already is contiguous float64), integers within ±2⁵³, a time
    column of datetimes or durations as seconds since its first stamp;
    anything else refused, located, with how to convert it."""
    dtype = series.dtype
    types = pd.api.types
    if isinstance(dtype, pd.CategoricalDtype):
        raise _refuse(name, column, "categorical", f"convert it to numbers yourself, e.g. df[{column!r}].astype(float)")
    if types.is_bool_dtype(dtype):
        raise _refuse(name, column, f"boolean ({dtype})", f"convert it to numbers yourself: df[{column!r}].astype(float)")
    if types.is_datetime64_any_dtype(dtype) or types.is_timedelta64_dtype(dtype):
        if is_time:
            return _stamps(name, series, column)
        kind = "durations" if types.is_timedelta64_dtype(dtype) else "date-times"
        hint = (
            f"convert to seconds as float: df[{column!r}].dt.total_seconds()"
            if kind == "durations"
            else f"convert to seconds as float: (t - t.iloc[0]).dt.total_seconds() with t = df[{column!r}]"
        )
        raise _refuse(name, column, f"{kind} ({dtype})", hint)
    if types.is_complex_dtype(dtype):
        raise _refuse(name, column, f"complex ({dtype})", f"choose the real number you mean: df[{column!r}].to_numpy().real, or np.abs(...)")
    if types.is_integer_dtype(dtype):
        if isinstance(dtype, np.dtype):
            return _integers(name, series.to_numpy(), column)
        _missing(name, series, column)
        return _integers(name, series.to_numpy(dtype=dtype.numpy_dtype), column)
    if types.is_float_dtype(dtype):
        if not isinstance(dtype, np.dtype):
            _missing(name, series, column)
        return np.ascontiguousarray(series.to_numpy(dtype=np.float64, copy=False))
    if types.is_string_dtype(dtype) or dtype == object:
        what = "text" if types.is_string_dtype(dtype) and dtype != object else "Python objects"
        return_hint = f"convert it to numbers yourself, e.g. pd.to_numeric(df[{column!r}])"
        raise _refuse(name, column, f"{what} ({dtype})", return_hint)
    raise _refuse(name, column, f"{dtype}", f"convert it to float64 yourself, e.g. pd.to_numeric(df[{column!r}])")


def _labels(name: str, frame: pd.DataFrame, column: str) -> tuple[np.ndarray, list[str]]:
    """The experiment labels coded, as ``pandas.factorize`` codes them (an
    int64 per row and the distinct labels as text: no string per row); a
    missing label is an error at its row."""
    series = frame[column]
    if isinstance(series, pd.DataFrame):  # a repeated name is refused before
        raise DataError(f"column `{column}` appears more than once", code="data", location=name)
    _missing(name, series, column, "missing experiment label", f"give every row the label of its experiment in `{column}`")
    codes, uniques = pd.factorize(series, sort=False)
    return np.ascontiguousarray(codes, dtype=np.int64), [str(v) for v in uniques.tolist()]


def _is_default_index(index: pd.Index) -> bool:
    """A RangeIndex of step 1 and no name (``reset_index(drop=True)``, or a
    slice of one): positions, which say nothing about time."""
    return isinstance(index, pd.RangeIndex) and index.step == 1 and index.name is None


def _time_from_index(name: str, frame: pd.DataFrame, time_column: str) -> pd.DataFrame:
    """The frame with its index as the time column when the index holds the
    time stamps (a DatetimeIndex or TimedeltaIndex, or an index named as the
    time column) and the frame has no time column; a frame whose index says
    something else (not a default RangeIndex) and that has no time column is
    refused rather than read as if the index were positions."""
    if time_column in frame.columns:
        return frame
    index = frame.index
    if isinstance(index, pd.MultiIndex):
        raise DataError(
            f"the frame has a MultiIndex ({', '.join(map(str, index.names))}) and no column `{time_column}`",
            code="data",
            location=name,
            hint="make the index columns: df.reset_index(); name the time column "
            f"`{time_column}` (or map it in the model's data {{ }} block)",
        )
    if index.name == time_column or isinstance(index, (pd.DatetimeIndex, pd.TimedeltaIndex)):
        return frame.rename_axis(time_column).reset_index()
    if not _is_default_index(index):
        # The first label as the user wrote it (a numpy scalar as a number).
        first = index[0].item() if len(index) and hasattr(index[0], "item") else (index[0] if len(index) else None)
        raise DataError(
            f"the frame has no column `{time_column}` and an index that is not positions "
            f"({type(index).__name__}{f' named {index.name!r}' if index.name is not None else ''}, "
            f"{f'first {first!r}' if len(index) else 'empty'}); leeway would ignore it and time the samples by the model's step",
            code="data",
            location=name,
            hint=f"if the index is the time, name it: df.rename_axis({time_column!r}); "
            "else drop it: df.reset_index(drop=True)",
        )
    return frame


def _handover(
    model: Model, data: Data
) -> list[tuple[str, list[tuple[str, np.ndarray]], tuple[np.ndarray, list[str]] | None]]:
    """The model's columns of every frame as contiguous float64 arrays (a
    view, not a copy, where the column already is one) and the experiment
    labels coded (an int64 per row, the distinct labels as text). Nothing is coerced silently: a column that is not of
    numbers (dates, durations, booleans, complex numbers, text, categories)
    is refused, except the time column's date-times and durations, read as
    seconds since the first stamp."""
    out = []
    experiment_column = model._core.experiment_column
    time_column = model.columns[0]
    frames = _frames(data)
    if not frames:
        raise DataError(
            f"no experiment given (an empty {type(data).__name__})",
            code="no-data",
            hint="pass a DataFrame, or a list or dict of them",
        )
    for name, raw in frames:
        frame = _to_pandas(raw, name)
        if not frame.columns.is_unique:
            twice = sorted({str(c) for c in frame.columns[frame.columns.duplicated()]})
            raise DataError(
                f"column `{twice[0]}` appears more than once",
                code="data",
                location=name,
                hint="give every column one name",
            )
        frame = _time_from_index(name, frame, time_column)
        columns = []
        for column in model.columns:
            if column not in frame.columns:
                continue  # the loader names what is missing, as for a file
            is_time = column == time_column
            if is_time and model._core.time_unit not in (None, "s"):
                _no_stamps_in_unit(name, frame[column], column, model._core.time_unit)
            values = _column(name, frame[column], column, is_time)
            columns.append((column, values))
        labels = None
        if experiment_column in frame.columns:
            labels = _labels(name, frame, experiment_column)
        out.append((name, columns, labels))
    return out


