"""leeway.dask on a LocalCluster of two worker processes: the distributed
estimate is `leeway estimate --json` on the same files, bit for bit; both
workers take part, each file opened by one of them; a worker killed in the middle of a pass changes nothing;
a worker's data error reaches the caller as the located DataError."""

from __future__ import annotations

import json
import os
import shutil
import time
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

distributed = pytest.importorskip("distributed")
import dask  # noqa: E402
from distributed import Client, LocalCluster  # noqa: E402
from distributed.diagnostics.plugin import WorkerPlugin  # noqa: E402

import leeway  # noqa: E402
import leeway.dask  # noqa: E402
from conftest import SHIP, run_leeway, ship_data  # noqa: E402


@pytest.fixture(scope="module")
def ship() -> leeway.Model:
    return leeway.Model.load(SHIP)


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> list[str]:
    """Four files of different lengths; the last holds two experiments."""
    tmp = tmp_path_factory.mktemp("campaign")
    paths = []
    for i, (n, seed) in enumerate([(900, 21), (1400, 22), (600, 23)]):
        path = tmp / f"run{i}.csv"
        ship_data(tmp, n, 1.0, seed).to_csv(path, index=False)
        paths.append(str(path))
    a = ship_data(tmp, 500, 1.0, 24).assign(experiment="a")
    b = ship_data(tmp, 700, 1.0, 25).assign(experiment="b")
    path = tmp / "two.csv"
    pd.concat([a, b]).to_csv(path, index=False)
    paths.append(str(path))
    return paths


def cluster() -> LocalCluster:
    return LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
    )


@pytest.fixture(scope="module")
def client():
    with cluster() as c, Client(c) as client:
        yield client


def cli(files: list[str], *args: str) -> str:
    data = [a for f in files for a in ("--data", f)]
    o = run_leeway("estimate", str(SHIP), *data, "--json", *args)
    return o.stdout


def distributed_json(ship: leeway.Model, files: list[str], client: Client, **options) -> str:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", leeway.LeewayWarning)
        return leeway.dask.estimate(ship, files, client, **options).to_json()


def same_document(ours: str, theirs: str) -> None:
    a, b = json.loads(ours), json.loads(theirs)
    assert b["errors"] == []
    # Floats compare by their shortest round-trip text: equal text, equal bits.
    assert json.dumps(a) == json.dumps(b)


def test_the_distributed_estimate_is_the_cli_estimate_bit_for_bit(
    ship: leeway.Model, files: list[str], client: Client
) -> None:
    cases = [
        ((), {}),
        # The workers read the heads the request names (the subsample's
        # warm start on workers: scenarios' `distributed.rs`, bit for bit).
        (("--refine-subsample", "0.5"), {"refine_subsample": 0.5}),
        (("--method", "ls", "--lags", "3"), {"method": "ls", "lags": 3}),
    ]
    for args, kwargs in cases:
        with distributed.get_task_stream(client) as stream:
            ours = distributed_json(ship, files, client, **kwargs)
        same_document(ours, cli(files, *args))
        # Every pass ran on the workers, and both took part.
        ran = {t["worker"] for t in stream.data if str(t["key"]).startswith("_run")}
        assert len(ran) == 2, ran
        if kwargs.get("refine_subsample"):
            # These short low-wind runs do not settle on half of them (nor
            # whole); the heads were refined on, on the workers.
            assert json.loads(ours)["diagnostics"]["subsample"]["refinements"] > 0, ours
    est = json.loads(ours)
    assert est["diagnostics"]["experiments"] == 5
    assert est["diagnostics"]["refinements"] == 0  # LS; the IV3 run above refined


