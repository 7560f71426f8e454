"""The API of leeway: models, checks, estimates, simulation and
validation, each a call into the native half (``_leeway``) with its
arguments checked here first."""

from __future__ import annotations

import json
import numbers
import os
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, TypeVar, Union

import numpy as np
import pandas as pd

from . import _leeway, _summary
from ._data import Data, Frame, _handover
from ._hints import python_spelling
from .errors import EstimateError, LeewayError, LeewayWarning, ModelError, OptionError

if TYPE_CHECKING:
    from ._select import Selection

T = TypeVar("T")


# The CLI's bounds on files read whole (docs/data-files.md, "Limits"): a
# device or a file without end (/dev/zero) is an error, not all memory.
MAX_MODEL_BYTES = 1 << 20
MAX_PLAN_BYTES = 1 << 20


def read_bounded(
    path: str | os.PathLike[str], limit: int, what: str, error: type[LeewayError], hint: str
) -> bytes:
    """The bytes of ``path``, at most ``limit`` of them: one more is an
    ``error`` of code ``what`` located at the file."""
    with open(path, "rb") as f:
        data = f.read(limit + 1)
    if len(data) > limit:
        raise error(
            f"the {what} file is larger than {limit >> 20} MiB",
            code=what,
            location=os.fspath(path),
            hint=hint,
        )
    return data


class Model:
    """A compiled model. Pickles by its source text, so it travels to worker
    processes and is recompiled there."""

    __slots__ = ("_core",)

    def __init__(self, core: _leeway.Model) -> None:
        self._core = core

    @classmethod
    def load(cls, path: str | os.PathLike[str], *, aggregate: bool = False) -> Model:
        """Reads and compiles a ``.som`` file. Raises ``ModelError`` with
        every diagnostic located at ``file:line:col``; ``OSError`` when the
        file cannot be read."""
        data = read_bounded(
            path, MAX_MODEL_BYTES, "model", ModelError,
            "a model of a few hundred lines is a few kB: is this the .som file?",
        )
        return cls(_leeway.Model.compile_bytes(data, os.fspath(path), aggregate))

    @classmethod
    def from_str(
        cls, text: str, *, file: str = "<string>", aggregate: bool = False
    ) -> Model:
        """Compiles model text; ``file`` names it in diagnostics."""
        return cls(_leeway.Model.compile_text(text, file, aggregate))

    @property
    def name(self) -> str:
        return self._core.name

    @property
    def source(self) -> str:
        return self._core.source

    @property
    def file(self) -> str:
        return self._core.file

    @property
    def aggregate(self) -> bool:
        return self._core.aggregate

    @property
    def parameters(self) -> list[str]:
        return self._core.parameters

    @property
    def nominal(self) -> dict[str, float]:
        """θ of the model's ``nominal { }`` block (0 where unlisted)."""
        return dict(zip(self._core.parameters, self._core.nominal))

    @property
    def states(self) -> list[str]:
        return self._core.states

    @property
    def inputs(self) -> list[str]:
        return self._core.inputs

    @property
    def columns(self) -> list[str]:
        """The data columns the model reads (after its ``data { }`` mapping)."""
        return self._core.columns

    @property
    def warnings(self) -> list[str]:
        """The compiler's warnings, one line each (``file:line:col: warning[code]: …``)."""
        return [python_spelling(w) for w in self._core.warnings]

    def check(
        self, patterns: Sequence[str] | None = None, *, centring: str | None = None
    ) -> Check:
        """The structure and identifiability report of ``leeway check``, for
        the given experiments' sign patterns or the smallest
        set the compiler finds. A pattern reads as ``leeway check --pattern``:
        ``"water.u:+,water.v:-"`` (arguments not named are ``+``).
        ``centring`` (``"experiment"``, ``"pooled"``, ``"none"``; default: the
        model's, as ``estimate`` uses it) is the instruments' centring the
        analysis assumes; a constant term it annihilates is reported with
        the centring and experiments that identify it."""
        if isinstance(patterns, str):
            patterns = [patterns]
        document = json.loads(
            _native(
                self._core.check_json,
                list(patterns) if patterns is not None else None,
                _text("centring", centring, optional=True),
            )
        )
        return Check._from_document(document)

    def select(
        self,
        data: Data,
        validate: Data | None = None,
        *,
        method: str = "iv3",
        lags: int = 1,
        tolerance: float = 1.0,
        step: float | None = None,
        time_tolerance: float = 0.05,
        resample: float | None = None,
    ) -> Selection:
        """Which of the model's candidate terms (parameters written
        ``?name``) the data need, as ``leeway select`` chooses them (the
        options are its flags; docs/selection.md). ``data`` are the
        estimation data as ``leeway.estimate`` takes them; ``validate``
        held-out data for the free-run criterion (default: each experiment
        held out in turn). ``lags`` should span the disturbances'
        correlation time in samples. Returns the path, the chosen model
        (``source``, ``model()``, ``write(path)``) and its ``estimate``; the
        chosen estimate's warnings are issued as ``LeewayWarning``, errors
        raise the classes of ``leeway.errors``."""
        from ._select import select  # _select imports this module

        return select(
            self, data, validate, method=method, lags=lags, tolerance=tolerance,
            step=step, time_tolerance=time_tolerance, resample=resample,
        )

    def __reduce__(self) -> tuple[Any, ...]:
        return (_model_from_source, (self.source, self.file, self.aggregate))

    def __repr__(self) -> str:
        return f"<leeway.Model {self.name} from {self.file}>"


