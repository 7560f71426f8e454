# The native half of leeway (py/src/lib.rs). Checked against the built
# module by `python -m mypy.stubtest leeway._leeway` (py/tests).
from typing import Any, final


import numpy as np
import numpy.typing as npt

__all__ = ["Model", "estimate_json", "simulate_columns", "validate_fits"]

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
    def experiment_column(self) -> str: ...
    @property
    def warnings(self) -> list[str]: ...
    def check_json(self, patterns: list[str] | None = None) -> str: ...

def estimate_json(
    model: Model,
    frames: list[tuple[str, list[tuple[str, npt.NDArray[np.float64]]], list[str] | None]],
    options: dict[str, Any],
) -> str: ...

def simulate_columns(
    model: Model,
    frame: tuple[str, list[tuple[str, npt.NDArray[np.float64]]], list[str] | None],
    theta: list[float],
    x0: list[tuple[str, float]],
    disturbances: list[tuple[str, float]],
    step: float | None = None,
) -> tuple[list[tuple[str, npt.NDArray[np.float64]]], str | None]: ...
def validate_fits(
    model: Model,
    frames: list[tuple[str, list[tuple[str, npt.NDArray[np.float64]]], list[str] | None]],
    thetas: list[list[float]],
    names: list[str],
    disturbances: list[tuple[str, float]],
    step: float | None = None,
    time_tolerance: float = 0.05,
    resample: float | None = None,
) -> tuple[
    list[str],
    list[tuple[int, str, int, bool, list[float | None]]],
    list[list[float | None]],
    list[str],
]: ...
