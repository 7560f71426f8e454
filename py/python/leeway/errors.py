"""The exceptions of leeway, one class per family of the stable error codes
that ``leeway estimate --json`` and ``leeway check --json`` report."""

from __future__ import annotations

import json
from typing import Any

from ._hints import python_spelling


class LeewayError(Exception):
    """A leeway error: ``code`` is the CLI's stable kebab-case code,
    ``hint`` how to fix it, ``location`` where (``file:line:col`` in a model,
    ``frame: row r, column `c``` in data) or ``None``; ``report``, where the
    error comes with one, the JSON document of ``leeway check --json``."""

    def __init__(
        self,
        message: str,
        *,
        code: str,
        hint: str | None = None,
        location: str | None = None,
        report: str | None = None,
    ) -> None:
        # The native half words its messages for the command line.
        message = python_spelling(message)
        super().__init__(message)
        self.message = message
        self.code = code
        self.hint = python_spelling(hint) if hint is not None else None
        self.location = location
        self.report: dict[str, Any] = json.loads(report) if report else {}

    def __str__(self) -> str:
        text = f"{self.location}: {self.message}" if self.location else self.message
        return f"{text} [{self.code}]" + (f"\n  help: {self.hint}" if self.hint else "")

    def __reduce__(self) -> tuple[Any, ...]:
        return (_rebuild, (type(self), self.message, self.__dict__))


def _rebuild(cls: type[LeewayError], message: str, state: dict[str, Any]) -> LeewayError:
    error = cls.__new__(cls)
    Exception.__init__(error, message)
    error.__dict__.update(state)
    return error


class ModelError(LeewayError):
    """The model does not compile. ``diagnostics`` lists every error as
    ``leeway check --json`` does (code, message, location, file, line,
    column, labels, help, notes); the exception's own fields are the first."""

    @property
    def diagnostics(self) -> list[dict[str, Any]]:
        return list(self.report.get("errors", []))


class DataError(LeewayError, ValueError):
    """The data cannot be read as the model's experiments (a missing column,
    a value that is not finite, time stamps off the step, too few samples)."""


class OptionError(LeewayError, ValueError):
    """An argument out of range or not one of its choices."""


class EstimateError(LeewayError):
    """Model and data are valid, but no estimate could be computed."""


class Unidentifiable(EstimateError):
    """θ is not identifiable from these experiments (``unidentifiable``)."""


class RankDeficient(EstimateError):
    """A combination of the parameters is not excited by the data (``rank-deficient``)."""


class SignViolation(EstimateError):
    """A sign assumption (paper A7) is violated under ``strict=True`` (``sign-violation``)."""


class PlanError(LeewayError, ValueError):
    """A trial plan (``leeway.design``'s ``plan``) cannot be read: a syntax
    error at ``location`` ``plan.toml:line:col``, an unknown name, a value
    out of range (``plan``)."""


class DesignError(LeewayError):
    """Model and plan are valid, but no trial can be designed for them
    (``cannot-design``: no steady state within the input limits, a rotation
    measured entry by entry). A model no trial can identify raises
    ``Unidentifiable`` (``not-identifiable``)."""


class LeewayWarning(UserWarning):
    """A warning of the model, the data checks or the estimator."""


__all__ = [
    "LeewayError",
    "ModelError",
    "DataError",
    "OptionError",
    "EstimateError",
    "Unidentifiable",
    "RankDeficient",
    "SignViolation",
    "PlanError",
    "DesignError",
    "LeewayWarning",
]