def _model_from_source(source: str, file: str, aggregate: bool) -> Model:
    return Model.from_str(source, file=file, aggregate=aggregate)


SignPattern = dict[str, str]


@dataclass(frozen=True)
class Check:
    """What ``leeway check --json`` reports, with the regressors as a DataFrame."""

    model: str
    identifiable: bool
    verdict: str | None
    """``identifiable``, ``not-identifiable`` or ``undecided`` (search cut)."""
    parameters: tuple[str, ...]
    outputs: tuple[str, ...]
    required_sign_patterns: tuple[SignPattern, ...]
    """The smallest set of experiments' sign patterns that identifies θ;
    with ``any_single_pattern``, one example (any single pattern does)."""
    analysed_sign_patterns: tuple[SignPattern, ...]
    any_single_pattern: bool
    data_conditions: tuple[str, ...]
    """Conditions on the data, not the structure (a measured medium must
    vary): ``estimate`` checks them on its data, ``design`` plans for them."""
    centring: str | None
    """The instruments' centring the verdicts assume (``experiment``,
    ``pooled`` or ``none``); ``None`` when the model has errors."""
    regressors: pd.DataFrame
    """One row per (parameter, output): expression, term as written, kind."""
    combinations: tuple[dict[str, Any], ...]
    """Parameter groups that enter only through combinations, with what separates them."""
    nuisance: dict[str, Any]
    """The nuisance reduction: ``before``, ``after``, ``kept``, ``dropped``, ``regressors``."""
    aggregates: tuple[dict[str, Any], ...]
    candidates: dict[str, Any] | None
    """A candidate model's candidates (``?name``): ``candidates`` in
    declaration order, ``full_set`` the verdict on the full set,
    ``exchangeable`` [{``candidate``, ``stands_for``}] (``select`` keeps
    ``stands_for``), ``refused`` why ``select`` refuses them, or ``None``;
    ``None`` for a model without candidates (docs/selection.md)."""
    warnings: tuple[str, ...]
    notes: tuple[str, ...]
    document: dict[str, Any]
    """The whole ``check --json`` document."""

    @classmethod
    def _from_document(cls, d: dict[str, Any]) -> Check:
        separations = {tuple(s["parameters"]): s for s in d.get("separations", [])}
        combinations = tuple(
            {
                **u,
                "separated_by": separations.get(tuple(u["parameters"]), {}).get(
                    "sign_patterns"
                ),
            }
            for u in d.get("unidentifiable", [])
        )
        regressors = pd.DataFrame(
            d["regressors"], columns=["parameter", "output", "expression", "term", "kind"]
        )
        return cls(
            model=d["model"],
            identifiable=d["identifiable"],
            verdict=d["verdict"],
            parameters=tuple(d["parameters"]),
            outputs=tuple(d["outputs"]),
            required_sign_patterns=tuple(d["required_sign_patterns"]),
            analysed_sign_patterns=tuple(d["analysed_sign_patterns"]),
            any_single_pattern=d["any_single_pattern"],
            data_conditions=tuple(d.get("data_conditions", [])),
            centring=(d.get("centring") or {}).get("name"),
            regressors=regressors,
            combinations=combinations,
            nuisance=d["nuisance"],
            aggregates=tuple(d["aggregates"]),
            candidates=d.get("candidates"),
            warnings=tuple(python_spelling(w["message"]) for w in d["warnings"]),
            notes=tuple(python_spelling(n["message"]) for n in d["notes"]),
            document=d,
        )


