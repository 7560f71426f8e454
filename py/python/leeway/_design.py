"""Trial design, as ``leeway design``: from a model and a plan (what is
known before the trial), the runs to make at sea, their predicted standard
errors and, with ``verify=M``, a Monte Carlo check of the design. The
numbers are the CLI's (the same code, leeway-design), bit for bit:
``Design.document`` is the document ``leeway design --json`` prints."""

from __future__ import annotations

import json
import numbers
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Union

import numpy as np
import pandas as pd

from . import _leeway
from ._api import MAX_PLAN_BYTES, Model, _integer, _is_bool, _native, _text, read_bounded
from ._hints import python_spelling
from .errors import OptionError, PlanError

Plan = Union[str, "os.PathLike[str]", Mapping[str, Any]]
"""A plan: the path of a ``.toml`` file (``.json`` for JSON), or a dict of
the same fields (docs/python.md, "Trial design")."""

# The CLI's bounds (cli/src/design/args.rs).
MAX_RUNS = 10_000
MAX_PILOT = 1000

_PREDICTION = ["nominal", "std_error", "relative", "asymptotic"]
_VERIFIED = ["truth", "mean", "std", "predicted", "reported", "coverage"]


@dataclass(frozen=True)
class Verification:
    """The Monte Carlo check of a design (``verify=M``): ``runs`` trials
    from ``seed``, each realising every experiment with the plan's random
    disturbances and noise and estimating with every method.

    ``parameters``: the designed method's figures per parameter — the
    ``truth`` (the plan's nominal), the ``mean`` and ``std`` of the
    estimates (the verified standard error), the ``predicted`` standard
    error, the estimator's own ``reported`` one (averaged) and the
    ``coverage`` of ±2·predicted. ``by_method``: the same for every method,
    indexed by (``method``, ``parameter``). ``methods``: per method,
    ``designed_for``, ``failed`` (with the first ``failure``),
    ``rank_deficient`` and ``diverged`` runs. ``fits``: per method and
    state, the mean validation fit (%). ``signs``: per experiment and held
    argument, the fraction of samples on its side (``mean`` over runs,
    ``min``). ``document["verdict"]``: whether the designed method's
    models pass (held-out fit within 10 points of the true model's,
    ``document["true_fits"]``; ``document["true_early_fits"]`` and each
    method's ``early_fits``: the same over the held-out run's first tenth,
    ``document["early_seconds"]`` long; coverage 90–98 % from 100 trials, within
    their sampling error), what fails and what would help — ``leeway
    design`` exits 1 when not. ``document["runs_verified"]``: when the
    design's verdict failed, every runs option the design tried, verified
    in turn (``runs``, ``differ_by``, ``centring``, ``passed``, ``failures``,
    ``taken``): the design is the first
    that passes, else the search's own."""

    runs: int
    seed: int
    samples: int
    method: str
    """The method the design was made for."""
    parameters: pd.DataFrame
    by_method: pd.DataFrame
    methods: pd.DataFrame
    fits: pd.DataFrame
    signs: pd.DataFrame
    document: dict[str, Any]
    """The ``verification`` object of ``leeway design --json``."""

    @classmethod
    def _from_document(cls, d: dict[str, Any]) -> Verification:
        rows = [
            (m["method"], p["name"], *(_float(p[c]) for c in _VERIFIED))
            for m in d["methods"]
            for p in m["parameters"]
        ]
        by_method = pd.DataFrame(
            rows, columns=["method", "parameter", *_VERIFIED]
        ).set_index(["method", "parameter"])
        by_method = by_method.astype("float64")
        designed = next((m["method"] for m in d["methods"] if m["designed_for"]), "")
        parameters = by_method.xs(designed, level="method") if designed else by_method.iloc[:0]
        methods = pd.DataFrame(
            [
                (m["method"], m["designed_for"], m["failed"], m["failure"], m["rank_deficient"], m["diverged"])
                for m in d["methods"]
            ],
            columns=["method", "designed_for", "failed", "failure", "rank_deficient", "diverged"],
        ).set_index("method")
        # Every method is validated on the same states, in the model's order.
        states = [state for state, _ in d["methods"][0]["fits"]] if d["methods"] else []
        fits = pd.DataFrame(
            [[_float(fit) for _, fit in m["fits"]] for m in d["methods"]],
            index=pd.Index([m["method"] for m in d["methods"]], name="method"),
            columns=pd.Index(states, name="state"),
            dtype="float64",
        )
        signs = pd.DataFrame(d["signs"], columns=["experiment", "argument", "mean", "min"])
        return cls(
            runs=d["runs"],
            seed=d["seed"],
            samples=d["samples"],
            method=designed,
            parameters=parameters,
            by_method=by_method,
            methods=methods,
            fits=fits,
            signs=signs,
            document=d,
        )

    def __repr__(self) -> str:
        return (
            f"<leeway.Verification of {self.method}: {self.runs} runs from seed {self.seed}, "
            f"{self.samples} samples per experiment; .parameters for the table>"
        )


