"""leeway past one machine, on Dask distributed.

An estimate makes a handful of passes over the data (the facts of every
experiment, then one pass per refinement of the instrumental variables, and
one for the standard errors). :func:`estimate` maps each pass over the data
files on the workers of a Dask cluster — every task opens its own file, so
the data never pass through the driver — and the driver combines the
experiments' small summaries (moment sums, independent of the experiments'
lengths) in experiment order, solves, and sends the next θ. The result
is the same, bit for bit, as :func:`leeway.estimate` on the same files, on
any number of workers, and when a worker dies mid-pass (Dask re-runs its
tasks elsewhere; every task is a pure function of its file and request)::

    from dask.distributed import Client, LocalCluster
    import leeway, leeway.dask

    # One worker a machine, a thread a core: the tasks run in Rust without
    # the GIL (docs/distributed.md).
    client = Client(LocalCluster(n_workers=1, threads_per_worker=2, processes=False))
    model = leeway.Model.load("ship.som")
    est = leeway.dask.estimate(model, ["run1.csv", "run2.csv"], client, method="iv3")

Workers keep each file they opened (validated once, then streamed from a
binary copy: memory does not grow with the file) for the passes of one
estimate — each pass's task of a file takes the file's opening as an
argument, so Dask runs it on the worker holding that opening, without
pinning it there (a lost worker's openings are made again elsewhere) —
and only while the file is the one they opened: every task checks
the file's identity (size, modification and change times, inode and a hash of its first
and last 64 KiB) against the identity its first opening reported to the
driver, and a file that changed during the estimate is a located
``DataError`` (``data-changed``), never an estimate of old or mixed content.
The cache is bounded (``LEEWAY_DASK_CACHE_SIZE`` datasets a worker, 256 by
default, least recently used dropped first) and cleared when the estimate
ends.
"""

from __future__ import annotations

import asyncio
import hashlib
import json
import os
import threading
import time
import uuid
from collections import OrderedDict
from collections.abc import Callable, Sequence
from typing import Any

from . import _design, _leeway
from ._api import Estimate, Model, _flag, _integer, _native, _number, _text
from . import mapreduce
from .errors import DataError, EstimateError, LeewayError, OptionError

__all__ = ["estimate", "study", "verify_design"]

# What a file was when a task opened it: size, modification and change
# times (ns), inode, device, and a hash of its size and first and last
# 64 KiB. The change time cannot be set back (as `touch -d` sets the
# modification time), so a rewrite that keeps size and modification time
# is seen too.
Identity = tuple[int, int, int, int, int, str]

_FINGERPRINT = 64 * 1024


class _Opened:
    __slots__ = ("dataset", "identity")

    def __init__(self, dataset: _leeway.Dataset, identity: Identity) -> None:
        self.dataset = dataset
        self.identity = identity


def _cache_size() -> int:
    try:
        return max(1, int(os.environ.get("LEEWAY_DASK_CACHE_SIZE", "256")))
    except ValueError:
        return 256


# Files opened on this worker, by estimate, model, path and load options,
# least recently used first.
_opened: OrderedDict[tuple[Any, ...], _Opened] = OrderedDict()
_lock = threading.Lock()


def _changed(path: str, why: str) -> DataError:
    return DataError(
        f"the file changed during the estimate ({why}); no estimate is made from old or mixed content",
        code="data-changed",
        location=path,
        hint="the file changed during the estimate; run the estimate again once it is written",
    )


def _identity(path: str) -> Identity:
    """The file's identity now: size, modification and change times, inode,
    device and a fingerprint of its size and its first and last 64 KiB
    (cheap enough for every task). Raises ``OSError`` when it cannot be read."""
    with open(path, "rb") as f:
        st = os.fstat(f.fileno())
        h = hashlib.blake2b(digest_size=16)
        h.update(st.st_size.to_bytes(8, "little"))
        h.update(f.read(_FINGERPRINT))
        if st.st_size > _FINGERPRINT:
            f.seek(max(_FINGERPRINT, st.st_size - _FINGERPRINT))
            h.update(f.read(_FINGERPRINT))
    return (st.st_size, st.st_mtime_ns, st.st_ctime_ns, st.st_ino, st.st_dev, h.hexdigest())