class Estimate:
    """An estimate: θ with standard errors, the nuisance parameters, the
    disturbance means and the diagnostics, as ``leeway estimate`` reports them."""

    def __init__(self, document: str) -> None:
        self._json = document
        d = json.loads(document)
        self.document: dict[str, Any] = d
        self.method: str = d["method"]
        self.params: pd.DataFrame = _columns(d["parameters"])
        """θ: estimate, std_error, status, estimates (what it estimates), aggregate."""
        self.nuisance: pd.DataFrame = _columns(d["nuisance"])
        """The nuisance columns (``rho``/``lambda``), as ``params``."""
        names = list(d["estimates"])
        covariance = d.get("covariance", {})
        self.cov: pd.DataFrame = pd.DataFrame(
            [
                [np.nan if (v := covariance.get(a, {}).get(b)) is None else v for b in names]
                for a in names
            ],
            index=pd.Index(names, name="parameter"),
            columns=pd.Index(names, name="parameter"),
            dtype="float64",
        )
        """The covariance of θ (the robust sandwich the standard errors come
        from: ``std_error == sqrt(diag(cov))`` bit for bit), indexed and
        columned by parameter in the model's order; NaN in the row and column
        of a parameter that was not estimated (held, or absorbed by an
        aggregate)."""
        rows = [
            (dist, comp, m["mean"], m["std_error"])
            for dist, comps in d["disturbances"].items()
            for comp, m in comps.items()
        ]
        self.disturbances: pd.DataFrame = pd.DataFrame(
            rows, columns=["disturbance", "component", "mean", "std_error"]
        ).set_index(["disturbance", "component"])
        """Means of the unmeasured disturbances (paper Corollary 1)."""
        self.diagnostics: dict[str, Any] = d["diagnostics"]
        self.sign_patterns: list[dict[str, Any]] = d["sign_patterns"]
        self.experiments: list[dict[str, Any]] = d["experiments"]
        self.warnings: list[str] = [python_spelling(w) for w in d["warnings"]]
        """The estimate's warnings, in Python's spelling (``document`` keeps the CLI's)."""
        self.notes: list[str] = [python_spelling(n) for n in d["notes"]]
        self.delay_scan: dict[str, Any] | None = d.get("delay_scan")
        """With ``scan_delay``: the input, the criterion (``by``), the chosen
        dead time (``samples``, ``seconds``) and the ``curve`` of every
        candidate (docs/json.md); None otherwise."""

    @property
    def theta(self) -> dict[str, float]:
        """θ by name (held parameters at their nominal value)."""
        return dict(self.document["estimates"])

    def to_json(self) -> str:
        """The document of ``leeway estimate --json`` (without its final newline)."""
        return self._json

    @property
    def bse(self) -> pd.Series:
        """The standard errors of θ (statsmodels' name); NaN where none
        (held, dropped: see ``params.status``)."""
        return self.params["std_error"].rename("bse")

    @property
    def tvalues(self) -> pd.Series:
        """θ over its standard error; NaN where there is none."""
        return self.table()["t"].rename("tvalues")

    @property
    def pvalues(self) -> pd.Series:
        """Two-sided p-values of θ = 0 from the normal distribution (N is
        large; docs/python.md); NaN where there is no standard error."""
        return self.table()["p"].rename("pvalues")

    def conf_int(self, alpha: float = 0.05) -> pd.DataFrame:
        """The ``1 − alpha`` confidence intervals of θ, columns ``lower`` and
        ``upper``: estimate ∓ z·std_error with z the normal quantile
        (``statistics.NormalDist``); NaN where there is no standard error."""
        return self.table(alpha)[["lower", "upper"]]

    def table(self, alpha: float = 0.05) -> pd.DataFrame:
        """θ with ``estimate``, ``std_error``, ``t``, ``p``, ``lower``,
        ``upper`` (at ``1 − alpha``), ``status`` and ``note`` (why a row has
        no standard error)."""
        return _summary.table(self.params, alpha)

    def summary(self, alpha: float = 0.05) -> _summary.Summary:
        """The summary table of the estimate (print it); its ``tables`` are
        DataFrames of θ, the nuisance parameters and the disturbance means
        with t, p and the ``1 − alpha`` intervals."""
        return _summary.summary(
            self.document, self.params, self.nuisance, self.disturbances, self.warnings, alpha
        )

    def __repr__(self) -> str:
        estimated = int(self.params["status"].isin(["estimated", "aggregate"]).sum())
        n = sum(e["samples"] for e in self.experiments)
        return (
            f"<leeway.Estimate {self.method} of {self.document.get('model')}: "
            f"{estimated} of {len(self.params)} parameters estimated, "
            f"{len(self.nuisance)} nuisance, N={n} in {len(self.experiments)} experiment(s), "
            f"{len(self.warnings)} warning(s); .summary() for the table>"
        )


