"""leeway at scale, beside pandas and the floors.

For each size (rows) the ship's paper data is written as CSV (by the bench
binary `stream-memory write`, in flat memory) and as Parquet (pandas), and
``leeway estimate --json`` is timed per method and format, best of
``--runs``; beside it: pandas reading the same file alone (CPU of the read
only, in its own process), and the floors — the file's bytes at the memory
bandwidth measured here (one read), and the moment sums' FLOP at the
core's peak (``flops`` bench binary × samples × moment passes, where the
passes are ``refinements + 1`` from the JSON). CPU is user + system of the
whole process (both cores count); RSS is the peak.

``--campaign FILES`` adds a campaign of that many 10⁶-sample Parquet files
estimated with IV3 in one process (``leeway estimate --data`` every file)
and on Dask LocalClusters (``leeway.dask``, when the ``leeway`` package is
importable) of both layouts docs/distributed.md compares — one worker of a
thread a core in this process, and one-thread worker processes, a core
each — compared bit for bit.

``--instructions`` counts instead of timing: each method and format run
once under valgrind's callgrind (the ``profiling`` build, which has the
symbols), and the instructions a sample of each phase of the estimate
printed; each profile stays in DIR for ``callgrind_annotate``. The same
command gives the same count to about a part in a million, so two builds
compare where a host's drift hides a few per cent of time (compare them
with the same DIR: the count moves by about 0.1 % with the length of the
paths). It is about 150× slower than a plain run: use 10⁵ rows.

    cargo build --release -p leeway-cli -p leeway-bench
    python bench/scale.py /tmp/scale --rows 1000000 10000000 --runs 3
    python bench/scale.py /tmp/scale --rows 1000000 --campaign 10
    cargo build --profile profiling -p leeway-cli
    python bench/scale.py /tmp/scale --rows 100000 --instructions

Prints Markdown tables (docs/performance.md quotes them with the load).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MODEL = ROOT / "examples" / "models" / "ship.som"


def run(cmd: list[str], out: Path | None = None) -> tuple[float, float, float]:
    """Wall seconds, CPU seconds (user + system) and peak RSS (MiB) of one
    run, as GNU time measures them (the peak is the command's own, not
    this process's at the fork)."""
    with open(out or os.devnull, "wb") as sink, tempfile.NamedTemporaryFile("r") as times:
        done = subprocess.run(
            ["/usr/bin/time", "-f", "%e %U %S %M", "-o", times.name, *cmd],
            stdout=sink, stderr=subprocess.DEVNULL,
        )
        if done.returncode not in (0, 1):
            raise SystemExit(f"failed ({done.returncode}): {' '.join(cmd)}")
        wall, user, system, kib = times.read().split()[-4:]
    return float(wall), float(user) + float(system), int(kib) / 1024


def best(runs: int, cmd: list[str], out: Path | None = None) -> tuple[float, float, float]:
    """The run of least CPU among `runs`."""
    return min((run(cmd, out) for _ in range(runs)), key=lambda r: r[1])


def pandas_read(path: Path, runs: int) -> float:
    """CPU seconds of pandas reading the file alone (import excluded), best of runs."""
    reader = "read_parquet" if path.suffix == ".parquet" else "read_csv"
    code = (
        "import sys, time, pandas as pd\n"
        "t = time.process_time()\n"
        f"pd.{reader}(sys.argv[1])\n"
        "print(time.process_time() - t)\n"
    )
    times = []
    for _ in range(runs):
        out = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True, check=True)
        times.append(float(out.stdout))
    return min(times)


def bandwidth() -> float:
    """Memory bandwidth, bytes a second read (a copy of 512 MiB, best of 5; read + write counted)."""
    import numpy as np

    a = np.ones(64 << 20)
    b = np.empty_like(a)
    b[:] = a
    best_s = min(_copy_seconds(a, b) for _ in range(5))
    return 2 * a.nbytes / best_s


def _copy_seconds(a, b) -> float:
    t = time.perf_counter()
    b[:] = a
    return time.perf_counter() - t


def write_data(bench: Path, directory: Path, rows: int) -> tuple[Path, Path]:
    csv = directory / f"ship-{rows}.csv"
    parquet = csv.with_suffix(".parquet")
    if not csv.exists():
        subprocess.run([str(bench / "stream-memory"), "write", str(rows), str(csv)], check=True, stdout=subprocess.DEVNULL)
    if not parquet.exists():
        to_parquet(csv, parquet)
    return csv, parquet


def to_parquet(csv: Path, parquet: Path) -> None:
    """The CSV file as Parquet (pandas, in its own process: this one stays small)."""
    code = "import sys, pandas as pd\npd.read_csv(sys.argv[1]).to_parquet(sys.argv[2], index=False)\n"
    subprocess.run([sys.executable, "-c", code, str(csv), str(parquet)], check=True)


def flops(bench: Path, data: Path, method: str) -> tuple[int, float]:
    out = subprocess.run(
        [str(bench / "flops"), str(MODEL), str(data), method, "--aggregate"],
        capture_output=True, text=True, check=True,
    ).stdout.split()
    return int(out[0]), float(out[1])