def _differs(first: Sequence[Any], second: Sequence[Any]) -> str | None:
    """What differs between two identities, said for a person (or ``None``)."""
    a, b = tuple(first), tuple(second)  # whatever container a serializer made of them
    if a[3:5] != b[3:5]:
        return "it was replaced by another file"
    if a[0] != b[0]:
        return f"its size went from {a[0]} to {b[0]} bytes"
    if a[5] != b[5]:
        return "its content changed"
    if a[1] != b[1]:
        return "its modification time changed"
    if a[2] != b[2]:
        return "it was written to, or its status changed"
    return None


def _check(path: str, expected: Identity) -> None:
    """Raises ``data-changed`` unless the file still has ``expected``'s identity."""
    try:
        now = _identity(path)
    except OSError as e:
        raise _changed(path, f"it can no longer be read: {e.strerror or e}") from None
    why = _differs(expected, now)
    if why is not None:
        raise _changed(path, why)


def _key(model: Model, path: str, options: dict[str, Any], token: str) -> tuple[Any, ...]:
    return (
        token,
        model.source,
        model.file,
        options["aggregate"],
        path,
        options["step"],
        options["time_tolerance"],
        options["resample"],
    )


def _dataset(
    model: Model, path: str, options: dict[str, Any], token: str, expected: Identity | None
) -> _Opened:
    """This estimate's dataset of ``path`` on this worker, opened now or
    before, and checked: the file is the one it was opened from, and (for
    every task after the first opening) the one the driver was told of."""
    key = _key(model, path, options, token)
    with _lock:
        found = _opened.get(key)
        if found is not None:
            _opened.move_to_end(key)
    if found is not None:
        if expected is not None and (why := _differs(expected, found.identity)) is not None:
            raise _changed(path, why)
        _check(path, found.identity)
        return found
    before: Identity | None
    try:
        before = _identity(path)
    except OSError:
        if expected is not None:
            raise _changed(path, "it can no longer be read") from None
        before = None  # the loader says why, located, as for any file
    if expected is not None and before is not None and (why := _differs(expected, before)) is not None:
        raise _changed(path, why)
    try:
        dataset = mapreduce.open_file(model, path, options)
    except LeewayError:
        # A file found broken because it changed while it was read is a
        # changed file (run again), not a broken one.
        if before is not None:
            _check(path, before)
        raise
    if before is None:  # opened although it could not be read a moment ago
        raise _changed(path, "it appeared while being opened")
    _check(path, before)  # not rewritten while it was validated
    opened = _Opened(dataset, before)
    with _lock:
        opened = _opened.setdefault(key, opened)
        _opened.move_to_end(key)
        size = _cache_size()
        while len(_opened) > size:
            _opened.popitem(last=False)
    return opened


def _forget(token: str) -> int:
    """Drops an estimate's datasets from this worker's cache (how many)."""
    with _lock:
        keys = [k for k in _opened if k[0] == token]
        for k in keys:
            del _opened[k]
    return len(keys)


# A task answers ("ok", value) or ("error", LeewayError): a located error of
# the data is an answer, not a failure Dask should retry; `retries=` is
# left to what a lost worker or connection causes.
Answer = tuple[str, Any]


def _answer(f: Callable[[], Any]) -> Answer:
    try:
        return ("ok", f())
    except LeewayError as e:
        return ("error", e)


def _open(model: Model, path: str, options: dict[str, Any], token: str) -> Answer:
    def opened() -> tuple[bytes, int, Identity]:
        o = _dataset(model, path, options, token, None)
        return o.dataset.summary(), len(o.dataset), o.identity

    return _answer(opened)