def _columns(entries: list[dict[str, Any]]) -> pd.DataFrame:
    frame = pd.DataFrame(
        entries,
        columns=["name", "kind", "value", "std_error", "status", "estimates", "aggregate"],
    )
    frame = frame.rename(columns={"value": "estimate"}).set_index("name")
    frame["estimate"] = frame["estimate"].astype("float64")
    frame["std_error"] = frame["std_error"].astype("float64")
    return frame


def _is_bool(v: Any) -> bool:
    return isinstance(v, (bool, np.bool_))


def _number(what: str, v: Any, *, code: str = "invalid-option", hint: str | None = None) -> float:
    """A finite real number (a Python or numpy int or float; never a bool,
    text or a complex number), as float."""
    if _is_bool(v) or not isinstance(v, numbers.Real):
        raise OptionError(
            f"{what} = {v!r} is a {type(v).__name__}, not a number",
            code=code,
            hint=hint or f"give {what} as a number",
        )
    try:
        value = float(v)
    except (TypeError, ValueError, OverflowError) as e:
        raise OptionError(f"{what} = {v!r}: {e}", code=code, hint=hint) from None
    if not np.isfinite(value):
        raise OptionError(
            f"{what} = {value} is not a finite number",
            code=code,
            hint=hint or f"give {what} as a finite number",
        )
    return value


def _integer(what: str, v: Any, lo: int, hi: int) -> int:
    if _is_bool(v) or not isinstance(v, numbers.Integral):
        raise OptionError(
            f"{what}={v!r} is a {type(v).__name__}, not an integer",
            code="invalid-option",
            hint=f"give {what} as an integer in {lo}..={hi}, e.g. {what}={lo + 1 if lo + 1 <= hi else lo}",
        )
    value = int(v)
    if not lo <= value <= hi:
        raise OptionError(
            f"{what}={value} is not in {lo}..={hi}",
            code="invalid-option",
            hint=f"give {what} as an integer in {lo}..={hi}",
        )
    return value


def _flag(what: str, v: Any) -> bool:
    if not _is_bool(v):
        raise OptionError(
            f"{what}={v!r} is a {type(v).__name__}, not a bool",
            code="invalid-option",
            hint=f"give {what}=True or {what}=False",
        )
    return bool(v)


def _text(what: str, v: Any, optional: bool = False) -> str | None:
    if v is None and optional:
        return None
    if not isinstance(v, str):
        raise OptionError(
            f"{what}={v!r} is a {type(v).__name__}, not a string",
            code="invalid-option",
            hint=f'give {what} as one of its names, e.g. {what}="{_EXAMPLES.get(what, "…")}"'
            + (" (or None)" if optional else ""),
        )
    return str(v)


def _seconds(what: str, v: Any, optional: bool = True) -> float | None:
    if v is None and optional:
        return None
    if isinstance(v, str):
        raise OptionError(
            f"{what}={v!r} is text, not a number of seconds",
            code="invalid-option",
            hint=f"give {what} as a number, e.g. {what}=0.1" + (" (or None)" if optional else ""),
        )
    return _number(what, v, hint=f"give {what} as a finite number" + (" (or None)" if optional else ""))


def _fraction(what: str, v: Any) -> float | None:
    """A fraction in (0, 1], or None."""
    if v is None:
        return None
    hint = f"give {what} as a fraction in (0, 1], e.g. {what}=0.1 (or None)"
    value = _number(what, v, hint=hint)
    if not 0.0 < value <= 1.0:
        raise OptionError(f"{what}={value} is not a fraction in (0, 1]", code="invalid-option", hint=hint)
    return value


