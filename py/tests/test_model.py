"""Model loading, checking, pickling and ModelError's located diagnostics."""

from __future__ import annotations

import pickle

import pandas as pd
import pytest

import leeway
from conftest import ROOT, SHIP, run_leeway

DRIFT = """model Drift {
    step 0.1
    state u
    input f
    der u = X_u*u + X_uu*u*|u| + X_f*f
    nominal { X_u = -0.5, X_f = 1.0 }
}
"""


def test_load_compiles_the_ship_and_names_its_signals() -> None:
    model = leeway.Model.load(SHIP)
    assert model.name == "Ship"
    assert model.states == ["u", "v", "r"]
    assert model.parameters[:3] == ["X_u", "X_vr", "X_uu"]
    assert model.nominal["X_u"] == -0.2
    assert model.file == str(SHIP)
    assert "psi" in model.columns and "wind_n" in model.columns


def test_check_is_a_frozen_report_with_regressors_as_a_dataframe() -> None:
    check = leeway.Model.from_str(DRIFT).check()
    assert check.identifiable and check.verdict == "identifiable"
    assert isinstance(check.regressors, pd.DataFrame)
    assert list(check.regressors["parameter"]) == ["X_u", "X_uu", "X_f"]
    assert check.regressors.loc[1, "term"] == "u*|u|"
    with pytest.raises(AttributeError):
        check.identifiable = False  # type: ignore[misc]


def test_check_matches_the_cli_document() -> None:
    model = leeway.Model.load(ROOT / "examples/models/rov.som")
    o = run_leeway("check", str(ROOT / "examples/models/rov.som"), "--json")
    import json

    cli = json.loads(o.stdout)
    check = model.check()
    assert check.document["required_sign_patterns"] == cli["required_sign_patterns"]
    assert check.document["regressors"] == cli["regressors"]
    assert len(check.required_sign_patterns) == 2  # the ROV needs a second experiment
    assert check.combinations == () or all("parameters" in c for c in check.combinations)


def test_check_with_one_pattern_reports_the_combination() -> None:
    model = leeway.Model.load(ROOT / "examples/models/rov.som")
    first = model.check().required_sign_patterns[0]
    spec = ",".join(f"{k}:{v}" for k, v in first.items())
    check = model.check([spec])
    assert not check.identifiable
    assert check.combinations and {"Y_vr", "Y_rv"} <= set(check.combinations[0]["parameters"])


def test_a_bad_pattern_is_an_option_error() -> None:
    with pytest.raises(leeway.OptionError) as e:
        leeway.Model.load(ROOT / "examples/models/rov.som").check(["nonsense+"])
    assert e.value.code == "invalid-option"
    assert isinstance(e.value, ValueError)


def test_model_error_carries_the_check_json_diagnostics() -> None:
    text = DRIFT.replace("X_f*f", "X_f*g")
    with pytest.raises(leeway.ModelError) as e:
        leeway.Model.from_str(text, file="drift.som")
    err = e.value
    assert err.code == "unknown-name" or err.code  # the compiler's stable code
    assert err.location is not None and err.location.startswith("drift.som:5:")
    assert err.diagnostics and err.diagnostics[0]["code"] == err.code
    assert err.diagnostics[0]["line"] == 5
    assert isinstance(err, leeway.LeewayError)
    # The same diagnostics as `leeway check --json` on the same file.
    import json
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "drift.som"
        path.write_text(text)
        cli = json.loads(run_leeway("check", str(path), "--json").stdout)
        with pytest.raises(leeway.ModelError) as e2:
            leeway.Model.load(path)
    assert [x["code"] for x in cli["errors"]] == [x["code"] for x in e2.value.diagnostics]
    assert [x["message"] for x in cli["errors"]] == [x["message"] for x in e2.value.diagnostics]


def test_a_model_that_is_not_utf8_is_located() -> None:
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "latin1.som"
        path.write_bytes(DRIFT.replace("Drift", "Dr\xe9ft").encode("latin-1"))
        with pytest.raises(leeway.ModelError) as e:
            leeway.Model.load(path)
    assert e.value.location is not None and e.value.location.endswith(":1:9")


def test_a_missing_file_is_an_oserror() -> None:
    with pytest.raises(FileNotFoundError):
        leeway.Model.load(ROOT / "no-such-model.som")


def test_model_pickles_by_source_text() -> None:
    model = leeway.Model.load(SHIP)
    back = pickle.loads(pickle.dumps(model))
    assert back.source == model.source and back.file == model.file
    assert back.parameters == model.parameters
    assert back.check().document == model.check().document


def test_errors_pickle_with_their_fields() -> None:
    with pytest.raises(leeway.ModelError) as e:
        leeway.Model.from_str("model X {")
    back = pickle.loads(pickle.dumps(e.value))
    assert type(back) is leeway.ModelError
    assert (back.code, back.location, back.hint) == (e.value.code, e.value.location, e.value.hint)


def test_check_takes_a_centring_and_names_the_way_out_for_a_constant() -> None:
    cat = leeway.Model.load(ROOT / "tests" / "models" / "catamaran.som")
    default = cat.check()
    assert default.centring == "experiment" and not default.identifiable
    (x0,) = default.combinations
    way = "`--centring none` or `pooled` from experiments with sign patterns {+water.u +water.v}, {-water.u +water.v}"
    separation = default.document["separations"][0]["message"]
    assert way in separation, separation
    # The centring named: identifiable from exactly those experiments.
    for centring in ("none", "pooled"):
        c = cat.check(centring=centring)
        assert c.centring == centring and c.identifiable
        assert c.required_sign_patterns == tuple(x0["separated_by"])
    # And from the experiments given: one sign of water.u is not enough.
    assert not cat.check(["water.u:+"], centring="none").identifiable
    with pytest.raises(leeway.OptionError, match="centring"):
        cat.check(centring="mean")
