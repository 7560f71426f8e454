"""leeway.mapreduce with a stand-in for Spark's ``applyInPandas``: every
pass hands each experiment's rows to a function as a DataFrame (nothing
kept between passes, groups visited in any order), and the driver gets the
estimate of ``leeway.estimate`` on the whole frame, bit for bit. This is
the recipe of docs/distributed.md."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import pandas as pd
import pytest

import leeway
import leeway.mapreduce as mr
from conftest import SHIP, ship_data


@pytest.fixture(scope="module")
def ship() -> leeway.Model:
    return leeway.Model.load(SHIP)


def apply_in_pandas(frame: pd.DataFrame, f) -> pd.DataFrame:  # type: ignore[no-untyped-def]
    """``df.groupBy("experiment").applyInPandas(f, schema)``: groups in no
    particular order (here: reversed), results concatenated."""
    groups = [g for _, g in frame.groupby("experiment", sort=True)][::-1]
    return pd.concat([f(g.reset_index(drop=True)) for g in groups], ignore_index=True)


def test_a_spark_style_map_gives_the_local_estimate(ship: leeway.Model, tmp_path: Path) -> None:
    frame = pd.concat(
        [ship_data(tmp_path, n, 1.0, seed).assign(experiment=name)
         for name, n, seed in [("a", 700, 31), ("b", 1100, 32), ("c", 500, 33)]],
        ignore_index=True,
    )
    options = mr.options(ship, method="iv3", lags=2)

    def opened(g: pd.DataFrame) -> pd.DataFrame:
        d = mr.open_frame(ship, g, options)
        return pd.DataFrame({"experiment": [g["experiment"].iloc[0]], "summary": [d.summary()], "count": [len(d)]})

    heads = apply_in_pandas(frame, opened).sort_values("experiment").reset_index(drop=True)
    offsets = dict(zip(heads["experiment"], heads["count"].cumsum() - heads["count"]))

    def mapped(request: bytes, answer) -> list[bytes]:  # type: ignore[no-untyped-def]
        def task(g: pd.DataFrame) -> pd.DataFrame:
            name = g["experiment"].iloc[0]
            out = answer(mr.open_frame(ship, g, options), int(offsets[name]), request)
            return pd.DataFrame({"experiment": name, "i": range(len(out)), "summary": out})

        rows = apply_in_pandas(frame, task).sort_values(["experiment", "i"])
        return list(rows["summary"])

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", leeway.LeewayWarning)
        ours = mr.estimate(
            ship,
            list(heads["experiment"]),
            list(heads["summary"]),
            lambda r: mapped(r, lambda d, _, q: d.facts(q)),
            lambda r: mapped(r, lambda d, offset, q: d.run(offset, q)),
            options,
        )
        local = leeway.estimate(ship, frame, method="iv3", lags=2)
    a, b = json.loads(ours.to_json()), json.loads(local.to_json())
    for key in ("file", "data", "data_files"):
        a.pop(key), b.pop(key)
    assert json.dumps(a) == json.dumps(b)
    assert a["diagnostics"]["experiments"] == 3 and a["diagnostics"]["refinements"] >= 1


def test_unknown_options_are_refused(ship: leeway.Model) -> None:
    with pytest.raises(leeway.OptionError, match="unknown option 'methd'"):
        mr.options(ship, methd="iv3")


def test_a_failing_pass_raises_its_own_exception(ship: leeway.Model, tmp_path: Path) -> None:
    frame = ship_data(tmp_path, 600, 1.0, 34)
    options = mr.options(ship)
    d = mr.open_frame(ship, frame, options)

    def broken(request: bytes) -> list[bytes]:
        raise ConnectionError("the cluster went away")

    with pytest.raises(ConnectionError, match="went away"):
        mr.estimate(ship, ["data"], [d.summary()], lambda r: d.facts(r), broken, options)