_EXAMPLES = {"scan_delay": "tau_x=0..2s", "scan_by": "fit", "method": "iv3", "instruments": "simulated", "initial": "delayed", "centring": "experiment", "combine": "summed"}

# The CLI's bounds (cli/src/estimate.rs, py/src/lib.rs), checked here too so
# that an integer too large for the native half is the same OptionError.
_MAX_LAGS = 1000
_MAX_REFINEMENTS = 100


def _checked_options(options: dict[str, Any]) -> dict[str, Any]:
    """The estimate options type-checked (bools are not numbers, numbers
    not text) and converted to plain Python values (numpy scalars
    accepted), so the native half sees exactly what it declares."""
    out = dict(options)
    for key in ("method", "instruments", "initial", "combine"):
        out[key] = _text(key, options[key])
    out["centring"] = _text("centring", options["centring"], optional=True)
    for key in ("aggregate", "strict", "runaway_guard"):
        out[key] = _flag(key, options[key])
    out["lags"] = _integer("lags", options["lags"], 1, _MAX_LAGS)
    out["max_refinements"] = _integer("max_refinements", options["max_refinements"], 0, _MAX_REFINEMENTS)
    out["step"] = _seconds("step", options["step"])
    out["resample"] = _seconds("resample", options["resample"])
    out["time_tolerance"] = _seconds("time_tolerance", options["time_tolerance"], optional=False)
    if "refine_subsample" in options:
        out["refine_subsample"] = _fraction("refine_subsample", options["refine_subsample"])
    for key in ("scan_delay", "scan_by"):
        if key in options:
            out[key] = _text(key, options[key], optional=True)
    return out


def _by_name(model: Model, mapping: Mapping[Any, Any], what: str, code: str) -> list[Any]:
    """The values of ``{name: value}`` in the model's parameter order: every
    parameter exactly once (the rule of the CLI's parameter files, applied
    by the same code)."""
    keys = list(mapping)
    slots, unknown, missing = model._core.parameter_names([str(k) for k in keys])
    if unknown or missing:
        raise OptionError(
            f"{what} must give every parameter of the model once"
            + (f"; unknown: {', '.join(unknown)}" if unknown else "")
            + (f"; missing: {', '.join(missing)}" if missing else ""),
            code=code,
            hint=f"the parameters are {', '.join(model.parameters)}",
        )
    values: list[Any] = [None] * len(model.parameters)
    for key, slot in zip(keys, slots):
        assert slot is not None  # every name is a parameter (checked above)
        values[slot] = mapping[key]
    return values


def _nominal(model: Model, nominal: Mapping[str, float] | None) -> list[float] | None:
    if nominal is None:
        return None
    if not isinstance(nominal, Mapping):
        raise OptionError(
            f"nominal is a {type(nominal).__name__}, not a mapping",
            code="invalid-nominal",
            hint="pass nominal={name: value} with every parameter of the model",
        )
    values = _by_name(model, nominal, "nominal", "invalid-nominal")
    return [
        _number(f"nominal[{p!r}]", v, code="invalid-nominal", hint="nominal values are finite numbers")
        for p, v in zip(model.parameters, values)
    ]


def estimate(
    model: Model,
    data: Data,
    method: str = "iv3",
    *,
    instruments: str = "simulated",
    initial: str = "delayed",
    centring: str | None = None,
    combine: str = "summed",
    nominal: Mapping[str, float] | None = None,
    aggregate: bool = False,
    strict: bool = False,
    lags: int = 1,
    max_refinements: int = 8,
    runaway_guard: bool = True,
    refine_subsample: float | None = None,
    step: float | None = None,
    time_tolerance: float = 0.05,
    resample: float | None = None,
    scan_delay: str | None = None,
    scan_by: str = "fit",
) -> Estimate:
    """Estimates θ, the nuisance parameters and the disturbance means, as
    ``leeway estimate`` does (the options are its flags; docs/cli.md,
    "leeway estimate"). ``data`` is a DataFrame (split on its ``experiment``
    column if it has one), a list or dict of DataFrames (a dict names the
    experiments), or Arrow/polars tables. ``scan_delay="tau_x=0..2s"``
    (``--scan-delay``) finds an input's dead time: the estimate is at the
    best one, and ``Estimate.delay_scan`` holds the curve.
    ``refine_subsample=0.1`` (``--refine-subsample``) refines on the first
    tenth of every experiment before the whole records (for long records;
    the same fixed point within the tolerance, not the same bits). Warnings are
    issued as ``LeewayWarning``; errors raise the classes of
    ``leeway.errors``."""
    options = _estimate_options(
        model,
        method=method,
        instruments=instruments,
        initial=initial,
        centring=centring,
        combine=combine,
        nominal=nominal,
        aggregate=aggregate,
        strict=strict,
        lags=lags,
        max_refinements=max_refinements,
        runaway_guard=runaway_guard,
        refine_subsample=refine_subsample,
        step=step,
        time_tolerance=time_tolerance,
        resample=resample,
        scan_delay=scan_delay,
        scan_by=scan_by,
    )
    result = Estimate(_native(_leeway.estimate_json, model._core, _handover(model, data), options))
    _warn(result)
    return result


