"""Residual analysis, as MATLAB's ``resid``: one-step-ahead predictions of θ
on recorded experiments, their residuals, and the tests a model that
describes the data passes (docs/python.md, "Residuals"). The arithmetic is
Rust's (``leeway_model::residuals``), the same as ``leeway validate
--resid``."""

from __future__ import annotations

import json
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from . import _leeway
from ._api import (
    Disturbances,
    Model,
    Theta,
    _disturbances,
    _integer,
    _means,
    _native,
    _seconds,
    _theta,
)
from ._hints import python_spelling
from ._data import Data, _handover
from .errors import LeewayWarning, OptionError

DEFAULT_LAGS = 25


@dataclass(frozen=True)
class ResidualAnalysis:
    """One-step residuals and their tests.

    ``residuals``, ``predicted`` and ``measured``: one row per sample,
    indexed by (``experiment``, ``sample``), with ``time`` (seconds from
    the experiment's first sample) and one column per state; the first
    sample of each experiment has no prediction (NaN). ``tests``: per
    state, the residual's ``mean`` and ``std``, the autocorrelation's
    largest ``max_abs``, the lags ``outside`` the 99 % band, ``white``,
    the Ljung–Box statistic ``ljung_box`` and its χ² ``p_value``.
    ``input_tests``: per (state, input), ``max_abs``, ``outside`` and
    ``independent``. ``autocorrelation`` (lags 1..M × states) and
    ``cross_correlation`` (lags −M..M × (state, input)). ``band``: the
    99 % band ±2.576/√N of each lag; ``white_band``/``input_band``: the
    bands the verdicts read (1 % over all lags together). ``document``:
    the ``residuals`` object of ``leeway validate --json --resid``."""

    residuals: pd.DataFrame
    predicted: pd.DataFrame
    measured: pd.DataFrame
    tests: pd.DataFrame
    input_tests: pd.DataFrame
    autocorrelation: pd.DataFrame
    cross_correlation: pd.DataFrame
    lags: int
    samples: int
    band: float
    white_band: float
    input_band: float
    document: dict[str, Any]

    @property
    def white(self) -> bool:
        """Every state's residual passes the whiteness test."""
        return bool(self.tests["white"].all())

    @property
    def independent(self) -> bool:
        """Every residual passes the independence test with every input."""
        return bool(self.input_tests["independent"].all()) if len(self.input_tests) else True

    def __str__(self) -> str:
        lines = [
            f"Residual analysis: one-step-ahead, N={self.samples}, lags 1..{self.lags}, "
            f"99 % band ±{self.band:.4f} (verdicts at 1 % over all lags: "
            f"±{self.white_band:.4f}, inputs ±{self.input_band:.4f})",
            f"{'state':<10} {'std':>10} {'max|r|':>8} {'white':>6} {'Q':>9} {'p':>7}  lags outside",
        ]
        for state, r in self.tests.iterrows():
            q = "" if r["ljung_box"] is None else f"{r['ljung_box']:.1f}"
            p = "" if r["p_value"] is None else f"{r['p_value']:.3f}"
            mx = "" if r["max_abs"] is None else f"{r['max_abs']:.3f}"
            std = "" if r["std"] is None else f"{r['std']:.4g}"
            lines.append(
                f"{str(state):<10} {std:>10} {mx:>8} {'yes' if r['white'] else 'NO':>6} {q:>9} {p:>7}  "
                f"{_lag_list(r['outside'])}"
            )
        if len(self.input_tests):
            lines.append(f"{'state':<10} {'input':<10} {'max|r|':>8} {'indep.':>6}  lags outside")
            for (state, u), r in self.input_tests.iterrows():
                mx = "" if r["max_abs"] is None else f"{r['max_abs']:.3f}"
                lines.append(
                    f"{str(state):<10} {str(u):<10} {mx:>8} {'yes' if r['independent'] else 'NO':>6}  "
                    f"{_lag_list(r['outside'])}"
                )
        return "\n".join(lines)


def _lag_list(lags: list[int]) -> str:
    shown = ", ".join(str(x) for x in lags[:12])
    return (shown + (f", … ({len(lags)})" if len(lags) > 12 else "")) or "—"


def _frame(experiments: list[Any], states: list[str], part: int) -> pd.DataFrame:
    pieces = []
    for name, h, *columns in experiments:
        values = columns[part]
        n = len(values[0]) if values else 0
        piece = pd.DataFrame({"time": np.arange(n) * h, **dict(zip(states, values))})
        piece.index = pd.MultiIndex.from_arrays(
            [[name] * n, np.arange(n)], names=["experiment", "sample"]
        )
        pieces.append(piece)
    return pd.concat(pieces) if pieces else pd.DataFrame(columns=["time", *states])


