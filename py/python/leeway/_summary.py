"""Inference on an estimate in the words of statsmodels and MATLAB's System
Identification Toolbox: standard errors (``bse``), t-values, p-values,
confidence intervals and a summary table.

The intervals and p-values use the normal distribution, not Student's t:
the instrumental-variable estimators are consistent and asymptotically
normal, their standard errors come from the robust sandwich covariance,
and the number of samples N is large (thousands), where t and normal
quantiles agree to the digits shown. The quantiles come from
``statistics.NormalDist`` (no scipy). A parameter whose standard error is
null — held at its nominal value, dropped, or no covariance computed — has
NaN in every column, never a made-up number, and its ``status`` says why.
"""

from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass, field
from statistics import NormalDist
from typing import Any

import pandas as pd

_NORMAL = NormalDist()


def quantile(alpha: float) -> float:
    """The two-sided normal quantile ``z`` with ``P(|Z| > z) = alpha``."""
    if not (isinstance(alpha, (int, float)) and not isinstance(alpha, bool) and 0.0 < alpha < 1.0):
        from .errors import OptionError

        raise OptionError(
            f"alpha={alpha!r} is not a probability strictly between 0 and 1",
            code="invalid-option",
            hint="give alpha=0.05 for 95 % intervals",
        )
    return _NORMAL.inv_cdf(1.0 - alpha / 2.0)


def p_value(t: float) -> float:
    """``P(|Z| > |t|)`` for a standard normal Z (NaN for NaN)."""
    if math.isnan(t):
        return math.nan
    return 2.0 * _NORMAL.cdf(-abs(t))


def table(params: pd.DataFrame, alpha: float = 0.05) -> pd.DataFrame:
    """``params`` (estimate, std_error, status, …) with ``t``, ``p``,
    ``lower``, ``upper`` at level ``1 − alpha`` and ``note``: why a row
    has no inference."""
    z = quantile(alpha)
    estimate = params["estimate"].astype("float64")
    se = params["std_error"].astype("float64")
    out = pd.DataFrame(index=params.index)
    out["estimate"] = estimate
    out["std_error"] = se
    out["t"] = estimate / se
    out["p"] = [p_value(t) for t in out["t"]]
    out["lower"] = estimate - z * se
    out["upper"] = estimate + z * se
    out["status"] = params["status"]
    sums = params["estimates"] if "estimates" in params else [None] * len(params)
    out["note"] = [_note(s, status, total) for s, status, total in zip(se, params["status"], sums)]
    return out


def _note(se: float, status: Any, total: Any) -> str:
    """Why a row has no inference, or what an aggregate's row estimates."""
    if status == "aggregate":
        return f"aggregate: estimates {total}"
    return "" if not math.isnan(se) else _why(status)


def _why(status: Any) -> str:
    if isinstance(status, str) and status not in ("estimated", "aggregate"):
        return f"no standard error: {status}"
    return "no standard error: the covariance could not be computed"


def _number(v: float, width: int = 10) -> str:
    if isinstance(v, float) and math.isnan(v):
        return "nan".rjust(width)
    return f"{v:.4g}".rjust(width)


def _rows(frame: pd.DataFrame, alpha: float) -> list[str]:
    lo, hi = f"[{alpha / 2:.3g}", f"{1 - alpha / 2:.3g}]"
    width = max([len(str(n)) for n in frame.index] + [9])
    head = (
        f"{'':<{width}} {'coef':>10} {'std err':>10} {'t':>9} {'P>|t|':>7} {lo:>10} {hi:>10}"
    )
    lines = [head]
    for name, r in frame.iterrows():
        p = "nan".rjust(7) if math.isnan(r["p"]) else f"{r['p']:7.3f}"
        t = "nan".rjust(9) if math.isnan(r["t"]) else f"{r['t']:9.2f}"
        line = (
            f"{str(name):<{width}} {_number(r['estimate'])} {_number(r['std_error'])} {t} {p}"
            f" {_number(r['lower'])} {_number(r['upper'])}"
        )
        if r["note"]:
            line += f"  ({r['note'].removeprefix('no standard error: ')})"
        lines.append(line)
    return lines