def test_one_worker_of_two_threads_gives_the_same_bits(
    ship: leeway.Model, files: list[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    # The layout docs/distributed.md recommends on one machine: one worker
    # in the driver's process, a thread a core. Its two threads run a
    # pass's tasks side by side over the files it opened, sharing one cache
    # of openings and one trajectory budget: the same estimate, bit for
    # bit, and each file opened once.
    from leeway import mapreduce

    openings: dict[str, int] = {}
    original = mapreduce.open_file

    def counted(model, path, options):  # type: ignore[no-untyped-def]
        openings[path] = openings.get(path, 0) + 1
        return original(model, path, options)

    monkeypatch.setattr(mapreduce, "open_file", counted)
    with LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=":0") as c:
        with Client(c) as client, distributed.get_task_stream(client) as stream:
            ours = distributed_json(ship, files, client, method="iv3")
    same_document(ours, cli(files))
    assert openings == dict.fromkeys(files, 1), openings
    # Two tasks of one pass ran at the same time.
    runs = sorted(
        (s["start"], s["stop"])
        for t in stream.data
        if str(t["key"]).startswith("_run")
        for s in t["startstops"]
        if s["action"] == "compute"
    )
    assert any(b[0] < a[1] for a, b in zip(runs, runs[1:])), runs


def _count_openings() -> None:
    """On a worker: count `mapreduce.open_file` calls by path."""
    from leeway import mapreduce

    if not hasattr(mapreduce, "_openings"):
        original = mapreduce.open_file
        mapreduce._openings = {}  # type: ignore[attr-defined]

        def counted(model, path, options):  # type: ignore[no-untyped-def]
            mapreduce._openings[path] = mapreduce._openings.get(path, 0) + 1  # type: ignore[attr-defined]
            return original(model, path, options)

        mapreduce.open_file = counted  # type: ignore[assignment]
    mapreduce._openings.clear()  # type: ignore[attr-defined]


def _openings() -> dict[str, int]:
    from leeway import mapreduce

    return dict(getattr(mapreduce, "_openings", {}))


class SlowFirstWorker(WorkerPlugin):
    """Makes the first worker slow at moment passes: a pass then shares
    its tasks out differently from the opening."""

    def setup(self, worker) -> None:  # type: ignore[no-untyped-def]
        self.slow = worker.name == 0

    def transition(self, key, start, finish, **kwargs) -> None:  # type: ignore[no-untyped-def]
        if self.slow and finish == "executing" and str(key).startswith("_run"):
            time.sleep(0.1)


def test_each_file_is_opened_once_by_one_worker(ship: leeway.Model, files: list[str], tmp_path: Path) -> None:
    # A file's later passes run on the worker that opened (validated and
    # copied) it, not on whichever is free: IV3's passes open each of
    # eight files once in all, though the first worker is slow at moment
    # passes (a task that went to whichever worker is free would land on
    # the other), and both workers hold files. Two conditions make it exact:
    # - Work stealing is off. It may move a pass's last tasks to an idle
    #   worker, which then opens their files too (the same estimate, some
    #   work twice); on these millisecond tasks, often.
    # - Five files at least. Dask places a group of tasks that depends on
    #   fewer than five others by load alone, as it does tasks without
    #   dependencies (a "root-ish" group).
    files = [*files, *(str(shutil.copy(f, tmp_path / f"again{i}.csv")) for i, f in enumerate(files))]
    with dask.config.set({"distributed.scheduler.work-stealing": False}):
        with cluster() as c, Client(c) as client:
            client.register_plugin(SlowFirstWorker())
            client.run(_count_openings)
            same_document(distributed_json(ship, files, client, method="iv3"), cli(files))
            per_worker = client.run(_openings)
    total: dict[str, int] = {}
    for counts in per_worker.values():
        for path, k in counts.items():
            total[path] = total.get(path, 0) + k
    assert total == dict.fromkeys(files, 1), per_worker
    assert all(counts for counts in per_worker.values()), per_worker


def test_a_worker_killed_mid_pass_changes_nothing(
    ship: leeway.Model, files: list[str], tmp_path: Path
) -> None:
    marker = str(tmp_path / "killed")

    class KillOnce(WorkerPlugin):
        """Kills its worker's process the first time any worker starts a
        pass task (the marker file makes it once per test)."""

        def __init__(self, marker: str) -> None:
            self.marker = marker

        def transition(self, key, start, finish, **kwargs) -> None:  # type: ignore[no-untyped-def]
            if finish == "executing" and str(key).startswith("_run"):
                try:
                    os.close(os.open(self.marker, os.O_CREAT | os.O_EXCL))
                except FileExistsError:
                    return
                os._exit(1)

    with cluster() as c, Client(c) as client:
        client.register_plugin(KillOnce(marker))
        ours = distributed_json(ship, files, client, method="iv3")
        assert os.path.exists(marker), "no worker was killed"
    same_document(ours, cli(files))


def test_a_workers_data_error_is_the_located_data_error(
    ship: leeway.Model, files: list[str], client: Client, tmp_path: Path
) -> None:
    frame = pd.read_csv(files[0])
    frame.loc[40, "u"] = np.nan
    bad = tmp_path / "bad.csv"
    frame.to_csv(bad, index=False)
    with pytest.raises(leeway.DataError) as e:
        leeway.dask.estimate(ship, [files[1], str(bad)], client)
    assert "bad.csv" in str(e.value.location)
    assert "u" in str(e.value) and e.value.code == "data"


def test_the_distributed_study_gives_reproduces_figures(
    ship: leeway.Model, client: Client, tmp_path: Path
) -> None:
    with distributed.get_task_stream(client) as stream:
        ours = leeway.dask.study(ship, client, runs=3, n=[300, 600], seed=7)
    ran = {t["worker"] for t in stream.data if str(t["key"]).startswith("_study_run")}
    assert len(ran) == 2, ran
    o = run_leeway("reproduce", "--runs", "3", "--n", "300,600", "--seed", "7", "--out", str(tmp_path))
    assert o.returncode == 0, o.stderr
    theirs = json.loads((tmp_path / "results.json").read_text())
    assert set(ours["cases"]) == {"low", "high"}
    for case, figures in ours["cases"].items():
        for name, summary in figures["estimators"].items():
            reproduced = theirs["cases"][case]["estimators"][name]
            for key, value in summary.items():
                assert json.dumps(value) == json.dumps(reproduced[key]), (case, name, key)
    assert json.dumps(ours["claims"], sort_keys=True) == json.dumps(theirs["claims"], sort_keys=True)


def test_the_openings_are_shared_out_by_bytes_per_thread(tmp_path: Path) -> None:
    # Regression (CI, stop 55): Dask placed every quick opening task on one
    # worker, and each later pass followed the openings: one worker ran the
    # whole estimate. The openings now suggest a worker each, the largest
    # file first to the least loaded worker by bytes per thread.
    sizes = {"a": 4000, "b": 1000, "c": 3000, "d": 2000}
    paths = []
    for name, n in sizes.items():
        (tmp_path / name).write_bytes(b"x" * n)
        paths.append(str(tmp_path / name))

    class Threads:
        def __init__(self, threads: dict[str, int]) -> None:
            self.threads = threads

        def nthreads(self, callback_timeout: float) -> dict[str, int]:
            return self.threads

    places = leeway.dask._places(Threads({"w1": 1, "w2": 1}), paths)
    assert places == ["w1", "w1", "w2", "w2"], places  # 5000 bytes each
    # A worker of two threads takes twice the bytes.
    places = leeway.dask._places(Threads({"w1": 2, "w2": 1}), [*paths, str(tmp_path / "gone")])
    assert places == ["w1", "w1", "w2", "w1", "w2"], places  # 7000 bytes and 3001
    assert leeway.dask._places(Threads({}), paths) == [None] * 4
