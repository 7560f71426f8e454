# The native half of leeway (py/src/lib.rs). Checked against the built
# module by `python -m mypy.stubtest leeway._leeway` (py/tests).
from collections.abc import Callable
from typing import Any, final


import numpy as np
import numpy.typing as npt

__version__: str

__all__ = [
    "__version__",
    "Model",
    "Dataset",
    "estimate_json",
    "select_json",
    "estimate_mapped",
    "simulate_columns",
    "validate_fits",
    "residual_analysis",
    "study_tasks",
    "study_run",
    "study_summary",
    "Designed",
    "read_log",
]

@final
class Model:
    @staticmethod
    def compile_text(source: str, file: str, aggregate: bool = False) -> Model: ...
    @staticmethod
    def compile_bytes(data: bytes, file: str, aggregate: bool = False) -> Model: ...
    @property
    def source(self) -> str: ...
    @property
    def file(self) -> str: ...
    @property
    def aggregate(self) -> bool: ...
    @property
    def name(self) -> str: ...
    @property
    def parameters(self) -> list[str]: ...
    @property
    def nominal(self) -> list[float]: ...
    @property
    def states(self) -> list[str]: ...
    @property
    def inputs(self) -> list[str]: ...
    @property
    def columns(self) -> list[str]: ...
    @property
    def time_unit(self) -> str | None: ...
    @property
    def experiment_column(self) -> str: ...
    @property
    def warnings(self) -> list[str]: ...
    def parameter_names(self, names: list[str]) -> tuple[list[int | None], list[str], list[str]]: ...
    def check_json(self, patterns: list[str] | None = None, centring: str | None = None) -> str: ...

def estimate_json(
    model: Model,
    frames: list[tuple[str, list[tuple[str, npt.NDArray[np.float64]]], tuple[npt.NDArray[np.int64], list[str]] | None]],
    options: dict[str, Any],
) -> str: ...

def select_json(
    model: Model,
    frames: list[tuple[str, list[tuple[str, npt.NDArray[np.float64]]], tuple[npt.NDArray[np.int64], list[str]] | None]],
    validate: list[tuple[str, list[tuple[str, npt.NDArray[np.float64]]], tuple[npt.NDArray[np.int64], list[str]] | None]],
    args: dict[str, Any],
) -> tuple[str, str, str]: ...

@final
class Dataset:
    @staticmethod
    def open(model: Model, path: str, options: dict[str, Any]) -> Dataset: ...
    @staticmethod
    def from_frames(
        model: Model,
        frames: list[tuple[str, list[tuple[str, npt.NDArray[np.float64]]], tuple[npt.NDArray[np.int64], list[str]] | None]],
        options: dict[str, Any],
    ) -> Dataset: ...
    def summary(self) -> bytes: ...
    def __len__(self) -> int: ...
    def facts(self, request: bytes) -> list[bytes]: ...
    def run(self, offset: int, request: bytes) -> list[bytes]: ...

def estimate_mapped(
    model: Model,
    files: list[str],
    summaries: list[bytes],
    options: dict[str, Any],
    facts: Callable[[bytes], list[bytes]],
    run: Callable[[bytes], list[bytes]],
) -> str: ...

def study_tasks(config: dict[str, Any]) -> list[tuple[int, int]]: ...
def study_run(model: Model, config: dict[str, Any], case: int, run: int) -> bytes: ...
def study_summary(config: dict[str, Any], runs: list[bytes]) -> str: ...
@final
class Designed:
    @staticmethod
    def make(
        model: Model, plan: str, json: bool, plan_name: str, located: bool, options: dict[str, Any]
    ) -> Designed: ...
    @property
    def parameters(self) -> list[str]: ...
    @property
    def theta(self) -> list[float]: ...
    @property
    def verifiable(self) -> bool: ...
    def document(self) -> str: ...
    def trial(self, index: int) -> bytes: ...
    def summarise(self, trials: list[bytes]) -> str: ...
    def runs(self) -> list[list[tuple[str, npt.NDArray[np.float64]]]]: ...

def read_log(
    model: Model,
    path: str,
    max_gap: float | None = None,
    keep: list[tuple[float | None, float | None]] = ...,
) -> tuple[list[tuple[str, list[tuple[str, npt.NDArray[np.float64]]]]], str]: ...
def simulate_columns(
    model: Model,
    frame: tuple[str, list[tuple[str, npt.NDArray[np.float64]]], tuple[npt.NDArray[np.int64], list[str]] | None],
    theta: list[float],
    x0: list[tuple[str, float]],
    disturbances: list[tuple[str, float]],
    zero: bool = False,
    means: list[tuple[str, float]] | None = None,
    step: float | None = None,
    disturbance_std: list[tuple[str, float]] = ...,
    correlation_time: list[tuple[str, float]] = ...,
    noise: list[tuple[str, float]] = ...,
    seed: int = 0,
) -> tuple[
    list[tuple[str, npt.NDArray[np.float64]]],
    str | None,
    list[tuple[str, float, str]],
    list[str],
]: ...
def validate_fits(
    model: Model,
    frames: list[tuple[str, list[tuple[str, npt.NDArray[np.float64]]], tuple[npt.NDArray[np.int64], list[str]] | None]],
    thetas: list[list[float]],
    names: list[str],
    disturbances: list[tuple[str, float]],
    zero: bool = False,
    means: list[list[tuple[str, float]] | None] = ...,
    step: float | None = None,
    time_tolerance: float = 0.05,
    resample: float | None = None,
) -> tuple[
    list[str],
    list[tuple[int, str, int, bool, list[float | None]]],
    list[list[float | None]],
    list[str],
    list[list[tuple[str, float, str]]],
]: ...
def residual_analysis(
    model: Model,
    frames: list[tuple[str, list[tuple[str, npt.NDArray[np.float64]]], tuple[npt.NDArray[np.int64], list[str]] | None]],
    theta: list[float],
    disturbances: list[tuple[str, float]],
    lags: int,
    zero: bool = False,
    means: list[tuple[str, float]] | None = None,
    step: float | None = None,
    time_tolerance: float = 0.05,
    resample: float | None = None,
    one_step: bool = False,
) -> tuple[
    list[
        tuple[
            str,
            float,
            list[npt.NDArray[np.float64]],
            list[npt.NDArray[np.float64]],
            list[npt.NDArray[np.float64]],
        ]
    ],
    str,
    list[str],
]: ...
