"""leeway for Python: compile vessel models written in the ``.som`` language,
prove whether their parameters are identifiable, and estimate them with
instrumental variables from pandas DataFrames.

>>> model = leeway.Model.load("examples/models/ship.som")   # doctest: +SKIP
>>> model.check().identifiable                               # doctest: +SKIP
>>> est = leeway.estimate(model, df, method="iv3")           # doctest: +SKIP
>>> est.params                                               # doctest: +SKIP
>>> est.cov                                                  # doctest: +SKIP
>>> leeway.simulate(model, est, inputs)                      # doctest: +SKIP
>>> leeway.validate(model, {"iv3": est}, held_out)           # doctest: +SKIP

Everything is computed by the same Rust code as the ``leeway`` command:
``Estimate.to_json()`` is the document of ``leeway estimate --json``,
``simulate`` returns what ``leeway simulate`` writes and ``validate`` the
fits ``leeway validate`` prints, bit for bit.
"""

from __future__ import annotations

import json
import os
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Union

import numpy as np
import pandas as pd

from . import _leeway
from .errors import (
    DataError,
    EstimateError,
    LeewayError,
    LeewayWarning,
    ModelError,
    OptionError,
    RankDeficient,
    SignViolation,
    Unidentifiable,
)

__all__ = [
    "Model",
    "Check",
    "Estimate",
    "estimate",
    "simulate",
    "validate",
    "Theta",
    "LeewayError",
    "ModelError",
    "DataError",
    "OptionError",
    "EstimateError",
    "Unidentifiable",
    "RankDeficient",
    "SignViolation",
    "LeewayWarning",
]


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
        with open(path, "rb") as f:
            data = f.read()
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
        return self._core.warnings

    def check(self, patterns: Sequence[str] | None = None) -> Check:
        """The structure and identifiability report of ``leeway check``, for
        the given experiments' sign patterns or the smallest
        set the compiler finds. A pattern reads as ``leeway check --pattern``:
        ``"water.u:+,water.v:-"`` (arguments not named are ``+``)."""
        document = json.loads(
            self._core.check_json(list(patterns) if patterns is not None else None)
        )
        return Check._from_document(document)

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
    analysed_sign_patterns: tuple[SignPattern, ...]
    any_single_pattern: bool
    regressors: pd.DataFrame
    """One row per (parameter, output): expression, term as written, kind."""
    combinations: tuple[dict[str, Any], ...]
    """Parameter groups that enter only through combinations, with what separates them."""
    nuisance: dict[str, Any]
    """The nuisance reduction: ``before``, ``after``, ``kept``, ``dropped``, ``regressors``."""
    aggregates: tuple[dict[str, Any], ...]
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
            regressors=regressors,
            combinations=combinations,
            nuisance=d["nuisance"],
            aggregates=tuple(d["aggregates"]),
            warnings=tuple(w["message"] for w in d["warnings"]),
            notes=tuple(n["message"] for n in d["notes"]),
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
        self.warnings: list[str] = d["warnings"]
        self.notes: list[str] = d["notes"]

    @property
    def theta(self) -> dict[str, float]:
        """θ by name (held parameters at their nominal value)."""
        return dict(self.document["estimates"])

    def to_json(self) -> str:
        """The document of ``leeway estimate --json`` (without its final newline)."""
        return self._json

    def __repr__(self) -> str:
        return f"<leeway.Estimate {self.method}: {len(self.params)} parameters>"


def _columns(entries: list[dict[str, Any]]) -> pd.DataFrame:
    frame = pd.DataFrame(
        entries,
        columns=["name", "kind", "value", "std_error", "status", "estimates", "aggregate"],
    )
    frame = frame.rename(columns={"value": "estimate"}).set_index("name")
    frame["estimate"] = frame["estimate"].astype("float64")
    frame["std_error"] = frame["std_error"].astype("float64")
    return frame


Frame = Any  # a pandas DataFrame, or anything with ``to_pandas()`` / ``__arrow_c_stream__``
Data = Union[Frame, Sequence[Frame], Mapping[str, Frame]]


