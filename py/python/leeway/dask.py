"""leeway past one machine, on Dask distributed.

An estimate makes a handful of passes over the data (the facts of every
experiment, then one pass per refinement of the instrumental variables, and
one for the standard errors). :func:`estimate` maps each pass over the data
files on the workers of a Dask cluster — every task opens its own file, so
the data never pass through the driver — and the driver combines the
experiments' small summaries (moment sums, independent of the experiments'
lengths) in experiment order, solves, and broadcasts the next θ. The result
is the same, bit for bit, as :func:`leeway.estimate` on the same files, on
any number of workers, and when a worker dies mid-pass (Dask re-runs its
tasks elsewhere; every task is a pure function of its file and request)::

    from dask.distributed import Client, LocalCluster
    import leeway, leeway.dask

    client = Client(LocalCluster(n_workers=2, threads_per_worker=1))
    model = leeway.Model.load("ship.som")
    est = leeway.dask.estimate(model, ["run1.csv", "run2.csv"], client, method="iv3")

Workers keep each file they opened (validated once, then streamed from a
binary copy: memory does not grow with the file) for the passes that follow.
"""

from __future__ import annotations

import json
import os
import threading
from collections.abc import Sequence
from typing import Any

from . import Estimate, Model, _leeway
from . import mapreduce
from .errors import DataError

__all__ = ["estimate", "study"]

# Files opened on this worker, by model, path and load options.
_opened: dict[tuple[Any, ...], _leeway.Dataset] = {}
_lock = threading.Lock()


def _dataset(model: Model, path: str, options: dict[str, Any]) -> _leeway.Dataset:
    key = (
        model.source,
        model.file,
        options["aggregate"],
        path,
        options["step"],
        options["time_tolerance"],
        options["resample"],
    )
    with _lock:
        found = _opened.get(key)
    if found is None:
        found = mapreduce.open_file(model, path, options)
        with _lock:
            found = _opened.setdefault(key, found)
    return found


def _open(model: Model, path: str, options: dict[str, Any]) -> tuple[bytes, int]:
    d = _dataset(model, path, options)
    return d.summary(), len(d)


def _facts(model: Model, path: str, options: dict[str, Any], request: bytes) -> list[bytes]:
    return _dataset(model, path, options).facts(request)


def _run(model: Model, path: str, options: dict[str, Any], offset: int, request: bytes) -> list[bytes]:
    return _dataset(model, path, options).run(offset, request)


def estimate(
    model: Model,
    experiments: Sequence[str | os.PathLike[str]],
    client: Any = None,
    **options: Any,
) -> Estimate:
    """Estimates like :func:`leeway.estimate` (the same keyword options and
    defaults: ``method="iv3"``, …) from data files (CSV or Parquet, as
    ``leeway estimate --data`` reads them; a file with an ``experiment``
    column holds several experiments), each pass mapped over the files on the workers of
    ``client`` (a ``dask.distributed.Client``; the current one if ``None``)."""
    from distributed import get_client

    client = client if client is not None else get_client()
    paths = [os.fspath(p) for p in experiments]
    if not paths:
        raise DataError(
            "no experiment given",
            code="no-data",
            hint="pass at least one data file",
        )
    chosen = mapreduce.options(model, **options)
    n = len(paths)
    models, settings = [model] * n, [chosen] * n
    opened = client.gather(client.map(_open, models, paths, settings, pure=False))
    offsets = []
    total = 0
    for _, count in opened:
        offsets.append(total)
        total += count

    def facts(request: bytes) -> list[bytes]:
        shared = [client.scatter(request, broadcast=True)] * n
        parts = client.gather(client.map(_facts, models, paths, settings, shared, pure=False))
        return [b for part in parts for b in part]

    def run(request: bytes) -> list[bytes]:
        shared = [client.scatter(request, broadcast=True)] * n
        parts = client.gather(client.map(_run, models, paths, settings, offsets, shared, pure=False))
        return [b for part in parts for b in part]

    return mapreduce.estimate(model, paths, [s for s, _ in opened], facts, run, chosen)


def _study_run(model: Model, config: dict[str, Any], case: int, run: int) -> bytes:
    return _leeway.study_run(model._core, config, case, run)


def study(
    model: Model,
    client: Any = None,
    *,
    runs: int = 100,
    n: Sequence[int] = (1000, 2000, 3000, 4000, 5000),
    cases: Sequence[str] = ("low", "high"),
    seed: int = 2024,
    paper_iv: bool = False,
) -> dict[str, Any]:
    """The paper's Monte Carlo study (``leeway reproduce``; ``model`` is the
    study's ship, examples/models/ship.som) with its runs spread over the
    workers of ``client``: one task per run and case, each simulating its
    record from its own seed. Returns the study's figures per case and
    estimator and its claims (``cases``, ``claims``), the same as
    ``reproduce``'s ``results.json`` for the same options."""
    from distributed import get_client

    client = client if client is not None else get_client()
    config = {
        "runs": runs,
        "n": list(n),
        "cases": list(cases),
        "seed": seed,
        "paper_iv": paper_iv,
    }
    tasks = _leeway.study_tasks(config)
    k = len(tasks)
    futures = client.map(
        _study_run,
        [model] * k,
        [config] * k,
        [c for c, _ in tasks],
        [r for _, r in tasks],
        pure=False,
    )
    result: dict[str, Any] = json.loads(_leeway.study_summary(config, client.gather(futures)))
    return result