def _estimate_options(
    model: Model, *, nominal: Mapping[str, float] | None, **options: Any
) -> dict[str, Any]:
    """The options as the native half takes them (the CLI's flags), checked."""
    return {**_checked_options(options), "nominal": _nominal(model, nominal)}


def _native(f: Callable[..., T], *args: Any) -> T:
    """Calls the native half. A Rust panic is a bug of leeway, never an
    answer: it reaches the caller as an ``EstimateError`` (``internal-error``)
    rather than as ``pyo3_runtime.PanicException`` (a ``BaseException``
    that ``except Exception`` would not catch)."""
    try:
        return f(*args)
    except BaseException as e:
        if type(e).__name__ != "PanicException":
            raise
        raise EstimateError(
            f"internal error (a panic in leeway's native code): {e}",
            code="internal-error",
            hint="this is a bug of leeway: please report it with the model, the data and the options",
        ) from None


def _warn(result: Estimate) -> None:
    for w in result.warnings:
        warnings.warn(w, LeewayWarning, stacklevel=3)


Theta = Union[Mapping[str, float], Sequence[float], Estimate]
"""θ for a simulation: ``{name: value}`` with every parameter of the model,
values in the model's parameter order, or an ``Estimate`` (its θ, held
parameters at their nominal values)."""


def _theta(model: Model, theta: Any, what: str = "theta") -> list[float]:
    """θ in the model's parameter order from anything ``Theta`` allows
    (checked here, since the caller may pass anything)."""
    if isinstance(theta, Estimate):
        theta = theta.theta
    if isinstance(theta, Mapping):
        values = _by_name(model, theta, what, "invalid-params")
    elif isinstance(theta, (str, bytes)) or not isinstance(theta, (Sequence, np.ndarray)):
        raise OptionError(
            f"{what} is a {type(theta).__name__}",
            code="invalid-params",
            hint="pass {name: value}, a sequence in the model's parameter order, or an Estimate",
        )
    else:
        values = list(theta)
    names = [*model.parameters, *(f"#{i}" for i in range(len(model.parameters), len(values)))]
    return [
        _number(f"{what}[{n!r}]", v, code="invalid-params", hint="θ values are finite numbers")
        for n, v in zip(names, values)
    ]


def _named_values(values: Mapping[str, float] | None, what: str) -> list[tuple[str, float]]:
    if values is None:
        return []
    if not isinstance(values, Mapping):
        raise OptionError(
            f"{what} is a {type(values).__name__}, not a mapping",
            code="invalid-option",
            hint=f"pass {what}={{name: value}}",
        )
    out = []
    for k, v in values.items():
        if not isinstance(k, str):
            raise OptionError(
                f"{what} has the key {k!r}, a {type(k).__name__}",
                code="invalid-option",
                hint=f"name the entries of {what} by text, e.g. {what}={{\"u\": 5.0}}",
            )
        out.append((k, _number(f"{what}[{k!r}]", v, hint=f"{what} values are finite numbers (base units)")))
    return out


Disturbances = Union[Mapping[str, float], str, None]
"""Constant unmeasured disturbances for a simulation: ``{"current.north":
0.2}`` (components not given take the estimate's means when θ is an
``Estimate``, else zero), ``"zero"`` for none, or ``None`` (the estimate's
means; zero with a ``LeewayWarning`` when θ is not an ``Estimate``)."""