def _to_pandas(frame: Any, name: str) -> pd.DataFrame:
    if isinstance(frame, pd.DataFrame):
        return frame
    if hasattr(frame, "to_pandas"):  # pyarrow.Table, polars.DataFrame
        return frame.to_pandas()
    if hasattr(frame, "__arrow_c_stream__"):
        import pyarrow as pa

        return pa.table(frame).to_pandas()
    raise DataError(
        f"{type(frame).__name__} is not a DataFrame",
        code="data",
        location=name,
        hint="pass a pandas DataFrame, a list or dict of them, or an Arrow/polars table",
    )


def _frames(data: Data) -> list[tuple[str, Any]]:
    if isinstance(data, Mapping):
        return [(str(k), v) for k, v in data.items()]
    if isinstance(data, Sequence) and not isinstance(data, (str, bytes)):
        return [(f"data[{i}]", v) for i, v in enumerate(data)]
    return [("data", data)]


def _handover(model: Model, data: Data) -> list[tuple[str, list[tuple[str, np.ndarray]], list[str] | None]]:
    """The model's columns of every frame as contiguous float64 arrays (a
    view, not a copy, where the column already is one) and the experiment
    labels as text."""
    out = []
    experiment_column = model._core.experiment_column
    for name, raw in _frames(data):
        frame = _to_pandas(raw, name)
        if not frame.columns.is_unique:
            twice = sorted({str(c) for c in frame.columns[frame.columns.duplicated()]})
            raise DataError(
                f"column `{twice[0]}` appears more than once",
                code="data",
                location=name,
                hint="give every column one name",
            )
        columns = []
        for column in model.columns:
            if column not in frame.columns:
                continue  # the loader names what is missing, as for a file
            try:
                values = frame[column].to_numpy(dtype=np.float64, copy=False)
            except (TypeError, ValueError) as e:
                raise DataError(
                    f"column `{column}` is not numeric ({frame[column].dtype}): {e}",
                    code="data",
                    location=f"{name}: column `{column}`",
                    hint="convert the column to numbers, e.g. with pd.to_numeric",
                ) from None
            columns.append((column, np.ascontiguousarray(values)))
        labels = None
        if experiment_column in frame.columns:
            labels = frame[experiment_column].astype(str).tolist()
        out.append((name, columns, labels))
    return out


def _nominal(model: Model, nominal: Mapping[str, float] | None) -> list[float] | None:
    if nominal is None:
        return None
    unknown = [k for k in nominal if k not in model.parameters]
    missing = [p for p in model.parameters if p not in nominal]
    if unknown or missing:
        raise OptionError(
            "nominal must give every parameter of the model once"
            + (f"; unknown: {', '.join(unknown)}" if unknown else "")
            + (f"; missing: {', '.join(missing)}" if missing else ""),
            code="invalid-option",
            hint=f"the parameters are {', '.join(model.parameters)}",
        )
    return [float(nominal[p]) for p in model.parameters]


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
    step: float | None = None,
    time_tolerance: float = 0.05,
    resample: float | None = None,
) -> Estimate:
    """Estimates θ, the nuisance parameters and the disturbance means, as
    ``leeway estimate`` does (the options are its flags; README,
    "Estimating"). ``data`` is a DataFrame (split on its ``experiment``
    column if it has one), a list or dict of DataFrames (a dict names the
    experiments), or Arrow/polars tables. Warnings are issued as
    ``LeewayWarning``; errors raise the classes of ``leeway.errors``."""
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
        step=step,
        time_tolerance=time_tolerance,
        resample=resample,
    )
    result = Estimate(_leeway.estimate_json(model._core, _handover(model, data), options))
    _warn(result)
    return result


def _estimate_options(
    model: Model, *, nominal: Mapping[str, float] | None, **options: Any
) -> dict[str, Any]:
    """The options as the native half takes them (the CLI's flags)."""
    return {**options, "nominal": _nominal(model, nominal)}


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
        unknown = [str(k) for k in theta if k not in model.parameters]
        missing = [p for p in model.parameters if p not in theta]
        if unknown or missing:
            raise OptionError(
                f"{what} must give every parameter of the model once"
                + (f"; unknown: {', '.join(unknown)}" if unknown else "")
                + (f"; missing: {', '.join(missing)}" if missing else ""),
                code="invalid-params",
                hint=f"the parameters are {', '.join(model.parameters)}",
            )
        values = [theta[p] for p in model.parameters]
    elif isinstance(theta, (str, bytes)) or not isinstance(theta, (Sequence, np.ndarray)):
        raise OptionError(
            f"{what} is a {type(theta).__name__}",
            code="invalid-params",
            hint="pass {name: value}, a sequence in the model's parameter order, or an Estimate",
        )
    else:
        values = list(theta)
    try:
        return [float(v) for v in values]
    except (TypeError, ValueError) as e:
        raise OptionError(
            f"{what} holds a value that is not a number: {e}",
            code="invalid-params",
            hint="θ values are numbers",
        ) from None


