"""A seeded fuzzer of the Python API's inputs and options: bad
frames (every dtype pandas, numpy and Arrow offer, missing values, huge
integers, odd shapes and containers) and bad options (bools, text, NaN,
signs, containers, numpy scalars) through `estimate`, `simulate`,
`validate` and `leeway.mapreduce`. Every call either answers or raises a
class of `leeway.errors` — never TypeError, AttributeError, a pyarrow
error or `pyo3_runtime.PanicException` — and a `DataError` is located.

The CI run is a few hundred cases (a few seconds); set
`LEEWAY_FUZZ_CASES=N` (and `LEEWAY_FUZZ_SEED`) for a longer campaign; run
with `-s` to see its counts."""

from __future__ import annotations

import collections
import os
import random
import tempfile
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest

import leeway
import leeway.mapreduce as mr
from conftest import SHIP, ship_data

CASES = int(os.environ.get("LEEWAY_FUZZ_CASES", "600"))
SEED = int(os.environ.get("LEEWAY_FUZZ_SEED", "2207"))

WEIRD = [
    True, False, np.bool_(True), -1, 0, 1, 2, 3, 2.5, -0.5, 1e-9, 1e308, -1e308, float("nan"), float("inf"),
    -float("inf"), "2", "0.1", "iv3", "", None, [], [1.0], {}, {"a": 1}, (1, 2), 1j, b"x", object(),
    np.int64(3), np.int32(-2), np.uint64(2**63), np.float64(0.1), np.float32(0.05), np.float64("nan"),
    10**30, -(10**30), 2**53 + 1, pd.NA, pd.NaT, pd.Timestamp("2025-01-01"), np.datetime64("2025-01-01"),
]

OPTIONS = ["method", "instruments", "initial", "centring", "combine", "nominal", "aggregate", "strict", "lags",
           "max_refinements", "runaway_guard", "refine_subsample", "step", "time_tolerance", "resample"]


def base_frame(rng: random.Random, n: int) -> pd.DataFrame:
    """A small frame of the ship's columns (numbers only; not a good
    experiment — the fuzzer is after the handover, not the estimate)."""
    g = np.random.default_rng(rng.randrange(2**32))
    k = np.arange(n)
    frame = pd.DataFrame({
        "time": k * 1.0,
        "u": 5 + g.normal(0, 0.1, n), "v": g.normal(0, 0.1, n), "r": g.normal(0, 0.01, n),
        "psi": np.cumsum(g.normal(0, 0.01, n)),
        "tau1": 50 + g.normal(0, 5, n), "tau2": 169 + g.normal(0, 10, n), "tau3": 235 + g.normal(0, 10, n),
        "wind_n": 1 + g.normal(0, 0.03, n), "wind_e": 1 + g.normal(0, 0.03, n),
    })
    return frame


_REAL: list[pd.DataFrame] = []


def real_frame() -> pd.DataFrame:
    """A steady turn of the ship simulated by the CLI (conftest), 800 samples."""
    if not _REAL:
        with tempfile.TemporaryDirectory() as tmp:
            _REAL.append(ship_data(Path(tmp), 800, 1.0, 11))
    return _REAL[0]


