"""Figures of leeway's results with matplotlib, which leeway does not
require: ``import leeway`` never imports it, and a function here without it
installed raises ``ImportError`` saying ``pip install matplotlib``. Each
function returns the matplotlib ``Figure`` (``fig.savefig("out.png")``).

- :func:`compare`: measured against simulated per output, each θ's fit in
  the legend (MATLAB's ``compare``; ``leeway validate --plot``).
- :func:`residuals`: the residuals' autocorrelation and their
  cross-correlation with each input, with the 99 % band (MATLAB's
  ``resid``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from ._api import Disturbances, Model, Thetas, _thetas, simulate, validate
from ._data import Data, _frames, _to_pandas
from ._residuals import ResidualAnalysis

__all__ = ["compare", "residuals"]


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