@dataclass(frozen=True)
class Summary:
    """An estimate's summary: ``str()`` is the table (header, θ with
    standard errors, t, P>|t| and the confidence interval, the nuisance
    parameters, the disturbance means, diagnostics and warnings);
    ``tables`` the same as DataFrames (``params``, ``nuisance``,
    ``disturbances``) and ``header`` the header's fields."""

    header: dict[str, Any]
    tables: dict[str, pd.DataFrame]
    alpha: float
    diagnostics: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)

    def __str__(self) -> str:
        h = self.header
        rule = "=" * 78
        thin = "-" * 78
        level = f"{100 * (1 - self.alpha):g} %"
        fields = [
            ("Model:", f"{h['model']} ({h['file']})"),
            ("Method:", f"{h['method']}; instruments: {h['instruments']}"),
            ("Data:", ", ".join(h["data"]) or "(frames)"),
            ("Samples N:", f"{h['samples']} in {h['experiments']} experiment(s) ({h['equations']} equations)"),
            ("Centring:", str(h["centring"])),
            ("Covariance:", f"robust sandwich (lags={h['lags']}); normal quantiles ({level} intervals)"),
        ]
        lines = [
            f"leeway estimate: {h['model']} ({h['method']})".center(78).rstrip(),
            rule,
            *(textwrap.fill(text, 78, initial_indent=f"{label:<14}", subsequent_indent=" " * 14) for label, text in fields),
            rule,
            *_rows(self.tables["params"], self.alpha),
        ]
        if len(self.tables["nuisance"]):
            lines += [thin, "Nuisance parameters (moments of the unmeasured disturbances)"]
            lines += _rows(self.tables["nuisance"], self.alpha)
        if len(self.tables["disturbances"]):
            lines += [thin, "Disturbance means"]
            d = self.tables["disturbances"].copy()
            d.index = [f"{a}.{b}" for a, b in d.index]
            lines += _rows(d, self.alpha)
        lines += [thin, "Diagnostics", *(f"  {x}" for x in self.diagnostics)]
        if self.warnings:
            lines += [thin, "Warnings"]
            lines += [
                textwrap.fill(w, 78, initial_indent=f"  [{i + 1}] ", subsequent_indent="      ")
                for i, w in enumerate(self.warnings)
            ]
        lines.append(rule)
        return "\n".join(lines)

    def __repr__(self) -> str:
        return str(self)


def summary(
    document: dict[str, Any],
    params: pd.DataFrame,
    nuisance: pd.DataFrame,
    disturbances: pd.DataFrame,
    warnings: list[str],
    alpha: float,
) -> Summary:
    """The summary of an estimate's document and frames."""
    d, g = document, document["diagnostics"]
    header = {
        "model": d.get("model"),
        "file": d.get("file"),
        "method": d["method"],
        "data": list(d.get("data", [])),
        "samples": sum(e["samples"] for e in d["experiments"]),
        "experiments": len(d["experiments"]),
        "equations": g.get("equations"),
        "centring": g.get("centring"),
        "instruments": g.get("instruments"),
        "lags": g.get("lags"),
    }
    disturbance_table = table(
        disturbances.rename(columns={"mean": "estimate"}).assign(status="estimated"), alpha
    )
    own = g.get("own_simulation", {})
    diagnostics = [
        f"rank {g.get('rank')} of {g.get('columns')} columns ({g.get('estimated')} estimated), "
        f"condition number {g.get('condition_number', math.nan):.3g}",
        f"refinements {g.get('refinements')} ({'converged' if g.get('converged') else 'not converged'})",
    ]
    sub = g.get("subsample")
    if sub is not None:
        how = "settled, then refined over all samples from it" if sub["used"] else f"not used ({sub.get('why_not')})"
        diagnostics.append(
            f"refined first on {sub['fraction']:g} of every experiment ({sub['samples']} samples, "
            f"{sub['refinements']} refinements): {how}"
        )
    if own.get("mean_fit") is not None:
        fits = ", ".join(f"{f['state']} {f['fit']:.1f} %" for f in own.get("fits", []) if f["fit"] is not None)
        diagnostics.append(f"own simulation fit: {fits} (mean {own['mean_fit']:.1f} %)")
    return Summary(
        header=header,
        tables={
            "params": table(params, alpha),
            "nuisance": table(nuisance, alpha),
            "disturbances": disturbance_table,
        },
        alpha=alpha,
        diagnostics=diagnostics,
        warnings=list(warnings),
    )