def _facts(
    opening: Answer,
    model: Model,
    path: str,
    options: dict[str, Any],
    token: str,
    identity: Identity,
    request: bytes,
) -> Answer:
    # `opening` (the file's `_open` answer) is not read: it is there so that
    # Dask runs this task on the worker that holds the file open.
    def answered() -> list[bytes]:
        o = _dataset(model, path, options, token, identity)
        out = _native(o.dataset.facts, request)
        _check(path, identity)  # not rewritten while it was read
        return out

    return _answer(answered)


def _verify(path: str, identity: Identity) -> Answer:
    return _answer(lambda: _check(path, identity))


def _run(
    opening: Answer,
    model: Model,
    path: str,
    options: dict[str, Any],
    token: str,
    identity: Identity,
    offset: int,
    request: bytes,
) -> Answer:
    # `opening`: as for `_facts`, where the task runs, not what it reads.
    def answered() -> list[bytes]:
        o = _dataset(model, path, options, token, identity)
        out = _native(o.dataset.run, offset, request)
        _check(path, identity)
        return out

    return _answer(answered)


# What a wait that ran out raises: distributed raises asyncio's, which on
# Python 3.10 is not the builtin TimeoutError.
_TIMEOUTS: tuple[type[BaseException], ...] = (TimeoutError, asyncio.TimeoutError)

# Seconds a pass waits while the scheduler has no worker at all, unless
# told otherwise (`no_workers_timeout=`), and how often it asks.
_NO_WORKERS_TIMEOUT = 30.0
_POLL = 1.0


def _lost_types() -> tuple[type[BaseException], ...]:
    """What a lost worker, connection or stalled cluster raises in the
    client: worth one more attempt of the pass."""
    from asyncio import CancelledError as AsyncCancelled
    from concurrent.futures import CancelledError

    from distributed.client import ClosedClientError
    from distributed.comm.core import CommClosedError
    from distributed.scheduler import KilledWorker

    return (CommClosedError, KilledWorker, *_TIMEOUTS, OSError, CancelledError, AsyncCancelled, ClosedClientError)


def _no_worker_types() -> tuple[type[BaseException], ...]:
    """What the scheduler fails a task with when it had no worker to run it
    on for Dask's ``distributed.scheduler.no-workers-timeout`` (a task that
    was already waiting when the last worker left gets
    ``NoValidWorkerError``, as a task whose restrictions no worker meets):
    another attempt would wait as long again."""
    from distributed.scheduler import NoValidWorkerError, NoWorkerError

    return (NoWorkerError, NoValidWorkerError)


def _no_worker(what: str, why: str, wait: str) -> EstimateError:
    return EstimateError(
        f"the {what} pass failed: {why}",
        code="worker-lost",
        hint="start workers, or see why they stopped (the workers' logs, client.scheduler_info()), "
        f"and run it again; {wait} is how long a pass waits with no worker, if workers take longer to start",
    )


class _Workers:
    """Whether the cluster still has a worker. Dask waits for workers to
    come for as long as it is asked to, so a pass whose workers all died
    would wait out its whole ``timeout``, twice: :meth:`check` raises
    ``worker-lost`` once the scheduler has had no worker for ``grace``
    seconds (``None``: never)."""

    def __init__(self, client: Any, what: str, grace: float | None) -> None:
        self.client, self.what, self.grace = client, what, grace
        self.none_since: float | None = None  # kept across the pass's attempts

    def check(self) -> None:
        if self.grace is None:
            return
        # A scheduler that does not answer raises OSError or TimeoutError:
        # a lost connection, as while waiting for the pass.
        if self.client.nthreads(callback_timeout=30):
            self.none_since = None
            return
        now = time.monotonic()
        if self.none_since is None:
            self.none_since = now
        elif now - self.none_since >= self.grace:
            why = f"the cluster has had no worker for {self.grace:g} s"
            raise _no_worker(self.what, why, "no_workers_timeout=")