def estimate_row(args, bench: Path, data: Path, method: str, rows: int, read_cpu: float, bw: float) -> str:
    out = Path(args.dir) / f"estimate-{data.stem}-{data.suffix[1:]}-{method}.json"
    cmd = [args.leeway, "estimate", str(MODEL), "--data", str(data), "--method", method, "--aggregate", "--json"]
    wall, cpu, rss = best(args.runs, cmd, out)
    report = json.loads(out.read_text())
    passes = (report["diagnostics"].get("refinements") or 0) + 1
    per_sample, peak = flops(bench, data, method)
    flop_floor = per_sample * rows * passes / (peak * 1e9)
    read_floor = data.stat().st_size / bw
    return (
        f"| {data.suffix[1:]} | {rows:,} | {method} | {wall:.2f} | {cpu:.2f} | {rss:.0f} | "
        f"{read_cpu:.2f} | {cpu / read_cpu:.2f} | {read_floor:.3f} | {passes} × {per_sample} | {flop_floor:.3f} |"
    )


# The phases of an estimate, by the function whose inclusive count is
# theirs (every thread counted together; a closure or function that
# inlining removes counts as absent).
PHASES = {
    "data checks": ["leeway_report::checks::data_checks::{{closure}}"],
    "facts": ["leeway_estimate::runner::PassRunner::facts_from"],
    "moment passes": ["leeway_estimate::runner::PassRunner::moments"],
    "covariance + own simulation": ["leeway_estimate::runner::PassRunner::long_run::{{closure}}"],
    # Across every pass:
    "regressors (interpreted)": ["<leeway_model::interp::PlannedSlots as leeway_model::model::SlotRegressors>::update_block"],
    "simulation steps (interpreted)": ["leeway_model::interp::plan::RhsPlan::eval"],
    "kernels": ["leeway_estimate::moments::MomentAccumulator::flush", "leeway_estimate::moments::LongRun::flush"],
}
SCAN = "leeway_data::validate::scan"
PARSE = "leeway_data::csv_chunk::parse_chunk"
# `count (pct)  file:function [object]`; the function may hold spaces and colons.
ANNOTATED = re.compile(r"^\s*([\d,]+) \([^)]*\)\s+([<*>]\s+)?[^:\s]*:(.*?)(?: \(\d[\d,]*x\))?(?: \[[^\]]*\])?\s*$")


def annotated(text: str) -> list[tuple[str, str, int]]:
    """`(mark, function, count)` of every line of callgrind_annotate's output."""
    lines = []
    for line in text.splitlines():
        m = ANNOTATED.match(line)
        if m:
            lines.append(((m.group(2) or "").strip(), m.group(3).strip(), int(m.group(1).replace(",", ""))))
    return lines


def callgrind(args, data: Path, method: str) -> tuple[dict[str, int], int]:
    """Instructions of each phase of one estimate under callgrind, and its passes."""
    stem = Path(args.dir) / f"callgrind-{data.stem}-{data.suffix[1:]}-{method}"
    out, json_out = stem.with_suffix(".out"), stem.with_suffix(".json")
    cmd = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", args.profiling,
           "estimate", str(MODEL), "--data", str(data), "--method", method, "--aggregate", "--json"]
    with open(json_out, "wb") as sink:
        done = subprocess.run(cmd, stdout=sink, stderr=subprocess.DEVNULL)
    if done.returncode not in (0, 1):
        raise SystemExit(f"failed ({done.returncode}): {' '.join(cmd)}")
    report = json.loads(json_out.read_text())
    passes = (report["diagnostics"].get("refinements") or 0) + 1

    def annotate(*options: str) -> str:
        return subprocess.run(["callgrind_annotate", "--threshold=100", "--inclusive=yes", *options, str(out)],
                              capture_output=True, text=True, check=True).stdout

    text = annotate()
    total = re.search(r"^\s*([\d,]+) \(100\.0%\)\s+PROGRAM TOTALS", text, re.M)
    if not total:
        raise SystemExit(f"callgrind_annotate printed no total for {out}")
    counts = {"total": int(total.group(1).replace(",", ""))}
    # A function is listed once per source file its inlined code came from;
    # its own line holds the whole inclusive count, the largest.
    inclusive: dict[str, int] = {}
    for _, function, count in annotated(text):
        inclusive[function] = max(inclusive.get(function, 0), count)
    for phase, functions in PHASES.items():
        counts[phase] = sum(inclusive.get(f, 0) for f in functions)
    # Reading: the validating pass, and the CSV chunks parsed on the other
    # threads (those it parsed itself are in its count already).
    parsed_by_scan = 0
    block: list[tuple[str, str, int]] = []
    for mark, function, count in annotated(annotate("--tree=caller")) + [("*", "", 0)]:
        if mark == "*":
            if function == PARSE:
                # Listed once per source file of its inlined code: the
                # callers of the whole function are under one of them.
                by_scan = sum(c for m, f, c in block if m == "<" and f.endswith("::next_row"))
                parsed_by_scan = max(parsed_by_scan, by_scan)
            block = []
        else:
            block.append((mark, function, count))
    counts["reading"] = inclusive.get(SCAN, 0) + inclusive.get(PARSE, 0) - parsed_by_scan
    return counts, passes


