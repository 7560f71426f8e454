"""Residual analysis, as MATLAB's ``resid`` reads an output-error model: the
errors of θ's free-run simulation on recorded experiments and the tests a
model that describes the data passes (docs/python.md, "Residuals"); and
one-step-ahead predictions (``predict``). The arithmetic is Rust's
(``leeway_model::residuals``), the same as ``leeway validate --resid``."""

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
    """The free run's errors and their tests.

    ``residuals``, ``simulated`` and ``measured``: one row per sample,
    indexed by (``experiment``, ``sample``), with ``time`` (seconds from
    the experiment's first sample) and one column per state; the
    simulation starts from each experiment's first measurement, which has
    no error (NaN). ``tests``: per state, the error's ``mean`` and ``std``,
    the autocorrelation's largest ``max_abs``, the lags ``outside`` the
    99 % band, ``white``, the Ljung–Box statistic ``ljung_box`` and its χ²
    ``p_value``, and the verdict ``independent``. ``input_tests``: per
    (state, input), ``max_abs``, ``outside``, ``band`` (the white band
    times √P for the colour of both series) and ``independent``.
    ``autocorrelation`` (lags 1..M × states) and ``cross_correlation``
    (lags −M..M × (state, input)). ``band``: the 99 % band ±2.576/√N of
    each lag for a white error; ``white_band``/``input_band``: the family
    bands (1 % over all lags together) for a white error. ``diverged``: the
    experiments whose simulation left the finite numbers. ``document``: the
    ``residuals`` object of ``leeway validate --json --resid``.

    The verdict is ``independent``: a model that describes the data leaves
    nothing of the inputs in its free-run error — true of the true model
    under measurement noise and disturbances independent of the inputs
    (open loop), whatever their colour. ``white`` is information: the true
    model's error is white only when the disturbances do not vary."""

    residuals: pd.DataFrame
    simulated: pd.DataFrame
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
    diverged: list[str]
    document: dict[str, Any]

    @property
    def white(self) -> bool:
        """Every state's error passes the whiteness test (information)."""
        return bool(self.tests["white"].all())

    @property
    def independent(self) -> bool:
        """The verdict: every simulation stayed finite and every state's
        error is independent of every input."""
        return bool(self.tests["independent"].all())

    def __str__(self) -> str:
        lines = [
            f"Residual analysis: free-run simulation errors, N={self.samples}, lags 1..{self.lags}, "
            f"99 % band ±{self.band:.4f} for a white error; verdict: independent of the inputs "
            f"at 1 % over all lags (±{self.input_band:.4f}·√P); whiteness is information "
            f"(±{self.white_band:.4f})",
            f"{'state':<10} {'std':>10} {'max|r|':>8} {'white':>6} {'Q':>9} {'p':>7} {'indep.':>6}  lags outside",
        ]
        for state, r in self.tests.iterrows():
            q = "" if r["ljung_box"] is None else f"{r['ljung_box']:.1f}"
            p = "" if r["p_value"] is None else f"{r['p_value']:.3f}"
            mx = "" if r["max_abs"] is None else f"{r['max_abs']:.3f}"
            std = "" if r["std"] is None else f"{r['std']:.4g}"
            lines.append(
                f"{str(state):<10} {std:>10} {mx:>8} {'yes' if r['white'] else 'no':>6} {q:>9} {p:>7} "
                f"{'yes' if r['independent'] else 'NO':>6}  {_lag_list(r['outside'])}"
            )
        if len(self.input_tests):
            lines.append(f"{'state':<10} {'input':<10} {'max|r|':>8} {'band':>7} {'indep.':>6}  lags outside")
            for (state, u), r in self.input_tests.iterrows():
                mx = "" if r["max_abs"] is None else f"{r['max_abs']:.3f}"
                band = "" if r["band"] is None else f"{r['band']:.3f}"
                lines.append(
                    f"{str(state):<10} {str(u):<10} {mx:>8} {band:>7} {'yes' if r['independent'] else 'NO':>6}  "
                    f"{_lag_list(r['outside'])}"
                )
        if self.diverged:
            lines.append(f"diverged: {', '.join(self.diverged)}")
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
        [{k: r[k] for k in ("state", "mean", "std", "max_abs", "outside", "white", "ljung_box", "p_value",
                            "independent")} for r in rows]
    ).set_index("state")
    inputs = [
        {"state": r["state"], "input": i["input"], "max_abs": i["max_abs"], "band": i["band"],
         "outside": i["outside"], "independent": i["independent"]}
        for r in rows for i in r["inputs"]
    ]
    input_tests = (
        pd.DataFrame(inputs).set_index(["state", "input"])
        if inputs
        else pd.DataFrame(columns=["max_abs", "band", "outside", "independent"])
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
        simulated=_frame(experiments, states, 1),
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
        diverged=list(doc["diverged"]),
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
    """The free-run simulation errors of ``model`` with ``theta`` on every
    experiment of ``data`` and their input-independence (the verdict) and
    whiteness tests at lags up to ``lags`` (``leeway validate --resid``).

    Each experiment is simulated from its first measured state, driven by
    its measured inputs (unmeasured disturbance components held as
    ``leeway.simulate`` holds them: an ``Estimate``'s means unless
    ``disturbances`` says otherwise); the error is e(k) = x(k) − x̂(k), per
    state and experiment, never across an experiment boundary. Why not
    one-step errors: with white measurement noise the true model's
    one-step error is MA(1) and fails every whiteness test.
    ``data``, ``step``, ``time_tolerance`` and ``resample`` are as for
    ``leeway.validate``."""
    checked_lags = _integer("lags", lags, 1, 100_000)
    experiments, document = _run_native(
        model, theta, data, checked_lags, disturbances, step, time_tolerance, resample, one_step=False
    )
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
    ``time`` (NaN at the first sample). For ``der x = f(x, u, θ)`` at step
    h, x̂(j+1|j) is one step of the simulator's integrator from the
    *measured* state x(j) with the measured inputs, rotation and
    disturbances at j (unmeasured ones held as in ``residuals``). Only
    ``k=1`` is implemented; for a free run from the first sample use
    ``leeway.simulate``."""
    if _integer("k", k, 1, 1_000_000) != 1:
        raise OptionError(
            f"k={k}: only one-step-ahead predictions (k=1) are implemented",
            code="invalid-option",
            hint="use k=1, or leeway.simulate for a simulation from the first sample",
        )
    experiments, _ = _run_native(
        model, theta, data, 1, disturbances, step, time_tolerance, resample, one_step=True
    )
    return _frame(experiments, model.states, 1)


def _run_native(
    model: Model,
    theta: Theta,
    data: Data,
    lags: int,
    disturbances: Disturbances,
    step: float | None,
    time_tolerance: float,
    resample: float | None,
    *,
    one_step: bool,
) -> tuple[list[Any], str]:
    """The native analysis (free run and tests, or one-step predictions),
    its warnings issued at the caller's caller."""
    checked_theta = _theta(model, theta)
    given, zero = _disturbances(disturbances)
    experiments, document, issued = _native(
        _leeway.residual_analysis,
        model._core,
        _handover(model, data),
        checked_theta,
        given,
        lags,
        zero,
        _means(theta),
        _seconds("step", step),
        _seconds("time_tolerance", time_tolerance, optional=False),
        _seconds("resample", resample),
        one_step,
    )
    for w in issued:
        warnings.warn(python_spelling(w), LeewayWarning, stacklevel=3)
    return experiments, document