def _wait(client: Any, futures: list[Any], timeout: float | None, workers: _Workers) -> None:
    """Returns when every future is done; raises ``TimeoutError`` after
    ``timeout`` seconds, and ``worker-lost`` as ``workers`` says, asking
    the scheduler every second."""
    from distributed import wait

    deadline = None if timeout is None else time.monotonic() + timeout
    while True:
        step = _POLL if deadline is None else min(_POLL, deadline - time.monotonic())
        if step <= 0:
            raise TimeoutError
        try:
            # `wait` waits through the default client: make it this one
            # (a client made with set_as_default=False is not).
            with client.as_current():
                wait(futures, timeout=step)  # type: ignore[no-untyped-call]
            return
        except _TIMEOUTS:
            pass
        workers.check()


def _submitted(client: Any, f: Callable[..., Answer], args: tuple[list[Any], ...], places: list[str | None] | None) -> list[Any]:
    if places is None:
        return list(client.map(f, *args, pure=False, retries=2))
    return [
        client.submit(f, *task, pure=False, retries=2)
        if at is None
        else client.submit(f, *task, pure=False, retries=2, workers=[at], allow_other_workers=True)
        for at, task in zip(places, zip(*args))
    ]


def _places(client: Any, paths: list[str]) -> list[str | None]:
    """A worker for each file's opening, sharing the bytes out by threads
    (the largest file first, to the least loaded worker). Later passes run
    where a file was opened, so Dask's own placement of these quick tasks
    by load alone could leave a worker with every file and the others
    idle for the whole estimate. A file the driver cannot see counts as
    one byte: the files are then shared out by count."""
    try:
        threads = {w: max(int(k), 1) for w, k in client.nthreads(callback_timeout=30).items()}
    except Exception:  # noqa: BLE001 — a hint only: the pass itself reports a closed client or a lost scheduler
        threads = {}
    if not threads:
        return [None] * len(paths)

    def size(path: str) -> int:
        try:
            return max(os.path.getsize(path), 1)
        except OSError:
            return 1

    load = dict.fromkeys(sorted(threads), 0)
    places: list[str | None] = [None] * len(paths)
    for i in sorted(range(len(paths)), key=lambda i: (-size(paths[i]), i)):
        at = min(load, key=lambda w: ((load[w] + size(paths[i])) / threads[w], w))
        load[at] += size(paths[i])
        places[i] = at
    return places


def _mapped(
    client: Any,
    what: str,
    f: Callable[..., Answer],
    timeout: float | None,
    no_workers: float | None,
    *args: list[Any],
    keep: list[Any] | None = None,
    places: list[str | None] | None = None,
) -> list[Any]:
    """``f`` mapped over ``args`` on the cluster (each task retried twice by
    Dask), waited for at most ``timeout`` seconds; a lost worker or
    connection, or a timeout, costs one more attempt of the whole pass and
    then ends in ``EstimateError`` (``worker-lost``), never a hang. A
    cluster with no worker for ``no_workers`` seconds, or a task Dask
    failed for want of a worker, ends the pass at once in ``worker-lost``.
    A task's ``LeewayError`` is raised as it is. ``keep`` receives the
    futures of the attempt that answered: their results stay on the
    workers that made them while it holds them. ``places`` suggests a
    worker for each task (Dask may run it elsewhere, as when that worker
    is gone)."""
    lost, no_worker = _lost_types(), _no_worker_types()
    workers = _Workers(client, what, no_workers)
    last: BaseException | None = None
    for _ in range(2):
        futures: list[Any] = []
        try:
            futures = _submitted(client, f, args, places)
            start = time.monotonic()
            _wait(client, futures, timeout, workers)
            left = None if timeout is None else max(1.0, timeout - (time.monotonic() - start))
            # Every task is done: a gather that waits is one whose results
            # were lost with their worker, bounded as a wait without one.
            answers = _gather(client, futures, _sooner(left, no_workers))
        except LeewayError:  # no worker left: another attempt would find none
            _cancel(client, futures)
            raise
        except no_worker as e:
            _cancel(client, futures)
            first = str(e).splitlines()[0] if str(e) else ""
            why = f"Dask found no worker to run it on ({type(e).__name__}: {first})"
            raise _no_worker(what, why, "Dask's distributed.scheduler.no-workers-timeout") from None
        except lost as e:
            last = e
            _cancel(client, futures)
            continue
        for status, value in answers:
            if status == "error":
                raise value
        if keep is not None:
            keep[:] = futures
        return [value for _, value in answers]
    reason = "timed out" if isinstance(last, _TIMEOUTS) else f"{type(last).__name__}: {last}"
    raise EstimateError(
        f"the {what} pass failed twice: a worker or the connection to the cluster was lost ({reason})",
        code="worker-lost",
        hint="check the cluster (client.scheduler_info(), the workers' logs) and run the estimate again; "
        "pass timeout= (seconds a pass may take) if passes are legitimately slow",
    )