def _disturbances(given: Disturbances) -> tuple[list[tuple[str, float]], bool]:
    """The values given by name, and whether ``"zero"`` was asked."""
    if isinstance(given, str):
        if given != "zero":
            raise OptionError(
                f"disturbances={given!r}: the only word taken is \"zero\"",
                code="invalid-option",
                hint='pass disturbances="zero" or {"current.north": 0.2}',
            )
        return [], True
    return _named_values(given, "disturbances"), False


def _means(theta: Any) -> list[tuple[str, float]] | None:
    """The disturbance means of an ``Estimate`` by ``medium.component``
    (those it could estimate); ``None`` for any other θ."""
    if not isinstance(theta, Estimate):
        return None
    return [
        (f"{medium}.{component}", float(mean))
        for (medium, component), mean in theta.disturbances["mean"].items()
        if mean is not None and np.isfinite(mean)
    ]


def _held(held: list[tuple[str, float, str]]) -> dict[str, dict[str, Any]]:
    """What a simulation held, as ``validate --json`` says it (plain data:
    ``attrs`` travel into Parquet metadata as JSON)."""
    return {name: {"value": value, "from": origin} for name, value, origin in held}


def simulate(
    model: Model,
    theta: Theta,
    inputs: Frame,
    *,
    x0: Mapping[str, float] | None = None,
    disturbances: Disturbances = None,
    step: float | None = None,
    disturbance_std: Mapping[str, float] | None = None,
    correlation_time: Mapping[str, float] | None = None,
    noise: Mapping[str, float] | None = None,
    seed: int = 0,
) -> pd.DataFrame:
    """Simulates ``model`` with ``theta`` on ``inputs`` from its first row, as
    ``leeway simulate`` does (docs/cli.md, "leeway simulate"), and returns the
    trajectory: the columns ``leeway simulate`` writes (time, states,
    heading, inputs, measured rotation and disturbances; data column names,
    declared units), bit for bit.

    ``inputs`` is one experiment (a DataFrame, or an Arrow/polars table)
    with every input, measured rotation and measured disturbance on every
    row, and optionally ``time``; the states and the heading are read from
    its first row, and ``x0={"u": 5.0, "psi": 0.0}`` gives or overrides
    them (base units). Unmeasured disturbances are held constant: an
    ``Estimate``'s means by default, ``disturbances={"current.north": 0.2}``
    to give components, ``disturbances="zero"`` for none (``Disturbances``);
    ``frame.attrs["disturbances"]`` says what was held and from where,
    ``{"current.north": {"value": 0.2, "from": "estimate"}}`` (``from``:
    ``given``, ``estimate`` or ``default``). When the simulation diverges, a
    ``LeewayWarning`` says where, and the rows before are returned
    (``frame.attrs["diverged"]`` is then true).

    A trial's data as a logger would record them, as ``leeway simulate``'s
    ``--disturbance-std``, ``--correlation-time``, ``--noise`` and
    ``--seed`` give them: ``disturbance_std={"current": 0.03}`` makes a
    component (or every component of a medium) vary about its mean (the
    held value; for a measured medium the input's values, and the craft
    feels and its sensor records the variation), ``correlation_time=
    {"current": 60}`` in seconds (first-order Gauss–Markov; 0, the default:
    independent samples), ``noise={"u": 0.01, "psi": 0.005, "wind": 0.2}``
    the sensor noise of a state, the heading or a measured disturbance (the
    frame holds the measured values), ``seed`` (default 0): the same seed,
    the same bits, as the CLI's."""
    checked_theta = _theta(model, theta)
    checked_x0 = _named_values(x0, "x0")
    given, zero = _disturbances(disturbances)
    checked_step = _seconds("step", step)
    checked_std = _named_values(disturbance_std, "disturbance_std")
    checked_time = _named_values(correlation_time, "correlation_time")
    checked_noise = _named_values(noise, "noise")
    checked_seed = _integer("seed", seed, 0, 2**64 - 1)
    (name, columns, labels), = _handover(model, {"inputs": inputs})
    values, diverged, held, issued = _native(
        _leeway.simulate_columns,
        model._core,
        (name, columns, labels),
        checked_theta,
        checked_x0,
        given,
        zero,
        _means(theta),
        checked_step,
        checked_std,
        checked_time,
        checked_noise,
        checked_seed,
    )
    frame = pd.DataFrame(dict(values))
    frame.attrs["diverged"] = diverged is not None
    frame.attrs["disturbances"] = _held(held)
    for w in issued:
        warnings.warn(w, LeewayWarning, stacklevel=2)
    if diverged is not None:
        warnings.warn(python_spelling(diverged), LeewayWarning, stacklevel=2)
    return frame


