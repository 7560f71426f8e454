"""Figures of leeway's results with matplotlib, which leeway does not
require: ``import leeway`` never imports it, and a function here without it
installed raises ``ImportError`` saying ``pip install matplotlib``. Each
function returns the matplotlib ``Figure`` (``fig.savefig("out.png")``).

- :func:`compare`: measured against simulated per output, each θ's fit in
  the legend (MATLAB's ``compare``; ``leeway validate --plot``).
- :func:`residuals`: the residuals' autocorrelation and their
  cross-correlation with each input, with the 99 % band (MATLAB's
  ``resid``).
- :func:`selection`: a structure selection's criteria against model size
  (``Model.select``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from ._api import Disturbances, Model, Thetas, _thetas, simulate, validate
from ._data import Data, _frames, _to_pandas
from ._residuals import ResidualAnalysis
from ._select import Selection

__all__ = ["compare", "residuals", "selection"]


def _pyplot() -> Any:
    try:
        import matplotlib.pyplot as plt
    except ImportError:
        raise ImportError(
            "leeway.plot draws with matplotlib, which is not installed: pip install matplotlib"
        ) from None
    return plt


def _experiments(model: Model, data: Data) -> list[tuple[str, pd.DataFrame]]:
    """Every experiment of ``data`` as its own frame (split on the
    experiment column, as ``leeway.validate`` splits)."""
    column = model._core.experiment_column
    out = []
    for name, raw in _frames(data):
        frame = _to_pandas(raw, name)
        if column in frame.columns:
            for label, part in frame.groupby(column, sort=False):
                out.append((str(label), part.drop(columns=[column]).reset_index(drop=True)))
        else:
            out.append((name, frame))
    return out


def compare(
    model: Model,
    thetas: Thetas,
    data: Data,
    *,
    disturbances: Disturbances = None,
    step: float | None = None,
    experiment: int | str = 0,
) -> Any:
    """Measured against simulated for one experiment of ``data`` (by
    position or name; the first by default): one panel per state, each θ
    simulated from the experiment's first sample as ``leeway.validate``
    simulates it, with its fit (``leeway.validate``'s, %) in the legend.
    ``thetas``, ``data``, ``disturbances`` and ``step`` are as for
    ``leeway.validate``. Returns the ``Figure``."""
    plt = _pyplot()
    experiments = _experiments(model, data)
    names = [n for n, _ in experiments]
    index = names.index(experiment) if isinstance(experiment, str) and experiment in names else experiment
    if not isinstance(index, int) or not 0 <= index < len(experiments):
        from .errors import OptionError

        raise OptionError(
            f"experiment={experiment!r} is not one of the data's experiments",
            code="invalid-option",
            hint=f"give a position 0..{len(experiments) - 1} or a name: {', '.join(names)}",
        )
    name, frame = experiments[index]
    named = [(label, theta) for label, _, theta in _thetas(thetas)]
    fits = validate(model, dict(named), {name: frame}, disturbances=disturbances, step=step)
    states = model.states
    fig, axes = plt.subplots(len(states), 1, sharex=True, squeeze=False, figsize=(8, 2.2 * len(states)))
    time_column = model.columns[0]
    simulations = [
        (label, simulate(model, theta, frame, disturbances=disturbances, step=step))
        for label, theta in named
    ]
    # The data columns follow the time column in the model's state order.
    columns = model.columns[1 : 1 + len(states)]
    measured_time = simulations[0][1][time_column].to_numpy()
    for ax, state, column in zip(axes[:, 0], states, columns):
        ax.plot(measured_time, frame[column].to_numpy()[: len(measured_time)], color="black", label="measured")
        for label, sim in simulations:
            fit = fits.loc[(label, name), state]
            text = f"{label} (fit {fit:.1f} %)" if np.isfinite(fit) else f"{label} (fit undefined)"
            ax.plot(sim[time_column].to_numpy(), sim[column].to_numpy(), label=text)
        ax.set_ylabel(state)
        ax.legend(loc="best", fontsize="small")
    axes[-1, 0].set_xlabel(f"{time_column} [s]")
    fig.suptitle(f"{model.name}: measured and simulated, experiment {name}")
    return fig


def _input_band(analysis: ResidualAnalysis, state: str, u: str) -> float:
    """The per-lag 99 % band of one cross-correlation: the white band times √P."""
    widened = analysis.input_tests.loc[(state, u), "band"]
    return analysis.band if widened is None else analysis.band * widened / analysis.input_band


def residuals(analysis: ResidualAnalysis) -> Any:
    """The residual analysis of ``leeway.residuals``: one row per state,
    its simulation error's autocorrelation at lags 1..M with the 99 % band
    ±2.576/√N of a white error, then its cross-correlation with each input
    at lags −M..M with the 99 % band widened by √P for the colour of both
    series (dashed). Returns the ``Figure``."""
    plt = _pyplot()
    states = list(analysis.tests.index)
    inputs = list(dict.fromkeys(u for _, u in analysis.cross_correlation.columns))
    fig, axes = plt.subplots(
        len(states), 1 + len(inputs), squeeze=False, figsize=(3.2 * (1 + len(inputs)), 2.2 * len(states))
    )
    band = analysis.band
    for row, state in zip(axes, states):
        auto = analysis.autocorrelation[state]
        panels = [(row[0], auto, f"{state}: autocorrelation", band)]
        panels += [
            (ax, analysis.cross_correlation[(state, u)], f"{state} × {u}", _input_band(analysis, state, u))
            for ax, u in zip(row[1:], inputs)
        ]
        for ax, series, title, band in panels:
            ax.vlines(series.index, 0, series.to_numpy(), color="tab:blue")
            ax.axhline(band, linestyle="--", color="tab:red", label="99 % band")
            ax.axhline(-band, linestyle="--", color="tab:red")
            ax.axhline(0, color="black", linewidth=0.5)
            ax.set_title(title, fontsize="small")
            ax.set_xlabel("lag")
    fig.suptitle(f"Simulation errors: N={analysis.samples}, 99 % band ±{analysis.band:.3f} for a white error")
    fig.tight_layout()
    return fig


def selection(result: Selection) -> Any:
    """The criteria of ``Model.select`` against model size (candidates
    kept) along the path: above, Hansen's J and the score ``J − d·ln N``
    the stopping rule minimises (symmetric log scale: J spans orders of
    magnitude once a true term is dropped); below, the held-out free-run
    criterion ``1 − fit/100`` (when there are held-out data). The chosen
    model is circled; each point is labelled with the candidate dropped to
    reach it. Returns the ``Figure``."""
    plt = _pyplot()
    steps = result.steps
    size = steps["size"].to_numpy()
    has_criterion = bool(steps["criterion"].notna().any())
    fig, axes = plt.subplots(2 if has_criterion else 1, 1, sharex=True, squeeze=False, figsize=(8, 6 if has_criterion else 3.5))
    top = axes[0, 0]
    top.plot(size, steps["j"].to_numpy(), marker="o", label="J")
    top.plot(size, steps["score"].to_numpy(), marker="s", label="J − d·ln N")
    top.set_yscale("symlog", linthresh=10)
    top.set_ylabel("over-identification")
    panels = [(top, steps["score"].to_numpy())]
    if has_criterion:
        bottom = axes[1, 0]
        bottom.plot(size, steps["criterion"].to_numpy(dtype=float), marker="o", color="tab:green", label="held-out 1 − fit/100")
        bottom.set_ylabel("held-out criterion")
        panels.append((bottom, steps["criterion"].to_numpy(dtype=float)))
    for ax, values in panels:
        chosen = result.chosen
        ax.plot([size[chosen]], [values[chosen]], marker="o", markersize=14, fillstyle="none", color="tab:red",
                linestyle="none", label=f"chosen: {len(result.kept)} candidates")
        for k, dropped in enumerate(steps["dropped"]):
            if isinstance(dropped, str):
                ax.annotate(f"−{dropped}", (size[k], values[k]), textcoords="offset points", xytext=(3, 4), fontsize="x-small")
        ax.legend(loc="best", fontsize="small")
        ax.grid(True, alpha=0.3)
    axes[-1, 0].set_xlabel("candidates kept")
    axes[-1, 0].invert_xaxis()
    fig.suptitle(f"Structure selection: {len(result.kept)} of {len(result.candidates)} candidates kept (step {result.chosen})")
    fig.tight_layout()
    return fig