@dataclass(frozen=True)
class Design:
    """A trial design, as ``leeway design --json`` reports it.

    ``experiments``: per run, its sign ``pattern``, per input the
    ``offset`` and excitation ``amplitude`` in its ``unit`` (the model's
    ``data { }`` unit, as in the run files; None: the model's own), the
    ``steady`` state, the
    ``held`` arguments with their margins (the dicts of ``leeway design
    --json``). ``prediction``: per parameter the ``nominal`` value, the
    predicted ``std_error`` at the budget's run length, ``relative`` to the
    nominal and the estimator's ``asymptotic`` one (empty when no
    excitation keeps the signs). ``curve``: the standard errors against run
    length. ``feasible`` is false when no plan within the limits keeps every
    held sign: ``shortfalls`` say what falls short and ``proposals`` what
    would work (not an exception). ``runs``: per experiment, its nominal
    record in the model's data columns (what ``design --out`` writes as
    ``run-N.csv``), which ``leeway.simulate(model, design.theta, runs[i],
    disturbances=…)`` replays."""

    model: str
    method: str
    centring: str
    aggregate: bool
    """Whether the estimate must hold unexcited θ at nominal (``aggregate=True``)."""
    feasible: bool
    step: float
    samples: int
    """Samples per experiment."""
    seconds: float
    """Seconds per experiment."""
    excitation: str
    families: pd.DataFrame
    """Every excitation family tried: ``scale``, ``score``, ``status``, ``detail``."""
    experiments: tuple[dict[str, Any], ...]
    prediction: pd.DataFrame
    curve: pd.DataFrame
    """Per run length (``samples``, ``seconds``, ``worst_relative``), each θ's standard error."""
    disturbances: pd.DataFrame
    """The unmeasured disturbance means: the plan's ``mean`` and the predicted ``std_error``."""
    worst_relative: float | None
    target: dict[str, Any] | None
    """The run a ``target`` precision needs: ``relative``, ``samples``, ``seconds``
    (both ``None`` past 10 million samples, beyond what leeway plans), ``within_budget``."""
    poorly_determined: tuple[dict[str, Any], ...]
    methods: tuple[dict[str, Any], ...]
    """Per estimator, whether the design keeps the signs it assumes."""
    shortfalls: tuple[dict[str, Any], ...]
    proposals: tuple[str, ...]
    noise: dict[str, float]
    assumptions: tuple[str, ...]
    verification: Verification | None
    theta: dict[str, float]
    """θ the design was made for (the plan's nominal values)."""
    runs: list[pd.DataFrame]
    document: dict[str, Any]
    """The whole document of ``leeway design --json``."""
    _json: str = field(repr=False, compare=False)

    @classmethod
    def _from_document(cls, text: str, runs: list[Any], theta: dict[str, float]) -> Design:
        d = json.loads(text)
        p = d["prediction"] or {}
        prediction = pd.DataFrame(
            [[_float(q[c]) for c in _PREDICTION] for q in p.get("parameters", [])],
            index=pd.Index([q["name"] for q in p.get("parameters", [])], name="parameter"),
            columns=_PREDICTION,
            dtype="float64",
        )
        names = list(prediction.index)
        curve = pd.DataFrame(
            [
                [c["samples"], c["seconds"], _float(c["worst_relative"]), *(_float(s) for s in c["std_errors"])]
                for c in p.get("curve", [])
            ],
            columns=["samples", "seconds", "worst_relative", *names],
        )
        disturbances = pd.DataFrame(
            [(q["name"], _float(q["mean"]), _float(q["std_error"])) for q in p.get("disturbances", [])],
            columns=["name", "mean", "std_error"],
        ).set_index("name")
        families = pd.DataFrame(
            d["families"], columns=["family", "scale", "score", "status", "detail"]
        ).set_index("family")
        families["score"] = families["score"].map(_float).astype("float64")
        return cls(
            model=d["model"],
            method=d["method"],
            centring=d["centring"],
            aggregate=d["aggregate"],
            feasible=d["feasible"],
            step=d["step"],
            samples=d["samples"],
            seconds=d["seconds"],
            excitation=d["excitation"],
            families=families,
            experiments=tuple(d["experiments"]),
            prediction=prediction,
            curve=curve,
            disturbances=disturbances,
            worst_relative=_float(p["worst_relative"]) if p else None,
            target=p.get("target"),
            poorly_determined=tuple(p.get("poorly_determined", [])),
            methods=tuple(d["methods"]),
            shortfalls=tuple(d["shortfalls"]),
            proposals=tuple(python_spelling(s) for s in d["proposals"]),
            noise=dict(d["noise"]),
            assumptions=tuple(python_spelling(s) for s in d["assumptions"]),
            verification=Verification._from_document(d["verification"]) if d["verification"] else None,
            theta=theta,
            runs=[pd.DataFrame(dict(columns)) for columns in runs],
            document=d,
            _json=text,
        )

    def to_json(self) -> str:
        """The document of ``leeway design --json`` (without its final newline)."""
        return self._json

    def __repr__(self) -> str:
        verdict = "feasible" if self.feasible else "infeasible (see .proposals)"
        return (
            f"<leeway.Design for {self.model} ({self.method}): {len(self.experiments)} experiment(s) of "
            f"{self.samples} samples ({self.seconds:g} s), {self.excitation}, {verdict}"
            + (f", verified by {self.verification.runs} runs" if self.verification else "")
            + ">"
        )


