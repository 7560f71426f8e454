"""leeway for Python: compile vessel models written in the ``.som`` language,
prove whether their parameters are identifiable, and estimate them with
instrumental variables from pandas DataFrames.

>>> model = leeway.Model.load("examples/models/ship.som")   # doctest: +SKIP
>>> model.check().identifiable                               # doctest: +SKIP
>>> est = leeway.estimate(model, df, method="iv3")           # doctest: +SKIP
>>> print(est.summary())                                     # doctest: +SKIP
>>> est.conf_int()                                           # doctest: +SKIP
>>> leeway.simulate(model, est, inputs)                      # doctest: +SKIP
>>> leeway.validate(model, {"iv3": est}, held_out)           # doctest: +SKIP
>>> model.select(df).kept                                    # doctest: +SKIP
>>> leeway.residuals(model, est, held_out).tests             # doctest: +SKIP
>>> leeway.design(model, "plan.toml", verify=100).prediction # doctest: +SKIP
>>> log = leeway.read_log(model, "ferry.toml")               # doctest: +SKIP

Everything is computed by the same Rust code as the ``leeway`` command:
``Estimate.to_json()`` is the document of ``leeway estimate --json``,
``simulate`` returns what ``leeway simulate`` writes, ``validate`` the
fits ``leeway validate`` prints, ``residuals`` the analysis of
``leeway validate --resid`` and ``design`` the trial design of ``leeway
design --json``, bit for bit. Figures: ``leeway.plot``
(matplotlib, imported only when used).
"""

from . import errors
from ._api import Check, Estimate, Model, Theta, estimate, simulate, validate
from ._design import Design, Verification, design
from ._leeway import __version__
from ._logs import Log, read_log
from ._residuals import ResidualAnalysis, predict, residuals
from ._select import Selection
from ._summary import Summary
from .errors import (
    DataError,
    DesignError,
    EstimateError,
    LeewayError,
    LeewayWarning,
    ModelError,
    OptionError,
    PlanError,
    RankDeficient,
    SignViolation,
    Unidentifiable,
)

__all__ = [
    "Model",
    "Check",
    "Estimate",
    "Summary",
    "ResidualAnalysis",
    "Selection",
    "Design",
    "Verification",
    "Log",
    "estimate",
    "simulate",
    "validate",
    "residuals",
    "predict",
    "design",
    "read_log",
    "Theta",
    "__version__",
    *errors.__all__,
]