def _sooner(a: float | None, b: float | None) -> float | None:
    """The shorter of two limits, either of which may be none (``None``)."""
    return b if a is None else a if b is None else min(a, b)


def _gather(client: Any, futures: list[Any], timeout: float | None) -> list[Answer]:
    gather = getattr(client, "_gather", None)
    if gather is None or timeout is None:
        answers: list[Answer] = client.gather(futures)
        return answers
    result: list[Answer] = client.sync(gather, futures, callback_timeout=timeout)
    return result


def _cancel(client: Any, futures: list[Any]) -> None:
    try:
        if futures:
            client.cancel(futures)
    except Exception:  # a cluster already gone: nothing left to cancel
        pass


def _clear(client: Any, token: str) -> None:
    """Drops the estimate's datasets on every worker; a worker already gone,
    or a cluster that does not answer within 30 s, is left as it is (the
    bounded cache drops them in time)."""
    try:
        client.sync(client._run, _forget, token, on_error="ignore", callback_timeout=30)
    except Exception:
        pass


_NO_WORKERS_HINT = "seconds a pass waits while the cluster has no worker, or None to wait for one"


def _seconds(name: str, value: float | None, hint: str) -> float | None:
    """A positive number of seconds, or ``None``."""
    if value is None:
        return None
    seconds = _number(name, value)
    if seconds <= 0:
        raise OptionError(f"{name}={seconds} is not positive", code="invalid-option", hint=hint)
    return seconds


def _client(client: Any) -> Any:
    if client is None:
        from distributed import get_client

        try:
            return get_client()
        except ValueError as e:
            raise OptionError(
                f"no Dask client: {e}",
                code="invalid-option",
                hint="pass client=Client(...) (dask.distributed), or create one first",
            ) from None
    if not all(hasattr(client, a) for a in ("map", "gather", "sync")):
        raise OptionError(
            f"client is a {type(client).__name__}, not a dask.distributed.Client",
            code="invalid-option",
            hint="pass client=Client(...) (dask.distributed)",
        )
    return client


def _paths(experiments: Any) -> list[str]:
    if isinstance(experiments, (str, bytes, os.PathLike)):
        experiments = [experiments]
    if not isinstance(experiments, Sequence):
        raise OptionError(
            f"experiments is a {type(experiments).__name__}, not a list of paths",
            code="invalid-option",
            hint="pass the data files as a list of str or pathlib.Path",
        )
    return [mapreduce._path(p) for p in experiments]


