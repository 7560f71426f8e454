"""Model.select: the path, the chosen model and its estimate bit for bit as
`leeway select --json` gives them, the chosen model written and read back,
and the errors as the package's classes."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import leeway
from conftest import run_leeway

# The ferry of cli/tests/cli/select.rs: five of its nine candidates true.
CANDIDATES = """model Ferry {
    step 0.1
    state u, v, r
    input tau_x, tau_y, tau_n

    der u = X_u*u + ?X_uu*u*|u| + ?X_vr*v*r + X_t*tau_x + ?X_r*r
    der v = Y_v*v + ?Y_vv*v*|v| + ?Y_ur*u*r + Y_t*tau_y + ?Y_tn*tau_n
    der r = N_r*r + ?N_rr*r*|r| + ?N_uv*u*v + N_t*tau_n + ?N_ty*tau_y

    nominal { X_u = -0.05, X_t = 6.7e-5, Y_v = -0.15, Y_t = 6e-5, N_r = -0.3, N_t = 2e-5 }
}
"""

TRUTH = {"X_u": -0.05, "X_uu": -0.05, "X_vr": 0.4, "X_t": 6.7e-5, "X_r": 0.0,
         "Y_v": -0.15, "Y_vv": -0.3, "Y_ur": -0.5, "Y_t": 6e-5, "Y_tn": 0.0,
         "N_r": -0.3, "N_rr": 0.0, "N_uv": 0.02, "N_t": 2e-5, "N_ty": 0.0}
TRUE_CANDIDATES = ["X_uu", "X_vr", "Y_vv", "Y_ur", "N_uv"]


@pytest.fixture(scope="module")
def ferry(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[Path]]:
    """The candidate model and three simulated runs of 3000 samples
    (forces at a new random level every 5 s), written by `leeway simulate`."""
    tmp = tmp_path_factory.mktemp("select")
    model = tmp / "cand.som"
    model.write_text(CANDIDATES)
    (tmp / "truth.json").write_text(json.dumps(TRUTH))
    runs = []
    for k in range(3):
        rng = np.random.default_rng(k)
        levels = np.repeat(rng.uniform(-1, 1, (60, 3)), 50, axis=0)
        inputs = pd.DataFrame({
            "time": np.arange(3000) / 10.0,
            "tau_x": 20000.0 + 8000.0 * levels[:, 0],
            "tau_y": 3000.0 * levels[:, 1],
            "tau_n": 15000.0 * levels[:, 2],
        })
        inputs.to_csv(tmp / f"in{k}.csv", index=False)
        run = tmp / f"run{k}.csv"
        o = run_leeway(
            "simulate", str(model), "--params", str(tmp / "truth.json"), "--input", str(tmp / f"in{k}.csv"),
            "--x0", "u=1,v=0,r=0", "--out", str(run), "--noise", "u=0.01,v=0.01,r=0.002", "--seed", str(k),
        )
        assert o.returncode == 0, o.stderr
        runs.append(run)
    return model, runs


def frames(runs: list[Path]) -> dict[str, pd.DataFrame]:
    """The runs by the names the CLI gives the files' experiments."""
    return {str(r): pd.read_csv(r) for r in runs}


def test_select_is_bit_identical_to_the_cli(ferry: tuple[Path, list[Path]], tmp_path: Path) -> None:
    model_file, runs = ferry
    out = tmp_path / "chosen-cli.som"
    args = [a for r in runs for a in ("--data", str(r))]
    o = run_leeway("select", str(model_file), *args, "--out", str(out), "--lags", "2", "--json")
    assert o.returncode == 0, o.stderr
    cli = json.loads(o.stdout)
    assert cli["errors"] == []

    model = leeway.Model.load(model_file)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", leeway.LeewayWarning)
        ours = model.select(frames(runs), lags=2)

    # Floats compare by their shortest round-trip text: equal text, equal bits.
    assert json.dumps(json.loads(ours.to_json())) == json.dumps(cli["selection"])
    assert sorted(ours.kept) == sorted(TRUE_CANDIDATES)
    assert ours.source == out.read_text()
    assert list(ours.steps.columns[:3]) == ["dropped", "reason", "wald"]
    assert len(ours.steps) == len(cli["selection"]["steps"])
    assert ours.steps.loc[ours.chosen, "size"] == len(ours.kept)
    assert pd.isna(ours.steps.loc[0, "dropped"])
    # The chosen estimate is the one `estimate` makes of the chosen model.
    cli_estimate = cli["selection"]["estimate"]
    assert ours.estimate.theta == dict(zip(cli_estimate["parameters"], cli_estimate["theta"]))
    chosen = ours.model()
    assert sorted(set(chosen.parameters) & set(TRUTH)) == sorted(chosen.parameters)
    written = tmp_path / "chosen.som"
    ours.write(written)
    assert leeway.Model.load(written).parameters == chosen.parameters
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", leeway.LeewayWarning)
        again = leeway.estimate(chosen, frames(runs), lags=2)
    assert again.theta == ours.estimate.theta
    assert "Selection" in repr(ours)


def test_held_out_data_and_errors(ferry: tuple[Path, list[Path]]) -> None:
    model_file, runs = ferry
    model = leeway.Model.load(model_file)
    data = list(frames(runs).values())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", leeway.LeewayWarning)
        s = model.select(data[:2], validate=data[2])
    # Criteria on the held-out run (NaN where its free run is not defined).
    assert s.steps["criterion"].iloc[: s.chosen + 1].notna().all()
    assert s.held_out == "the validation data"
    with pytest.raises(leeway.OptionError) as e:
        model.select(data, method="ls")
    assert e.value.code == "invalid-option"
    with pytest.raises(leeway.OptionError):
        model.select(data, tolerance=-1)
    with pytest.raises(leeway.OptionError):
        model.select(data, lags=0)
    plain = leeway.Model.from_str(CANDIDATES.replace("?", ""), file="plain.som")
    with pytest.raises(leeway.ModelError) as m:
        plain.select(data)
    assert m.value.code == "no-candidates" and m.value.location == "plain.som"
    with pytest.raises(leeway.DataError):
        model.select([d.drop(columns="tau_y") for d in data])


def test_the_selection_figure_is_written(ferry: tuple[Path, list[Path]], tmp_path: Path) -> None:
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import leeway.plot

    model_file, runs = ferry
    data = list(frames(runs).values())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", leeway.LeewayWarning)
        s = leeway.Model.load(model_file).select(data[:2], validate=data[2])
    fig = leeway.plot.selection(s)
    assert len(fig.axes) == 2
    # The chosen model's score is marked where the path puts it.
    chosen = [line for line in fig.axes[0].lines if line.get_label().startswith("chosen")]
    assert chosen[0].get_xdata()[0] == s.steps.loc[s.chosen, "size"]
    out = tmp_path / "selection.png"
    fig.savefig(out)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_check_reports_the_candidates_as_the_cli(tmp_path: Path) -> None:
    path = tmp_path / "cand.som"
    path.write_text(CANDIDATES)
    check = leeway.Model.load(path).check()
    cli = json.loads(run_leeway("check", str(path), "--json").stdout)
    assert check.candidates == cli["candidates"]
    assert check.candidates is not None
    assert check.candidates["candidates"] == ["X_uu", "X_vr", "X_r", "Y_vv", "Y_ur", "Y_tn", "N_rr", "N_uv", "N_ty"]
    plain = tmp_path / "plain.som"
    plain.write_text(CANDIDATES.replace("?", ""))
    assert leeway.Model.load(plain).check().candidates is None
