"""An estimate speaks statistics: ``summary()``, ``conf_int``, ``bse``,
``tvalues``, ``pvalues`` (normal quantiles, statsmodels' names), NaN with
a reason where a parameter has no standard error; a clean namespace and
``__version__``."""

from __future__ import annotations

import math
import warnings
from statistics import NormalDist

import numpy as np
import pytest

import leeway
from conftest import SHIP


@pytest.fixture(scope="module")
def est(ship_frame) -> leeway.Estimate:  # type: ignore[no-untyped-def]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", leeway.LeewayWarning)
        return leeway.estimate(leeway.Model.load(SHIP), ship_frame)


def test_inference_uses_the_normal_quantiles(est) -> None:  # type: ignore[no-untyped-def]
    p = est.params
    estimated = p.index[p["status"] == "estimated"]
    assert len(estimated) > 0
    np.testing.assert_array_equal(est.bse.to_numpy(), p["std_error"].to_numpy())
    t = est.tvalues
    np.testing.assert_allclose(t[estimated], p.loc[estimated, "estimate"] / p.loc[estimated, "std_error"])
    name = estimated[0]
    assert est.pvalues[name] == pytest.approx(2 * NormalDist().cdf(-abs(t[name])))
    ci = est.conf_int()
    assert list(ci.columns) == ["lower", "upper"]
    z = 1.959963984540054
    assert ci.loc[name, "lower"] == pytest.approx(p.loc[name, "estimate"] - z * p.loc[name, "std_error"])
    wide = est.conf_int(alpha=0.01)
    assert wide.loc[name, "upper"] > ci.loc[name, "upper"]
    with pytest.raises(leeway.OptionError, match="alpha"):
        est.conf_int(alpha=1.5)


def test_a_parameter_without_a_standard_error_is_nan_with_a_reason(est) -> None:  # type: ignore[no-untyped-def]
    held = est.params.index[est.params["std_error"].isna()]
    assert len(held) > 0, "the ship's wind terms are held with one 1 m/s run"
    table = est.table()
    for name in held:
        assert table.loc[name, ["t", "p", "lower", "upper"]].isna().all()
        assert "held" in table.loc[name, "note"] or "dropped" in table.loc[name, "note"]
        assert math.isnan(est.pvalues[name])


def test_the_summary_reads_like_statsmodels(est) -> None:  # type: ignore[no-untyped-def]
    s = est.summary()
    text = str(s)
    for label in ("Model:", "Method:", "Samples N:", "Centring:", "coef", "std err", "P>|t|",
                  "[0.025", "0.975]", "Nuisance parameters", "Disturbance means", "Diagnostics"):
        assert label in text, label
    assert "current.north" in text and "held at nominal" in text
    assert set(s.tables) == {"params", "nuisance", "disturbances"}
    assert list(s.tables["params"].index) == list(est.params.index)
    assert s.header["samples"] == sum(e["samples"] for e in est.experiments)
    assert "--" not in text.replace("-" * 78, "")
    assert "summary()" in repr(est) and est.method in repr(est)


def test_the_namespace_is_the_public_api() -> None:
    public = {n for n in dir(leeway) if not n.startswith("_")}
    submodules = {"errors", "mapreduce", "dask", "plot"}
    assert public - submodules == set(leeway.__all__) - {"__version__"}
    for leaked in ("np", "pd", "json", "os", "Any", "annotations", "warnings"):
        assert leaked not in public


def test_version_is_the_crates() -> None:
    import re
    from importlib.metadata import version

    assert re.fullmatch(r"\d+\.\d+\.\d+.*", leeway.__version__)
    assert leeway.__version__ == version("leeway")


def test_aggregates_are_labelled_as_such(est) -> None:  # type: ignore[no-untyped-def]
    # A wind that barely varies: its parameters are held, and the ones they
    # are combined with estimate sums — "aggregate" in the status, the
    # document and the summary, never "estimated".
    p = est.params
    sums = p[p["aggregate"].notna()]
    assert len(sums) > 0, p
    assert (sums["status"] == "aggregate").all(), sums
    assert (p.loc[p["status"] == "estimated", "aggregate"].isna()).all()
    assert not any("- -" in str(s) for s in sums["estimates"])
    text = str(est.summary())
    for name, row in sums.iterrows():
        line = next(x for x in text.splitlines() if x.startswith(f"{name} "))
        assert f"aggregate: estimates {row['estimates']}" in line, line