def _float(v: Any) -> float:
    """A number of the document (``null`` for what JSON cannot hold) as float."""
    return float("nan") if v is None else float(v)


def _precision(target: Any) -> float | None:
    """``target`` as a fraction: ``0.05`` or ``"5%"`` (as ``--target``)."""
    if target is None:
        return None
    hint = 'give target as a fraction or a percentage, e.g. target=0.05 or target="5%"'
    if isinstance(target, str):
        text = target.strip()
        try:
            value = float(text[:-1].strip()) / 100 if text.endswith("%") else float(text)
        except ValueError:
            raise OptionError(f"target={target!r} is not a precision", code="invalid-option", hint=hint) from None
    elif _is_bool(target) or not isinstance(target, numbers.Real):
        raise OptionError(
            f"target={target!r} is a {type(target).__name__}, not a precision", code="invalid-option", hint=hint
        )
    else:
        value = float(target)
    if not (np.isfinite(value) and 0 < value < 1):
        raise OptionError(
            f"target={target!r}: a relative precision is between 0 and 100 %", code="invalid-option", hint=hint
        )
    return value


def _plain(v: Any) -> Any:
    """numpy scalars and arrays as the JSON a plan holds."""
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, np.ndarray):
        return v.tolist()
    raise TypeError(f"a {type(v).__name__} is not a plan value")