def _analysis(doc: dict[str, Any], experiments: list[Any], states: list[str]) -> ResidualAnalysis:
    m = doc["lags"]
    rows = doc["states"]
    tests = pd.DataFrame(
        [{k: r[k] for k in ("state", "mean", "std", "max_abs", "outside", "white", "ljung_box", "p_value")} for r in rows]
    ).set_index("state")
    inputs = [
        {"state": r["state"], "input": i["input"], "max_abs": i["max_abs"],
         "outside": i["outside"], "independent": i["independent"]}
        for r in rows for i in r["inputs"]
    ]
    input_tests = (
        pd.DataFrame(inputs).set_index(["state", "input"])
        if inputs
        else pd.DataFrame(columns=["max_abs", "outside", "independent"])
    )
    nan = float("nan")
    auto = pd.DataFrame(
        {r["state"]: [nan if v is None else v for v in r["autocorrelation"]] for r in rows},
        index=pd.Index(range(1, m + 1), name="lag"),
    )
    cross = pd.DataFrame(
        {(r["state"], i["input"]): [nan if v is None else v for v in i["correlation"]]
         for r in rows for i in r["inputs"]},
        index=pd.Index(range(-m, m + 1), name="lag"),
    )
    return ResidualAnalysis(
        measured=_frame(experiments, states, 0),
        predicted=_frame(experiments, states, 1),
        residuals=_frame(experiments, states, 2),
        tests=tests,
        input_tests=input_tests,
        autocorrelation=auto,
        cross_correlation=cross,
        lags=m,
        samples=doc["samples"],
        band=doc["band"],
        white_band=doc["white_band"],
        input_band=doc["input_band"],
        document=doc,
    )


def residuals(
    model: Model,
    theta: Theta,
    data: Data,
    *,
    lags: int = DEFAULT_LAGS,
    disturbances: Disturbances = None,
    step: float | None = None,
    time_tolerance: float = 0.05,
    resample: float | None = None,
) -> ResidualAnalysis:
    """The one-step-ahead residuals of ``model`` with ``theta`` on every
    experiment of ``data`` and their whiteness and input-independence
    tests at lags up to ``lags`` (``leeway validate --resid``).

    For ``der x = f(x, u, θ)`` at step h, the prediction x̂(k+1|k) is one
    step of the simulator's integrator from the *measured* state x(k) with
    the measured inputs, rotation and disturbances at k (unmeasured
    disturbance components held as ``leeway.simulate`` holds them: an
    ``Estimate``'s means unless ``disturbances`` says otherwise); the residual is e(k+1) = x(k+1) −
    x̂(k+1|k), per state and experiment, never across an experiment
    boundary. ``data``, ``step``, ``time_tolerance`` and ``resample`` are
    as for ``leeway.validate``."""
    checked_theta = _theta(model, theta)
    checked_lags = _integer("lags", lags, 1, 100_000)
    given, zero = _disturbances(disturbances)
    experiments, document, issued = _native(
        _leeway.residual_analysis,
        model._core,
        _handover(model, data),
        checked_theta,
        given,
        checked_lags,
        zero,
        _means(theta),
        _seconds("step", step),
        _seconds("time_tolerance", time_tolerance, optional=False),
        _seconds("resample", resample),
    )
    for w in issued:
        warnings.warn(python_spelling(w), LeewayWarning, stacklevel=2)
    return _analysis(json.loads(document), experiments, model.states)


def predict(
    model: Model,
    theta: Theta,
    data: Data,
    *,
    k: int = 1,
    disturbances: Disturbances = None,
    step: float | None = None,
    time_tolerance: float = 0.05,
    resample: float | None = None,
) -> pd.DataFrame:
    """The ``k``-step-ahead predictions x̂(j|j−k) of every state on every
    experiment of ``data``, indexed by (``experiment``, ``sample``) with
    ``time`` (see ``residuals`` for how a prediction is made; NaN at the
    first sample). Only ``k=1`` is implemented; for a free run from the
    first sample use ``leeway.simulate``."""
    if _integer("k", k, 1, 1_000_000) != 1:
        raise OptionError(
            f"k={k}: only one-step-ahead predictions (k=1) are implemented",
            code="invalid-option",
            hint="use k=1, or leeway.simulate for a simulation from the first sample",
        )
    analysis = residuals(
        model, theta, data, lags=1, disturbances=disturbances, step=step,
        time_tolerance=time_tolerance, resample=resample,
    )
    return analysis.predicted
