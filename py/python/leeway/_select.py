"""Structure selection: ``Model.select``, which of a model's candidate terms
(``?name``) the data need, as ``leeway select`` chooses them
(docs/selection.md)."""

from __future__ import annotations

import json
import os
from typing import TYPE_CHECKING, Any

import pandas as pd

from . import _leeway
from ._api import Estimate, _integer, _MAX_LAGS, _native, _number, _seconds, _text, _warn
from ._data import Data, _handover

if TYPE_CHECKING:
    from ._api import Model


class Selection:
    """The outcome of ``Model.select``: the path from the full candidate
    model (one step per dropped candidate), the step chosen, the chosen
    model's source text and its estimate, and the terms it may lack.
    ``document`` is ``leeway select --json``'s ``selection``, bit for bit."""

    def __init__(self, model: Model, document: str, chosen_source: str, estimate: str) -> None:
        self._json = document
        d = json.loads(document)
        self.document: dict[str, Any] = d
        self.candidates: list[str] = d["candidates"]
        """The candidates the model declares, in declaration order."""
        self.steps: pd.DataFrame = pd.DataFrame(
            d["steps"],
            columns=["dropped", "reason", "wald", "wald_df", "p_value", "size", "j", "j_df", "score", "criterion"],
        ).rename_axis("step")
        """The path: per step the candidate dropped (None: the full model),
        why (``wald``, ``exchangeable with X``, ``not excited``), its Wald
        statistic, degrees of freedom and p-value, the candidates kept
        (``size``), Hansen's J and its degrees of freedom, the score
        ``J − d·ln N`` and the held-out criterion (NaN without held-out data)."""
        self.chosen: int = d["chosen"]
        """The step chosen (a row of ``steps``)."""
        self.kept: list[str] = d["kept"]
        self.dropped: list[str] = d["dropped"]
        self.held_out: str = d["held_out"]
        """Where the held-out criterion comes from."""
        self.suggestions: pd.DataFrame = pd.DataFrame(
            d["suggestions"], columns=["equation", "term", "correlation"]
        )
        """Terms the chosen model may lack: per equation the undeclared
        regressors most correlated with its one-step residuals."""
        self.source: str = chosen_source
        """The chosen model as ``.som`` text (what ``leeway select --out`` writes)."""
        self.estimate: Estimate = Estimate(estimate)
        """The chosen model's estimate, as ``leeway.estimate`` of ``model()`` gives it."""
        self._file = model.file

    def model(self, *, file: str | None = None) -> Model:
        """The chosen model, compiled (``file`` names it in diagnostics;
        default: the candidate model's file)."""
        from ._api import Model

        return Model.from_str(self.source, file=self._file if file is None else file)

    def write(self, path: str | os.PathLike[str]) -> None:
        """Writes the chosen model's source to ``path``, as ``--out`` does."""
        with open(path, "w", encoding="utf-8") as f:
            f.write(self.source)

    def to_json(self) -> str:
        """``leeway select --json``'s ``selection`` (without its final newline)."""
        return self._json

    def __repr__(self) -> str:
        return (
            f"<leeway.Selection: kept {len(self.kept)} of {len(self.candidates)} candidates "
            f"at step {self.chosen} of {len(self.steps) - 1}: {', '.join(self.kept) or 'none'}>"
        )


def select(
    model: Model,
    data: Data,
    validate: Data | None = None,
    *,
    method: str = "iv3",
    lags: int = 1,
    tolerance: float = 0.5,
    step: float | None = None,
    time_tolerance: float = 0.05,
    resample: float | None = None,
) -> Selection:
    """``Model.select``: see there."""
    args = {
        "method": _text("method", method),
        "lags": _integer("lags", lags, 1, _MAX_LAGS),
        "tolerance": _number("tolerance", tolerance, hint="give a non-negative number such as 0.5"),
        "step": _seconds("step", step),
        "time_tolerance": _seconds("time_tolerance", time_tolerance, optional=False),
        "resample": _seconds("resample", resample),
    }
    frames = _handover(model, data)
    held_out = [] if validate is None else _handover(model, validate)
    document, source, estimate = _native(_leeway.select_json, model._core, frames, held_out, args)
    result = Selection(model, document, source, estimate)
    _warn(result.estimate)
    return result


__all__ = ["Selection", "select"]