Thetas = Union[Theta, Sequence[Theta], Mapping[str, Theta]]


def _thetas(given: Thetas) -> list[tuple[str, str, Any]]:
    """Each θ given: its name, how errors call it, and θ as passed (an
    ``Estimate`` kept for its disturbance means)."""
    if isinstance(given, Estimate):
        return [(given.method, "theta", given)]
    if isinstance(given, Mapping):
        if all(isinstance(v, (Estimate, Mapping, Sequence, np.ndarray)) and not isinstance(v, str)
               for v in given.values()) and given:
            return [(str(k), f"thetas[{k!r}]", v) for k, v in given.items()]
        return [("theta", "theta", given)]
    if isinstance(given, (Sequence, np.ndarray)) and not isinstance(given, (str, bytes)):
        items = list(given)
        if items and all(isinstance(v, (Estimate, Mapping, Sequence, np.ndarray)) for v in items):
            names = [v.method if isinstance(v, Estimate) else f"theta[{i}]" for i, v in enumerate(items)]
            if len(set(names)) < len(names):
                names = [f"theta[{i}]" for i in range(len(items))]
            return [(n, n, v) for n, v in zip(names, items)]
        return [("theta", "theta", given)]
    return [("theta", "theta", given)]


def validate(
    model: Model,
    thetas: Thetas,
    data: Data,
    *,
    disturbances: Disturbances = None,
    step: float | None = None,
    time_tolerance: float = 0.05,
    resample: float | None = None,
) -> pd.DataFrame:
    """Simulates the model with each θ on every experiment of ``data`` (from
    its first sample, with its inputs, measured disturbances and rotation)
    and returns the fits ``leeway validate`` reports, bit for bit:
    ``100·(1 − ‖y − ŷ‖/‖y − ȳ‖)`` in % per output, as MATLAB's ``compare``.

    ``thetas`` is one θ (a mapping, a sequence or an ``Estimate``), a list of
    them (named by the estimates' methods, else ``theta[i]``) or a dict
    naming each. ``data`` is what ``leeway.estimate`` takes. The frame is
    indexed by (``model``, ``experiment``) with the columns ``samples``,
    ``diverged`` and one per output (the states, then the integrated
    heading); after each θ's experiments a row ``experiment="mean"`` holds
    the mean over experiments (NaN when a simulation diverged; experiments
    with a constant measurement left out), as ``leeway validate --json``'s
    ``mean``. A fit is NaN when undefined (constant measurement, or the
    simulation diverged). Each θ holds the unmeasured disturbances as
    ``simulate`` does (an ``Estimate``'s own means by default;
    ``disturbances`` gives them for every θ); ``frame.attrs["disturbances"]``
    maps each θ's name to what it held. Warnings are issued as
    ``LeewayWarning``."""
    given = _thetas(thetas)
    named = [(n, _theta(model, t, what)) for n, what, t in given]
    fixed, zero = _disturbances(disturbances)
    checked_step = _seconds("step", step)
    checked_tolerance = _seconds("time_tolerance", time_tolerance, optional=False)
    checked_resample = _seconds("resample", resample)
    outputs, rows, means, issued, held = _native(
        _leeway.validate_fits,
        model._core,
        _handover(model, data),
        [t for _, t in named],
        [n for n, _ in named],
        fixed,
        zero,
        [_means(t) for _, _, t in given],
        checked_step,
        checked_tolerance,
        checked_resample,
    )
    records = []
    for m, (name, _) in enumerate(named):
        mine = [r for r in rows if r[0] == m]
        for _, experiment, samples, diverged, fits in mine:
            records.append((name, experiment, samples, diverged, *fits))
        records.append((
            name, "mean", sum(r[2] for r in mine), any(r[3] for r in mine), *means[m],
        ))
    frame = pd.DataFrame(
        records, columns=["model", "experiment", "samples", "diverged", *outputs]
    ).set_index(["model", "experiment"])
    frame[outputs] = frame[outputs].astype("float64")
    frame.attrs["disturbances"] = {n: _held(h) for (n, _), h in zip(named, held)}
    for w in issued:
        warnings.warn(python_spelling(w), LeewayWarning, stacklevel=2)
    return frame