def instructions(args, bench: Path) -> None:
    """Instructions a sample of each phase, per format and method."""
    if not shutil.which("valgrind") or not shutil.which("callgrind_annotate"):
        raise SystemExit("--instructions runs valgrind's callgrind: install valgrind (Debian: apt install valgrind)")
    if not Path(args.profiling).exists():
        raise SystemExit(f"no {args.profiling}: build it with `cargo build --profile profiling -p leeway-cli`")
    phases = ["reading", *PHASES]
    print("\ninstructions a sample (callgrind); the phases after the covariance pass are parts of the passes")
    print(f"\n| format | rows | method | total | {' | '.join(phases)} | passes | moment-sum FLOP a sample |")
    print("|---|---|---|---|" + "---|" * len(phases) + "---|---|")
    for rows in args.rows:
        for data in write_data(bench, Path(args.dir), rows):
            for method in args.methods:
                counts, passes = callgrind(args, data, method)
                per_sample, _ = flops(bench, data, method)
                shares = (f"{counts[k] / rows:,.0f} ({100 * counts[k] / counts['total']:.1f} %)" for k in phases)
                print(f"| {data.suffix[1:]} | {rows:,} | {method} | {counts['total'] / rows:,.0f} | "
                      + " | ".join(shares)
                      + f" | {passes} | {passes} × {per_sample} |", flush=True)


def campaign(args, bench: Path, files: int) -> None:
    directory = Path(args.dir) / "campaign"
    directory.mkdir(parents=True, exist_ok=True)
    paths = []
    for i in range(files):
        csv = directory / f"run{i:04}.csv"
        parquet = csv.with_suffix(".parquet")
        if not parquet.exists():
            subprocess.run([str(bench / "stream-memory"), "write", "1000000", str(csv), str(i)], check=True,
                           stdout=subprocess.DEVNULL)
            to_parquet(csv, parquet)
            csv.unlink()
        paths.append(parquet)
    out = directory / "local.json"
    cmd = [args.leeway, "estimate", str(MODEL), "--method", "iv3", "--aggregate", "--json"]
    cmd += [a for p in paths for a in ("--data", str(p))]
    wall, cpu, rss = run(cmd, out)
    print(f"\ncampaign of {files} × 10⁶ samples, IV3, one process: {wall:.1f} s wall, {cpu:.1f} s CPU, {rss:.0f} MiB peak")
    try:
        import leeway
        import leeway.dask
        from dask.distributed import Client, LocalCluster
    except ImportError:
        print("(no leeway or dask package here: the LocalCluster run is skipped)")
        return
    model = leeway.Model.load(str(MODEL))
    local = json.loads(out.read_text())
    cores = os.cpu_count() or 1
    layouts = {
        f"one worker of {cores} threads": {"n_workers": 1, "threads_per_worker": cores, "processes": False},
        f"{cores} one-thread worker processes": {"n_workers": cores, "threads_per_worker": 1},
    }
    for name, layout in layouts.items():
        with LocalCluster(dashboard_address=":0", **layout) as cluster, Client(cluster) as client:
            start = time.perf_counter()
            spread = leeway.dask.estimate(model, [str(p) for p in paths], client, method="iv3", aggregate=True)
            wall = time.perf_counter() - start
        same = json.loads(spread.to_json())["parameters"] == local["parameters"]
        print(f"the same on a LocalCluster of {name}: {wall:.1f} s wall; parameters bit-identical to the CLI's: {same}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("dir")
    parser.add_argument("--rows", type=int, nargs="*", default=[1_000_000])
    parser.add_argument("--methods", nargs="+", default=["ls", "iv1", "iv2", "iv3"])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--leeway", default=str(ROOT / "target" / "release" / "leeway"))
    parser.add_argument("--campaign", type=int, default=0, metavar="FILES")
    parser.add_argument("--instructions", action="store_true", help="count instructions (callgrind) instead of timing")
    parser.add_argument("--profiling", default=str(ROOT / "target" / "profiling" / "leeway"))
    args = parser.parse_args()
    # The bench binaries (`stream-memory`, `flops`) of this checkout's release build.
    bench = ROOT / "target" / "release"
    Path(args.dir).mkdir(parents=True, exist_ok=True)
    if args.instructions:
        instructions(args, bench)
        return
    bw = bandwidth()
    print(f"machine: {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}, memory bandwidth {bw / 1e9:.1f} GB/s (copy)")
    print("\n| format | rows | method | wall s | CPU s | peak MiB | pandas read CPU s | CPU / pandas | read floor s | passes × FLOP/sample | FLOP floor s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for rows in args.rows:
        for data in write_data(bench, Path(args.dir), rows):
            read_cpu = pandas_read(data, args.runs)
            for method in args.methods:
                print(estimate_row(args, bench, data, method, rows, read_cpu, bw), flush=True)
    if args.campaign:
        campaign(args, bench, args.campaign)
    print(f"\nload at the end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
