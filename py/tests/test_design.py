"""leeway.design is `leeway design --json`, bit for bit: the document, the
typed fields read from it, the runs' nominal records (which replay through
leeway.simulate), the plan's errors at their line and column, an infeasible
design as a result with proposals, and the verification spread over Dask
workers equal to the local one."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import leeway
from conftest import ROOT, run_leeway

ROV = ROOT / "examples" / "models" / "rov.som"
ROV_PLAN = ROOT / "examples" / "plans" / "rov.toml"
BLIMP = ROOT / "examples" / "models" / "blimp.som"

# The ROV's tide (examples/plans/rov.toml), which its nominal runs hold.
TIDE = {"current.north": 0.3, "current.east": 0.1}

WINDY_BLIMP = """
[inputs.thrust]
range = [0, 2000]
rate = 500
[inputs.yaw_moment]
range = [-20000, 20000]
rate = 10000

[disturbances.wind]
mean = [1.5, 0.5]
std = 0.3
correlation_time = 20
mean_uncertainty = 0.5

[budget]
time = 1200
"""


@pytest.fixture(scope="module")
def rov() -> leeway.Model:
    return leeway.Model.load(ROV)


@pytest.fixture(scope="module")
def verified(rov: leeway.Model) -> leeway.Design:
    return leeway.design(rov, ROV_PLAN, pilot=5, verify=3, target="5%")


def test_the_design_is_the_cli_document_bit_for_bit(verified: leeway.Design) -> None:
    o = run_leeway(
        "design", str(ROV), "--plan", str(ROV_PLAN), "--pilot", "5", "--verify", "3", "--target", "5%", "--json"
    )
    assert verified.to_json() == o.stdout.rstrip("\n")
    d = json.loads(o.stdout)
    # Exit 1 when the verified models fall short (the verdict), else 0.
    assert o.returncode == (0 if d["verification"]["verdict"]["passed"] else 1), o.stderr
    assert verified.document == d
    # The typed fields are the document's numbers.
    assert (verified.model, verified.method, verified.feasible) == ("Rov", "iv3", True)
    assert verified.samples == d["samples"] and verified.seconds == d["seconds"]
    assert verified.excitation == d["excitation"] and len(verified.experiments) == 2
    parameters = d["prediction"]["parameters"]
    assert list(verified.prediction.index) == [p["name"] for p in parameters] == list(verified.theta)
    assert verified.prediction["std_error"].tolist() == [p["std_error"] for p in parameters]
    assert verified.prediction["nominal"].to_dict() == verified.theta
    assert verified.target is not None and verified.target["relative"] == 0.05
    v = verified.verification
    assert v is not None and (v.runs, v.seed, v.method) == (3, 0, "iv3")
    iv3 = next(m for m in d["verification"]["methods"] if m["method"] == "iv3")
    assert v.parameters["std"].tolist() == [p["std"] for p in iv3["parameters"]]
    assert v.parameters["coverage"].tolist() == [p["coverage"] for p in iv3["parameters"]]
    assert list(v.methods.index) == ["ls", "iv1", "iv2", "iv3"]
    assert v.methods["failed"].sum() == 0
    assert v.fits.loc["iv3"].tolist() == [f for _, f in iv3["fits"]]
    assert list(v.signs["experiment"]) == [1, 1, 2, 2]
    # The ROV's models pass at 3 trials: nothing else was verified.
    assert v.document["verdict"]["passed"] and v.document["runs_verified"] == []


def test_a_failing_verdict_verifies_the_other_runs_as_the_cli(tmp_path: Path) -> None:
    # The survey boat on 150 s at sea falls short whatever its runs:
    # the other runs the design tried are verified in turn, in the library,
    # as for the CLI, bit for bit.
    fixtures = ROOT / "design" / "tests" / "fixtures"
    plan = tmp_path / "boat.toml"
    plan.write_text((fixtures / "survey_boat.toml").read_text().replace("time = 1800", "time = 150"))
    model = fixtures / "survey_boat.som"
    d = leeway.design(leeway.Model.load(model), plan, pilot=0, verify=2)
    o = run_leeway("design", str(model), "--plan", str(plan), "--pilot", "0", "--verify", "2", "--json")
    assert o.returncode == 1, o.stderr
    assert d.to_json() == o.stdout.rstrip("\n")
    doc = json.loads(o.stdout)
    assert d.verification is not None and not d.verification.document["verdict"]["passed"]
    tried = [o for o in doc["runs_tried"] if o["worst_relative"] is not None]
    record = d.verification.document["runs_verified"]
    key = ("runs", "centring", "differ_by")
    assert [r[k] for k in key for r in record[:1]] == [
        o[k] for k in key for o in doc["runs_tried"] if o["chosen"]
    ]
    assert len(record) == len(tried) >= 2 and all(r["passed"] is False for r in record), record
    assert sum(r["taken"] for r in record) == 1


def test_a_target_reads_as_a_fraction_or_a_percentage(rov: leeway.Model, verified: leeway.Design) -> None:
    plain = leeway.design(rov, ROV_PLAN, pilot=5, target=0.05)
    assert plain.document["prediction"] == verified.document["prediction"]
    for bad in ["120%", 0, "five", True]:
        with pytest.raises(leeway.OptionError) as e:
            leeway.design(rov, ROV_PLAN, pilot=5, target=bad)
        assert "target" in str(e.value)


def test_a_dict_or_json_plan_is_the_toml_plan(rov: leeway.Model, tmp_path: Path) -> None:
    tomllib = pytest.importorskip("tomllib")  # Python 3.11+
    fields = tomllib.loads(ROV_PLAN.read_text())
    from_file = leeway.design(rov, ROV_PLAN, pilot=0)
    from_dict = leeway.design(rov, fields, pilot=0)
    assert from_dict.to_json() == from_file.to_json()
    as_json = tmp_path / "rov.json"
    as_json.write_text(json.dumps(fields))
    assert leeway.design(rov, as_json, pilot=0).to_json() == from_file.to_json()
    # numpy numbers are plan numbers.
    fields["step"] = np.float64(fields["step"])
    assert leeway.design(rov, fields, pilot=0).to_json() == from_file.to_json()


def test_the_runs_replay_to_the_nominal_states(rov: leeway.Model, verified: leeway.Design, tmp_path: Path) -> None:
    assert len(verified.runs) == len(verified.experiments)
    o = run_leeway(
        "design", str(ROV), "--plan", str(ROV_PLAN), "--pilot", "5", "--target", "5%", "--out", str(tmp_path)
    )
    assert o.returncode == 0, o.stderr
    for i, run in enumerate(verified.runs):
        # What `design --out` writes, value for value.
        written = pd.read_csv(tmp_path / f"run-{i + 1}.csv")
        pd.testing.assert_frame_equal(run, written, check_exact=True)
        assert len(run) == verified.samples
        replayed = leeway.simulate(rov, verified.theta, run, disturbances=TIDE)
        for state in [*rov.states, "psi"]:
            np.testing.assert_allclose(replayed[state], run[state], rtol=0, atol=1e-12)
        assert run["u"].abs().max() > 0.5  # the craft moves: the comparison means something


def test_a_plan_error_is_located_at_its_line_and_column(rov: leeway.Model, tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text("step = 0.05\n[inputs.tau_x]\nrange = [-6000, 6000\n")
    with pytest.raises(leeway.PlanError) as e:
        leeway.design(rov, bad)
    assert e.value.code == "plan"
    assert e.value.location == f"{bad}:3:21"  # where the `]` is missing
    assert isinstance(e.value, ValueError)
    o = run_leeway("design", str(ROV), "--plan", str(bad))
    assert o.returncode == 2 and f"{bad}:3:21" in o.stderr
    typo = tmp_path / "typo.toml"
    typo.write_text("step = 0.05\n[inputs.tau_x]\nrange = [-6000, 6000]\nrte = 3\n")
    with pytest.raises(leeway.PlanError) as e:
        leeway.design(rov, typo)
    assert e.value.location == f"{typo}:4:1" and "rte" in str(e.value)
    # A dict has no lines: the error names the field.
    with pytest.raises(leeway.PlanError) as e:
        leeway.design(rov, {"step": "fast"})
    assert e.value.location == "plan" and "string" in str(e.value)
    with pytest.raises(FileNotFoundError):
        leeway.design(rov, tmp_path / "missing.toml")


def test_a_budget_beyond_the_cli_s_bound_is_a_located_plan_error(rov: leeway.Model, tmp_path: Path) -> None:
    # The bound of budget.samples (10 million per experiment) holds for a
    # time budget over a step too, refused at once as the CLI refuses it
    # (design/tests/design/bounds.rs covers the Rust both share).
    plan = tmp_path / "long.toml"
    plan.write_text(ROV_PLAN.read_text().replace("time = 1200", "time = 1e308"))
    with pytest.raises(leeway.PlanError) as e:
        leeway.design(rov, plan, pilot=0)
    line = next(i for i, text in enumerate(plan.read_text().splitlines(), 1) if text.startswith("time = 1e308"))
    assert e.value.location == f"{plan}:{line}:8"
    assert "more than 10000000 samples" in str(e.value)
    o = run_leeway("design", str(ROV), "--plan", str(plan))
    assert o.returncode == 2 and f"{plan}:{line}:8" in o.stderr and "more than 10000000 samples" in o.stderr
    with pytest.raises(leeway.PlanError) as e:
        leeway.design(rov, {"step": 1e-9, "inputs": {name: {"range": [-4000, 4000]} for name in rov.inputs}}, pilot=0)
    assert e.value.location == "plan" and "more than 10000000 samples" in str(e.value)


def test_the_windy_blimp_is_infeasible_not_an_error(tmp_path: Path) -> None:
    plan = tmp_path / "windy.toml"
    plan.write_text(WINDY_BLIMP)
    blimp = leeway.Model.load(BLIMP)
    d = leeway.design(blimp, plan, pilot=0, verify=2)
    assert not d.feasible
    assert d.verification is None  # as the CLI: an infeasible design is not verified
    assert d.shortfalls and any("measure wind" in p for p in d.proposals), d.proposals
    assert d.prediction.empty and list(d.prediction.columns) == ["nominal", "std_error", "relative", "asymptotic"]
    o = run_leeway("design", str(BLIMP), "--plan", str(plan), "--pilot", "0", "--json")
    assert o.returncode == 1
    assert d.to_json() == o.stdout.rstrip("\n")


def test_a_model_no_trial_identifies_raises_unidentifiable() -> None:
    model = leeway.Model.from_str(
        "model M { step 0.1 state u input f der u = A*u + B*u + C*f nominal { A = -0.5, B = -0.1, C = 0.1 } }"
    )
    with pytest.raises(leeway.Unidentifiable) as e:
        leeway.design(model, {"inputs": {"f": {"range": [-1, 1]}}})
    assert e.value.code == "not-identifiable"
    assert "--" not in str(e.value)  # the hint in Python's spelling


def test_options_are_checked(rov: leeway.Model) -> None:
    for kwargs in [{"verify": 0}, {"pilot": 1001}, {"method": "ls"}, {"seed": -1}, {"verify": 2.5}]:
        with pytest.raises(leeway.OptionError):
            leeway.design(rov, ROV_PLAN, **kwargs)
    with pytest.raises(leeway.OptionError):
        leeway.design(rov, 42)  # type: ignore[arg-type]


def test_the_dask_verification_is_the_local_one(rov: leeway.Model) -> None:
    distributed = pytest.importorskip("distributed")
    import leeway.dask

    local = leeway.design(rov, ROV_PLAN, pilot=0, verify=4, seed=5)
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
    ) as c, distributed.Client(c) as client:
        with distributed.get_task_stream(client) as stream:
            spread = leeway.dask.verify_design(rov, ROV_PLAN, client, runs=4, pilot=0, seed=5)
        ran = {t["worker"] for t in stream.data if str(t["key"]).startswith("_design_trial")}
        assert len(ran) == 2, ran
    assert spread.verification is not None and spread.verification.runs == 4
    # The cluster verifies the design itself; leeway.design also verifies
    # the other runs the design tried when its verdict fails.
    record = local.verification.document["runs_verified"] if local.verification else []
    if not record:
        assert spread.to_json() == local.to_json()
    else:
        first = record[0]
        verdict = spread.verification.document["verdict"]
        assert (verdict["passed"], verdict["failures"]) == (first["passed"], first["failures"])
