"""Estimation as map and reduce, for any engine that can run a function
where the data are and bring small results back.

An estimate makes a handful of passes over the data: the facts of every
experiment (signs, means, bounds), then one pass per refinement of the
instrumental variables and one for the standard errors. Each pass maps a
request (bytes) over the experiments: a :class:`Dataset` — experiments
opened where they are, from a file (:func:`open_file`) or a DataFrame
(:func:`open_frame`) — answers it with one small summary per experiment
(moment sums, independent of the experiment's length). :func:`estimate` is
the driver: it combines the summaries in experiment order, solves, and sends
the next request. Whatever runs the map, the estimate is the same, bit for
bit, as :func:`leeway.estimate` on the same data. :mod:`leeway.dask` is this
on Dask; docs/distributed.md shows Spark.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from typing import Any

from . import _leeway
from ._api import Estimate, Model, _checked_options, _estimate_options, _native, _number, _warn
from ._data import Data, _handover
from .errors import OptionError

__all__ = ["Dataset", "options", "open_file", "open_frame", "estimate"]

Dataset = _leeway.Dataset

_DEFAULTS: dict[str, Any] = {
    "method": "iv3",
    "instruments": "simulated",
    "initial": "delayed",
    "centring": None,
    "combine": "summed",
    "nominal": None,
    "aggregate": False,
    "strict": False,
    "lags": 1,
    "max_refinements": 8,
    "runaway_guard": True,
    "refine_subsample": None,
    "step": None,
    "time_tolerance": 0.05,
    "resample": None,
}


def options(model: Model, **given: Any) -> dict[str, Any]:
    """The options of :func:`leeway.estimate` (its keyword arguments, with
    its defaults) as the native half takes them: give the same dict to
    every :func:`open_file`/:func:`open_frame` and to :func:`estimate`."""
    unknown = sorted(set(given) - set(_DEFAULTS))
    if unknown:
        raise OptionError(
            f"unknown option {unknown[0]!r}",
            code="invalid-option",
            hint=f"the options are {', '.join(_DEFAULTS)}",
        )
    chosen = {**_DEFAULTS, **given}
    return _estimate_options(model, **chosen)


def _checked(options: Any) -> dict[str, Any]:
    """Options as :func:`options` made them, checked again (a dict may have
    been edited or built by hand on its way to a worker)."""
    if not isinstance(options, dict) or set(options) != set(_DEFAULTS):
        raise OptionError(
            f"options is not what leeway.mapreduce.options returns ({type(options).__name__})",
            code="invalid-option",
            hint="build the options with leeway.mapreduce.options(model, ...)",
        )
    nominal = options["nominal"]
    if nominal is not None:
        if isinstance(nominal, (str, bytes)) or not isinstance(nominal, (list, tuple)):
            raise OptionError(
                f"options['nominal'] is a {type(nominal).__name__}",
                code="invalid-nominal",
                hint="build the options with leeway.mapreduce.options(model, nominal={...})",
            )
        nominal = [_number(f"nominal[{i}]", v, code="invalid-nominal") for i, v in enumerate(nominal)]
    return {**_checked_options(options), "nominal": nominal}


def _path(path: Any) -> str:
    try:
        text = os.fspath(path)
    except TypeError:
        text = None
    if not isinstance(text, str):
        raise OptionError(
            f"{path!r} is a {type(path).__name__}, not a path",
            code="invalid-option",
            hint="name data files by str or pathlib.Path",
        )
    return text


def open_file(model: Model, path: str | os.PathLike[str], options: dict[str, Any]) -> Dataset:
    """A data file's experiments (CSV or Parquet, as ``leeway estimate
    --data`` reads it), validated once and streamed on every pass."""
    return _native(_leeway.Dataset.open, model._core, _path(path), _checked(options))


def open_frame(model: Model, data: Data, options: dict[str, Any]) -> Dataset:
    """The experiments of ``data`` (anything :func:`leeway.estimate` takes),
    validated as files are and held in memory."""
    checked = _checked(options)
    return _native(_leeway.Dataset.from_frames, model._core, _handover(model, data), checked)


def estimate(
    model: Model,
    names: Sequence[str],
    summaries: Sequence[bytes],
    facts: Callable[[bytes], list[bytes]],
    run: Callable[[bytes], list[bytes]],
    options: dict[str, Any],
) -> Estimate:
    """Drives an estimate whose passes run elsewhere. ``names`` and
    ``summaries`` are each dataset's name and :meth:`Dataset.summary`, in
    the order that fixes the experiments' order; ``facts(request)`` returns
    ``[d.facts(request) for d in datasets]`` flattened, ``run(request)``
    returns ``[d.run(offset_d, request) for d in datasets]`` flattened, where
    ``offset_d`` is the number of experiments in the datasets before ``d``.
    An exception raised by ``facts`` or ``run`` is raised from here."""
    document = _native(
        _leeway.estimate_mapped,
        model._core,
        [str(n) for n in names],
        [bytes(b) for b in summaries],
        _checked(options),
        facts,
        run,
    )
    result = Estimate(document)
    _warn(result)
    return result
