"""Errors and warnings raised in Python speak Python: every CLI flag a
message of the native half may name is mapped to its keyword
(``leeway/_hints.py``), and no error or warning a user sees contains
``--``."""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import leeway
from conftest import SHIP
from leeway._hints import KEYWORDS, python_spelling

ROOT = Path(__file__).resolve().parents[2]
# The crates whose messages reach Python (the CLI's own crate does not).
CRATES = ["structure", "model", "data", "estimate", "report", "design", "select", "py"]


def test_every_flag_the_libraries_name_is_mapped() -> None:
    named: dict[str, str] = {}
    for crate in CRATES:
        for path in (ROOT / crate / "src").rglob("*.rs"):
            for line in path.read_text().splitlines():
                if line.lstrip().startswith("//"):
                    continue  # comments reach nobody
                for flag in re.findall(r"(?<![\w-])--[a-z][a-z0-9-]*", line):
                    named.setdefault(flag, f"{path.relative_to(ROOT)}")
    assert named, "no flag found: the scan is broken"
    unmapped = {f: where for f, where in named.items() if f not in KEYWORDS}
    assert not unmapped, f"flags named by the libraries with no Python keyword: {unmapped}"


@pytest.mark.parametrize("cli, python", [
    ("a constant term is estimable with uncentred instruments (--centring none: x), or with --centring pooled",
     'a constant term is estimable with uncentred instruments (centring="none": x), or with centring="pooled"'),
    ("--resample H interpolates onto a uniform grid", "resample=H interpolates onto a uniform grid"),
    ("--resample 0.5 conflicts with the model's step 1", "resample=0.5 conflicts with the model's step 1"),
    ("or estimate the identifiable combinations with --aggregate", "or estimate the identifiable combinations with aggregate=True"),
    ("(nominal { } in the model, or --nominal FILE)", "(nominal { } in the model, or nominal={name: value})"),
    ("`leeway check --json` lists every one", "`Model.check()` lists every one"),
    ("(`leeway check --centring`, `leeway estimate --centring`)",
     "(`Model.check(centring=…)`, `leeway.estimate(centring=…)`)"),
    ("drop --strict to estimate anyway", "drop strict=True to estimate anyway"),
    ("compare with --method ls, record", 'compare with method="ls", record'),
    ("a time span of -- nothing", "a time span of -- nothing"),
])
def test_cli_flags_are_written_as_keywords(cli: str, python: str) -> None:
    assert python_spelling(cli) == python


def ship_frame_jittered() -> pd.DataFrame:
    rng = np.random.default_rng(3)
    n = 200
    t = np.arange(n, dtype=float)
    t[50] += 0.4  # beyond the 5 % tolerance: the error names its options
    return pd.DataFrame({
        "time": t, "u": 5 + rng.normal(0, 0.1, n), "v": rng.normal(0, 0.1, n), "r": rng.normal(0, 0.01, n),
        "psi": np.zeros(n), "tau1": np.full(n, 100.0), "tau2": rng.normal(0, 1, n), "tau3": rng.normal(0, 1, n),
        "wind_n": np.ones(n), "wind_e": np.zeros(n),
    })


def test_errors_and_warnings_raised_in_python_name_no_cli_flag() -> None:
    ship = leeway.Model.load(SHIP)
    seen = []
    for call in (
        lambda: leeway.estimate(ship, ship_frame_jittered()),
        lambda: leeway.estimate(ship, ship_frame_jittered(), resample=0.5),
        lambda: leeway.validate(ship, ship.nominal, ship_frame_jittered()),
    ):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            with pytest.raises(leeway.LeewayError) as e:
                call()
        seen.append(str(e.value))
        seen += [str(w.message) for w in caught]
    assert any("time_tolerance" in s or "resample" in s for s in seen), seen
    for text in seen:
        assert "--" not in text, text