def _plan(plan: Any) -> tuple[str, bool, str, bool]:
    """The plan's text, whether it is JSON, its name in errors and whether
    errors are located at a line and column of it (a file's, not a dict's)."""
    if isinstance(plan, Mapping):
        try:
            text = json.dumps(plan, allow_nan=False, default=_plain)
        except (TypeError, ValueError) as e:
            raise PlanError(
                f"the plan cannot be written as JSON: {e}",
                code="plan",
                location="plan",
                hint="plan values are numbers, text, lists and dicts (finite numbers)",
            ) from None
        return text, True, "plan", False
    if isinstance(plan, (str, os.PathLike)):
        path = Path(plan)
        data = read_bounded(
            path, MAX_PLAN_BYTES, "plan", PlanError,
            "a plan is a few lines of TOML or JSON: is this the plan file?",
        )
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError as e:
            raise PlanError(
                f"the plan is not UTF-8 text: {e.reason} at byte {e.start}",
                code="plan",
                location=os.fspath(plan),
                hint="save the plan as UTF-8 TOML or JSON",
            ) from None
        return text, path.suffix.lower() == ".json", os.fspath(plan), True
    raise OptionError(
        f"plan is a {type(plan).__name__}",
        code="invalid-option",
        hint="pass the path of a plan file (.toml or .json) or a dict of its fields",
    )


def _options(target: Any, seed: Any, pilot: Any, method: Any) -> dict[str, Any]:
    return {
        "method": _text("method", method),
        "target": _precision(target),
        "seed": _integer("seed", seed, 0, (1 << 64) - 1),
        "pilot": _integer("pilot", pilot, 0, MAX_PILOT),
        "verify": None,
    }


def _runs(what: str, runs: Any, optional: bool) -> int | None:
    if runs is None and optional:
        return None
    return _integer(what, runs, 1, MAX_RUNS)


def _designed(model: Model, plan: tuple[str, bool, str, bool], options: dict[str, Any]) -> _leeway.Designed:
    """The design of ``model`` for the plan read by :func:`_plan`."""
    if not isinstance(model, Model):
        raise OptionError(
            f"model is a {type(model).__name__}, not a leeway.Model",
            code="invalid-option",
            hint='load it with leeway.Model.load("craft.som")',
        )
    return _native(_leeway.Designed.make, model._core, *plan, options)


def _design(core: _leeway.Designed, document: str) -> Design:
    names = core.parameters
    return Design._from_document(document, core.runs(), dict(zip(names, core.theta)))


def design(
    model: Model,
    plan: Plan,
    *,
    target: float | str | None = None,
    verify: int | None = None,
    seed: int = 0,
    pilot: int = 100,
    method: str = "iv3",
) -> Design:
    """Designs the trial for ``model`` as ``leeway design MODEL --plan PLAN``
    does (the keywords are its flags: ``leeway design --help``): ``plan`` is a plan file
    (TOML, or JSON for a ``.json`` name) or a dict of its fields;
    ``target`` the relative standard error wanted for every θ (``0.05`` or
    ``"5%"``); ``verify`` the number of Monte Carlo trials checking the
    design (run only for a feasible design, as the CLI does); ``seed`` seeds
    the excitation, the prediction and the verification; ``pilot`` trials
    calibrate the predicted standard errors (0: the estimator's asymptotic
    ones); ``method`` is ``"iv3"`` or ``"iv2"``.

    Returns a ``Design`` whose ``document`` is ``leeway design --json``'s,
    bit for bit. A plan that cannot be read raises ``PlanError`` located at
    ``file:line:col``; a model no trial can identify ``Unidentifiable``; a
    model and plan no design can serve ``DesignError``. A design that cannot
    keep every held sign is not an error: ``feasible`` is false and
    ``proposals`` say what would work."""
    options = _options(target, seed, pilot, method)
    options["verify"] = _runs("verify", verify, optional=True)
    core = _designed(model, _plan(plan), options)
    return _design(core, core.document())