def _named_values(values: Mapping[str, float] | None, what: str) -> list[tuple[str, float]]:
    if values is None:
        return []
    if not isinstance(values, Mapping):
        raise OptionError(
            f"{what} is a {type(values).__name__}, not a mapping",
            code="invalid-option",
            hint=f"pass {what}={{name: value}}",
        )
    try:
        return [(str(k), float(v)) for k, v in values.items()]
    except (TypeError, ValueError) as e:
        raise OptionError(f"{what}: {e}", code="invalid-option") from None


def simulate(
    model: Model,
    theta: Theta,
    inputs: Frame,
    *,
    x0: Mapping[str, float] | None = None,
    disturbances: Mapping[str, float] | None = None,
    step: float | None = None,
) -> pd.DataFrame:
    """Simulates ``model`` with ``theta`` on ``inputs`` from its first row, as
    ``leeway simulate`` does (README, "leeway simulate"), and returns the
    trajectory: the columns ``leeway simulate`` writes (time, states,
    heading, inputs, measured rotation and disturbances; data column names,
    declared units), bit for bit.

    ``inputs`` is one experiment (a DataFrame, or an Arrow/polars table)
    with every input, measured rotation and measured disturbance on every
    row, and optionally ``time``; the states and the heading are read from
    its first row, and ``x0={"u": 5.0, "psi": 0.0}`` gives or overrides
    them (base units). ``disturbances={"current.north": 0.2}`` holds
    unmeasured components constant (others are zero). When the simulation
    diverges, a ``LeewayWarning`` says where, and the rows before are
    returned (``frame.attrs["diverged"]`` is then true)."""
    (name, columns, labels), = _handover(model, {"inputs": inputs})
    values, diverged = _leeway.simulate_columns(
        model._core,
        (name, columns, labels),
        _theta(model, theta),
        _named_values(x0, "x0"),
        _named_values(disturbances, "disturbances"),
        step,
    )
    frame = pd.DataFrame(dict(values))
    frame.attrs["diverged"] = diverged is not None
    if diverged is not None:
        warnings.warn(diverged, LeewayWarning, stacklevel=2)
    return frame


Thetas = Union[Theta, Sequence[Theta], Mapping[str, Theta]]


def _thetas(model: Model, given: Thetas) -> list[tuple[str, list[float]]]:
    if isinstance(given, Estimate):
        return [(given.method, _theta(model, given))]
    if isinstance(given, Mapping):
        if all(isinstance(v, (Estimate, Mapping, Sequence, np.ndarray)) and not isinstance(v, str)
               for v in given.values()) and given:
            return [(str(k), _theta(model, v, f"thetas[{k!r}]")) for k, v in given.items()]
        return [("theta", _theta(model, given))]
    if isinstance(given, (Sequence, np.ndarray)) and not isinstance(given, (str, bytes)):
        items = list(given)
        if items and all(isinstance(v, (Estimate, Mapping, Sequence, np.ndarray)) for v in items):
            names = [v.method if isinstance(v, Estimate) else f"theta[{i}]" for i, v in enumerate(items)]
            if len(set(names)) < len(names):
                names = [f"theta[{i}]" for i in range(len(items))]
            return [(n, _theta(model, v, n)) for n, v in zip(names, items)]
        return [("theta", _theta(model, given))]
    return [("theta", _theta(model, given))]


def validate(
    model: Model,
    thetas: Thetas,
    data: Data,
    *,
    disturbances: Mapping[str, float] | None = None,
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
    simulation diverged). Warnings are issued as ``LeewayWarning``."""
    named = _thetas(model, thetas)
    outputs, rows, means, issued = _leeway.validate_fits(
        model._core,
        _handover(model, data),
        [t for _, t in named],
        [n for n, _ in named],
        _named_values(disturbances, "disturbances"),
        step,
        time_tolerance,
        resample,
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
    for w in issued:
        warnings.warn(w, LeewayWarning, stacklevel=2)
    return frame
