"""Robot logs as they are written, as ``--data log.toml`` reads them: a
manifest of per-topic files (CSV, Parquet, ROS 2 bags) or a bag, joined on
the model's grid by the CLI's code (docs/logs.md)."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any, Union

import pandas as pd

from . import _leeway
from ._api import Model, _native
from .errors import OptionError


@dataclass(frozen=True)
class Log:
    """A log joined on the model's grid. ``experiments``: one DataFrame per
    experiment (a log split at its gaps gives ``name/1``, ``name/2``, …),
    with the columns ``leeway simulate`` writes — ``time`` from the
    experiment's first sample, then the model's signals in their declared
    units — ready for ``leeway.estimate(model, log.experiments)``.
    ``notes``: what the join did, as ``estimate --json`` reports it under
    ``data_files`` — every signal's source, rate and what the grid read of
    it, every gap that split the log, every stall held across, and every
    piece kept or dropped, with times in seconds from ``origin`` (the
    log's first stamp, ISO-8601 UTC)."""

    experiments: dict[str, pd.DataFrame]
    notes: dict[str, Any]

    @property
    def gaps(self) -> pd.DataFrame:
        """The gaps that split the log: ``signal``, ``from``, ``to``, ``limit`` (s)."""
        rows = [g for e in self.notes.get("experiments", []) for g in e.get("gaps", [])]
        return pd.DataFrame(rows, columns=["signal", "from", "to", "limit"])

    @property
    def stalls(self) -> pd.DataFrame:
        """Holes within the gap limit but longer than a signal's stall
        threshold (``limit``), held or interpolated across: ``signal``,
        ``from``, ``to``, ``limit`` (s)."""
        rows = [g for e in self.notes.get("experiments", []) for g in e.get("stalls", [])]
        return pd.DataFrame(rows, columns=["signal", "from", "to", "limit"])

    @property
    def pieces(self) -> pd.DataFrame:
        """Every piece of the log, split or kept by a window: ``experiment``
        (None: dropped as too short), ``from``, ``to`` (s), ``samples``."""
        rows = [p for e in self.notes.get("experiments", []) for p in e.get("pieces", [])]
        return pd.DataFrame(rows, columns=["experiment", "from", "to", "samples"])

    @property
    def signals(self) -> pd.DataFrame:
        """Every signal as read: ``signal``, ``source``, ``samples``,
        ``median_step`` (s), ``on_grid`` (what the grid read of it: at the
        grid time, or its mean over the step and of how many samples)."""
        rows = self.notes.get("signals", [])
        return pd.DataFrame(rows, columns=["signal", "source", "samples", "median_step", "on_grid"])


def read_log(
    model: Model,
    path: Union[str, "os.PathLike[str]"],
    *,
    max_gap: float | None = None,
    keep: list[tuple[float | None, float | None]] | None = None,
) -> Log:
    """Reads the log at ``path`` — a manifest (``.toml``) or a ROS 2 bag
    (``.mcap``) — for ``model`` as ``leeway estimate --data PATH`` does;
    ``max_gap`` is ``--max-gap`` (seconds; default five of each signal's
    median steps, at least five grid steps), ``keep`` is ``--keep``: the
    windows kept, ``(from, to)`` in seconds from the log's first stamp,
    either end ``None`` for open. An option the manifest also sets must
    agree with it. A malformed log raises ``DataError`` located in the file
    at fault."""
    if not isinstance(model, Model):
        raise OptionError(
            f"model is a {type(model).__name__}, not a leeway.Model",
            code="invalid-option",
            hint='load it with leeway.Model.load("craft.som")',
        )
    windows = [(None if a is None else float(a), None if b is None else float(b)) for a, b in (keep or [])]
    frames, notes = _native(_leeway.read_log, model._core, os.fspath(path), max_gap, windows)
    experiments = {name: pd.DataFrame(dict(columns)) for name, columns in frames}
    return Log(experiments, json.loads(notes)[0])