def estimate(
    model: Model,
    experiments: Sequence[str | os.PathLike[str]],
    client: Any = None,
    *,
    timeout: float | None = 3600.0,
    no_workers_timeout: float | None = _NO_WORKERS_TIMEOUT,
    **options: Any,
) -> Estimate:
    """Estimates like :func:`leeway.estimate` (the same keyword options and
    defaults: ``method="iv3"``, …) from data files (CSV or Parquet, as
    ``leeway estimate --data`` reads them; a file with an ``experiment``
    column holds several experiments), each pass mapped over the files on the workers of
    ``client`` (a ``dask.distributed.Client``; the current one if ``None``).

    Each task is retried twice by Dask and a failed pass once more; a pass
    that does not end within ``timeout`` seconds, or fails again, raises
    ``EstimateError`` (``worker-lost``). So does, at once, a pass during
    which the cluster has had no worker for ``no_workers_timeout`` seconds
    (30 by default; ``None`` waits for workers to come, up to ``timeout``),
    or whose tasks Dask failed for want of a worker (``NoWorkerError``,
    ``NoValidWorkerError``). A file that changes during the estimate raises
    ``DataError`` (``data-changed``)."""
    client = _client(client)
    timeout = _seconds("timeout", timeout, "seconds a pass may take, or None")
    no_workers = _seconds("no_workers_timeout", no_workers_timeout, _NO_WORKERS_HINT)
    paths = _paths(experiments)
    if not paths:
        raise DataError(
            "no experiment given",
            code="no-data",
            hint="pass at least one data file",
        )
    chosen = mapreduce.options(model, **options)
    n = len(paths)
    models, settings = [model] * n, [chosen] * n
    token = uuid.uuid4().hex
    tokens = [token] * n
    # Each file's opening, held while the estimate runs: its later tasks
    # take it as an argument, and Dask runs a task where its arguments are,
    # so a file is validated and copied once, by the worker that opened it,
    # not again by every worker its tasks land on. Nothing is pinned: when
    # that worker is lost, Dask opens the file again on another.
    openings: list[Any] = []
    try:
        opened = _mapped(
            client, "open", _open, timeout, no_workers, models, paths, settings, tokens,
            keep=openings, places=_places(client, paths),
        )
        identities = [identity for _, _, identity in opened]
        offsets = []
        total = 0
        for _, count, _ in opened:
            offsets.append(total)
            total += count

        # The request (θ and the plan, a few kB) travels in each task's
        # arguments: no scatter, whose broadcast can wedge on a lost worker.
        def facts(request: bytes) -> list[bytes]:
            parts = _mapped(
                client, "facts", _facts, timeout, no_workers,
                openings, models, paths, settings, tokens, identities, [request] * n,
            )
            return [b for part in parts for b in part]

        def run(request: bytes) -> list[bytes]:
            parts = _mapped(
                client,
                "moment",
                _run,
                timeout,
                no_workers,
                openings,
                models,
                paths,
                settings,
                tokens,
                identities,
                offsets,
                [request] * n,
            )
            return [b for part in parts for b in part]

        result = mapreduce.estimate(model, paths, [s for s, _, _ in opened], facts, run, chosen)
        # Every file is still the one the estimate read (a change after its
        # last pass would otherwise go unseen): one light task per file.
        _mapped(client, "final", _verify, timeout, no_workers, paths, identities)
        return result
    finally:
        openings.clear()
        _clear(client, token)


def _study_run(model: Model, config: dict[str, Any], case: int, run: int) -> Answer:
    return _answer(lambda: _native(_leeway.study_run, model._core, config, case, run))


def study(
    model: Model,
    client: Any = None,
    *,
    runs: int = 100,
    n: Sequence[int] = (1000, 2000, 3000, 4000, 5000),
    cases: Sequence[str] = ("low", "high"),
    seed: int = 2024,
    paper_iv: bool = False,
    no_workers_timeout: float | None = _NO_WORKERS_TIMEOUT,
) -> dict[str, Any]:
    """The paper's Monte Carlo study (``leeway reproduce``; ``model`` is the
    study's ship, examples/models/ship.som) with its runs spread over the
    workers of ``client``: one task per run and case, each simulating its
    record from its own seed. Returns the study's figures per case and
    estimator and its claims (``cases``, ``claims``), the same as
    ``reproduce``'s ``results.json`` for the same options. A cluster left
    with no worker for ``no_workers_timeout`` seconds raises
    ``EstimateError`` (``worker-lost``), as in :func:`estimate`."""
    client = _client(client)
    no_workers = _seconds("no_workers_timeout", no_workers_timeout, _NO_WORKERS_HINT)
    if isinstance(n, (str, bytes)) or not isinstance(n, Sequence):
        raise OptionError(f"n={n!r} is not a list of record lengths", code="invalid-option", hint="n=[1000, 2000]")
    if isinstance(cases, (str, bytes)) or not isinstance(cases, Sequence):
        raise OptionError(f"cases={cases!r} is not a list of names", code="invalid-option", hint='cases=["low", "high"]')
    config = {
        "runs": _integer("runs", runs, 1, 1 << 32),
        "n": [_integer("n", v, 1, 1 << 40) for v in n],
        "cases": [_text("cases", c) for c in cases],
        "seed": _integer("seed", seed, 0, (1 << 64) - 1),
        "paper_iv": _flag("paper_iv", paper_iv),
    }
    tasks = _native(_leeway.study_tasks, config)
    k = len(tasks)
    runs_done = _mapped(
        client,
        "study",
        _study_run,
        None,  # a study's runs take what they take; a lost worker is retried
        no_workers,
        [model] * k,
        [config] * k,
        [c for c, _ in tasks],
        [r for _, r in tasks],
    )
    result: dict[str, Any] = json.loads(_native(_leeway.study_summary, config, runs_done))
    return result