def mutate_column(rng: random.Random, frame: pd.DataFrame, column: str) -> pd.DataFrame:
    """The frame with one column changed in kind (a copy); a change pandas
    itself refuses (mutations stack) leaves the frame as it was."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return mutated(rng, frame.copy(), column)
    except Exception:  # noqa: BLE001 — the generator's own failure, not leeway's
        return frame


def mutated(rng: random.Random, frame: pd.DataFrame, column: str) -> pd.DataFrame:
    s = frame[column]
    n = len(frame)
    row = rng.randrange(n) if n else 0
    kind = rng.choice([
        "datetime", "datetime-tz", "timedelta", "complex", "bool", "boolean", "str", "object-str", "object-float",
        "category", "Float64-na", "Int64-na", "int64-big", "uint64-big", "uint64", "int8", "float16", "float32",
        "nan", "inf", "huge", "None-object", "mixed-object", "arrow-string", "arrow-bool", "arrow-int-null",
        "arrow-ts", "decimal", "period", "interval", "sparse", "bytes", "NaT",
    ])
    if kind == "datetime":
        frame[column] = pd.Timestamp("2024-01-01") + pd.to_timedelta(s, unit="s")
    elif kind == "datetime-tz":
        frame[column] = (pd.Timestamp("2024-01-01") + pd.to_timedelta(s, unit="s")).dt.tz_localize("UTC")
    elif kind == "timedelta":
        frame[column] = pd.to_timedelta(s, unit="s")
    elif kind == "complex":
        frame[column] = s + 1j * rng.random()
    elif kind == "bool":
        frame[column] = s > s.median()
    elif kind == "boolean":
        frame[column] = (s > s.median()).astype("boolean")
    elif kind == "str":
        frame[column] = s.map(repr)
    elif kind == "object-str":
        frame[column] = s.map(repr).astype(object)
    elif kind == "object-float":
        frame[column] = s.astype(object)
    elif kind == "category":
        frame[column] = s.round().astype("category")
    elif kind == "Float64-na":
        frame[column] = s.astype("Float64")
        frame.loc[row, column] = pd.NA
    elif kind == "Int64-na":
        frame[column] = s.round().astype("Int64")
        frame.loc[row, column] = pd.NA
    elif kind == "int64-big":
        values = s.round().astype("int64").to_numpy().copy()
        values[row] = rng.choice([2**53 + 1, -(2**53) - 7, 2**62])
        frame[column] = values
    elif kind == "uint64-big":
        values = s.abs().round().astype("uint64").to_numpy().copy()
        values[row] = 2**64 - 40
        frame[column] = values
    elif kind == "uint64":
        frame[column] = s.abs().round().astype("uint64")
    elif kind == "int8":
        frame[column] = s.round().clip(-100, 100).astype("int8")
    elif kind == "float16":
        frame[column] = s.astype("float16")
    elif kind == "float32":
        frame[column] = s.astype("float32")
    elif kind == "nan":
        frame.loc[row, column] = np.nan
    elif kind == "inf":
        frame.loc[row, column] = rng.choice([np.inf, -np.inf])
    elif kind == "huge":
        frame.loc[row, column] = rng.choice([1e308, -1e308, 1e300, 5e-324])
    elif kind == "None-object":
        frame[column] = s.astype(object)
        frame.loc[row, column] = None
    elif kind == "mixed-object":
        frame[column] = s.astype(object)
        frame.loc[row, column] = rng.choice(["x", b"y", [1], (2,), 3j])
    elif kind == "arrow-string":
        import pyarrow as pa

        frame[column] = s.map(repr).astype(pd.ArrowDtype(pa.string()))
    elif kind == "arrow-bool":
        import pyarrow as pa

        frame[column] = (s > 0).astype(pd.ArrowDtype(pa.bool_()))
    elif kind == "arrow-int-null":
        import pyarrow as pa

        frame[column] = s.round().astype("int64").astype(pd.ArrowDtype(pa.int64()))
        frame.loc[row, column] = None
    elif kind == "arrow-ts":
        import pyarrow as pa

        frame[column] = (pd.Timestamp("2024-01-01") + pd.to_timedelta(s.round(3), unit="s")).astype(
            pd.ArrowDtype(pa.timestamp("ms")))
    elif kind == "decimal":
        import decimal

        frame[column] = [decimal.Decimal(repr(v)) for v in s]
    elif kind == "period":
        frame[column] = pd.period_range("2024-01", periods=n, freq="D")
    elif kind == "interval":
        frame[column] = pd.arrays.IntervalArray.from_breaks(np.arange(n + 1.0))
    elif kind == "sparse":
        frame[column] = s.astype(pd.SparseDtype("float64", 0.0))
    elif kind == "bytes":
        frame[column] = s.map(lambda v: repr(v).encode())
    elif kind == "NaT":
        frame[column] = pd.Timestamp("2024-01-01") + pd.to_timedelta(s, unit="s")
        frame.loc[row, column] = pd.NaT
    return frame


def bad_data(rng: random.Random, model: leeway.Model) -> Any:
    n = rng.choice([0, 1, 3, 40, 120])
    frame = base_frame(rng, n)
    shape = rng.random()
    if shape < 0.55 and n:
        for _ in range(rng.choice([1, 1, 2])):
            frame = mutate_column(rng, frame, rng.choice(model.columns))
    elif shape < 0.62:
        frame = frame.assign(experiment=rng.choice([
            [rng.choice(["a", "b", None, np.nan, 1, 2.5]) for _ in range(n)],
            ["a"] * n,
            list(range(n)),
        ]))
    elif shape < 0.67:
        frame = frame.drop(columns=rng.choice(model.columns))
    elif shape < 0.70:
        frame = pd.concat([frame, frame[["u"]]], axis=1)
    elif shape < 0.73:
        frame.columns = pd.MultiIndex.from_tuples([("a", c) for c in frame.columns])
    elif shape < 0.76:
        return frame["u"]
    elif shape < 0.79:
        return frame.to_numpy()
    elif shape < 0.82:
        return frame.set_index("time")
    elif shape < 0.85:
        return rng.choice([None, 3, "frame.csv", b"x", [], {}, [None], {1: frame}, [frame, 3], {"a": "b"}])
    elif shape < 0.90:
        import pyarrow as pa

        source = mutate_column(rng, frame, rng.choice(model.columns)) if n else frame
        try:
            return pa.Table.from_pandas(source)
        except (TypeError, ValueError, pa.ArrowException):  # a frame Arrow cannot hold
            return pa.Table.from_pandas(frame)
    elif shape < 0.93:
        frame = frame.rename(columns={"time": 0})
    elif shape < 0.96:
        return [frame, mutate_column(rng, frame, rng.choice(model.columns)) if n else frame]
    return frame


def huge(v: Any) -> bool:
    """A finite float beyond 1e12 (an extreme nominal value, such as 1e300)."""
    return isinstance(v, float) and np.isfinite(v) and abs(v) > 1e12


def bad_options(rng: random.Random, model: leeway.Model, extreme: bool = False) -> dict[str, Any]:
    options: dict[str, Any] = {"method": "ls"}
    for _ in range(rng.choice([1, 1, 2])):
        key = rng.choice(OPTIONS)
        if key == "nominal":
            nominal: Any = dict(model.nominal)
            how = rng.random()
            if how < 0.6:
                nominal[rng.choice(model.parameters)] = rng.choice([v for v in WEIRD if extreme or not huge(v)])
            elif how < 0.8:
                nominal = rng.choice(WEIRD)
            else:
                nominal.pop(rng.choice(model.parameters))
            options[key] = nominal
        else:
            options[key] = rng.choice(WEIRD)
    return options


def bad_theta(rng: random.Random, model: leeway.Model) -> Any:
    theta: Any = dict(model.nominal)
    how = rng.random()
    if how < 0.5:
        theta[rng.choice(model.parameters)] = rng.choice(WEIRD)
    elif how < 0.7:
        theta = [*theta.values()][: rng.randrange(len(model.parameters) + 2)]
    elif how < 0.85:
        theta = rng.choice(WEIRD)
    return theta


def one_case(
    rng: random.Random, model: leeway.Model, good: pd.DataFrame, real: pd.DataFrame, extreme: bool
) -> Callable[[], Any]:
    """A call with bad data or bad options (or both), chosen by ``rng``."""
    which = rng.choice(["estimate", "estimate", "simulate", "validate", "mapreduce", "real", "real"])
    if which == "real":
        # An identifiable experiment, so that odd options and nominal values
        # reach the estimator's numerics (extreme but finite values too).
        options = bad_options(rng, model, extreme)
        options.setdefault("method", "iv3")
        if rng.random() < 0.5:
            options["method"] = rng.choice(["ls", "iv1", "iv2", "iv3"])
            options["initial"] = rng.choice(["delayed", "nominal"])
        if rng.random() < 0.5:
            extremes = [1e305, -5e307, 1.7e308, 1e-300, 1e150] if extreme else [1e6, -1e3, 1e-300]
            options["nominal"] = {p: rng.choice([v, v, -v, 0.0, *extremes]) for p, v in model.nominal.items()}
        return _labelled(f"estimate(real, **{options!r})", lambda: leeway.estimate(model, real, **options))
    data = bad_data(rng, model) if rng.random() < 0.7 else good
    if which == "estimate":
        options = bad_options(rng, model) if rng.random() < 0.5 else {"method": "ls"}
        return _labelled(f"estimate({_kind(data)}, **{options!r})", lambda: leeway.estimate(model, data, **options))
    if which == "simulate":
        theta = bad_theta(rng, model) if rng.random() < 0.4 else model.nominal
        extra: dict[str, Any] = {}
        if rng.random() < 0.4:
            extra[rng.choice(["x0", "disturbances", "step"])] = rng.choice(
                [*WEIRD, {"u": rng.choice(WEIRD)}, {"current.north": rng.choice(WEIRD)}, {rng.choice([3, None, 2.5, b"u", ("u",)]): 1.0}])
        return _labelled(f"simulate({theta!r}, {_kind(data)}, **{extra!r})",
                         lambda: leeway.simulate(model, theta, data, **extra))
    if which == "validate":
        theta = bad_theta(rng, model) if rng.random() < 0.4 else model.nominal
        extra = {}
        if rng.random() < 0.4:
            extra[rng.choice(["disturbances", "step", "time_tolerance", "resample"])] = rng.choice(WEIRD)
        return _labelled(f"validate({theta!r}, {_kind(data)}, **{extra!r})",
                         lambda: leeway.validate(model, theta, data, **extra))
    options = bad_options(rng, model) if rng.random() < 0.5 else {"method": "ls"}

    def mapped() -> Any:
        chosen = mr.options(model, **options)
        return len(mr.open_frame(model, data, chosen))

    return _labelled(f"mapreduce({_kind(data)}, **{options!r})", mapped)


def _kind(data: Any) -> str:
    if isinstance(data, pd.DataFrame):
        return f"DataFrame[{len(data)}]({', '.join(f'{c}:{t}' for c, t in data.dtypes.items())})"
    return type(data).__name__


def _labelled(label: str, call: Callable[[], Any]) -> Callable[[], Any]:
    call.label = label  # type: ignore[attr-defined]
    return call


def run_campaign(cases: int, seed: int, extreme: bool = False) -> collections.Counter[str]:
    model = leeway.Model.load(SHIP)
    rng = random.Random(seed)
    good = base_frame(random.Random(seed + 1), 120)
    real = real_frame()
    counts: collections.Counter[str] = collections.Counter()
    failures = []
    for i in range(cases):
        call = one_case(rng, model, good, real, extreme)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                call()
            counts["answered"] += 1
        except leeway.LeewayError as e:
            counts[type(e).__name__] += 1
            if e.code == "internal-error":
                failures.append((i, f"panic: {e.message} in {call.label}"))  # type: ignore[attr-defined]
            elif isinstance(e, leeway.DataError) and not e.location and e.code != "no-data":
                failures.append((i, f"unlocated DataError: {e} in {call.label}"))  # type: ignore[attr-defined]
        except BaseException as e:  # noqa: BLE001 — exactly what must not happen
            if isinstance(e, KeyboardInterrupt):
                raise
            counts["foreign:" + type(e).__name__] += 1
            failures.append((i, f"{type(e).__module__}.{type(e).__name__}: {e} in {call.label}"))  # type: ignore[attr-defined]
    counts["cases"] = cases
    print(f"\nfuzz seed {seed}{' (extreme nominal values)' if extreme else ''}: {dict(sorted(counts.items()))}")
    for i, what in failures:
        print(f"  case {i}: {what}")
    assert not failures, failures[:20]
    return counts


def test_every_failure_is_a_leeway_error() -> None:
    counts = run_campaign(CASES, SEED)
    # The cases exercise both outcomes and all the classes that matter.
    assert counts["answered"] > 0
    assert counts["DataError"] > 0 and counts["OptionError"] > 0


@pytest.mark.parametrize("seed", [1, 2])
def test_other_seeds(seed: int) -> None:
    run_campaign(max(50, CASES // 6), seed)


def test_extreme_nominal_values_are_located_errors() -> None:
    run_campaign(max(100, CASES // 3), SEED + 7, extreme=True)