# Designs made on this worker, by model, plan and options, least recently
# used first: a worker's trials of one verification share one design.
_designs: OrderedDict[tuple[Any, ...], _leeway.Designed] = OrderedDict()
_designs_lock = threading.Lock()
_DESIGNS_KEPT = 4


def _worker_design(model: Model, plan: tuple[str, bool, str, bool], options: dict[str, Any]) -> _leeway.Designed:
    """The design of (model, plan, options) on this worker: made once (a
    design is deterministic, so it is the driver's), then reused."""
    key = (model.source, model.file, model.aggregate, plan[:2], tuple(sorted(options.items())))
    # Held while designing: the worker's other threads wait for this design
    # rather than make it again.
    with _designs_lock:
        found = _designs.get(key)
        if found is None:
            found = _native(_leeway.Designed.make, model._core, *plan, options)
            _designs[key] = found
            while len(_designs) > _DESIGNS_KEPT:
                _designs.popitem(last=False)
        _designs.move_to_end(key)
        return found


def _design_trial(
    model: Model, plan: tuple[str, bool, str, bool], options: dict[str, Any], index: int
) -> Answer:
    return _answer(lambda: _native(_worker_design(model, plan, options).trial, index))


def verify_design(
    model: Model,
    plan: _design.Plan,
    client: Any = None,
    *,
    runs: int,
    seed: int = 0,
    target: float | str | None = None,
    pilot: int = 100,
    method: str = "iv3",
    no_workers_timeout: float | None = _NO_WORKERS_TIMEOUT,
) -> _design.Design:
    """:func:`leeway.design` with ``verify=runs``, the Monte Carlo trials of
    the verification spread over the workers of ``client`` (one task per
    trial; each worker makes the design once from the model, the plan and
    the options, as the driver does, rather than receive it). Returns the
    same ``Design`` as ``leeway.design(model, plan, verify=runs, …)``, its
    verification bit for bit, when the design's verdict passes; when it
    fails, the design is returned with its failing verification — the
    other runs the design tried are verified in turn by
    :func:`leeway.design` only. A design that does not keep every held sign
    is returned unverified (``verification`` is ``None``), as locally. A
    cluster left with no worker for ``no_workers_timeout`` seconds raises
    ``EstimateError`` (``worker-lost``), as in :func:`estimate`."""
    client = _client(client)
    no_workers = _seconds("no_workers_timeout", no_workers_timeout, _NO_WORKERS_HINT)
    options = _design._options(target, seed, pilot, method)
    count = _design._runs("runs", runs, optional=False)
    assert count is not None  # not optional
    plan_text = _design._plan(plan)
    core = _design._designed(model, plan_text, options)
    if not core.verifiable:
        return _design._design(core, _native(core.document))
    trials = _mapped(
        client,
        "verification",
        _design_trial,
        None,  # trials take what they take; a lost worker is retried
        no_workers,
        [model] * count,
        [plan_text] * count,
        [options] * count,
        list(range(count)),
    )
    return _design._design(core, _native(core.summarise, trials))
