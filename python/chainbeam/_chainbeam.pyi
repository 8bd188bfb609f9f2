"""Type stubs of the extension module ``chainbeam._chainbeam`` (crates/chainbeam-py); checked
against the built module by ``python -m mypy.stubtest chainbeam`` (scripts/test-all)."""

from collections.abc import Callable
from os import PathLike
from typing import Any, final

import numpy as np
from numpy.typing import NDArray

__version__: str
__all__ = ["Scene", "_scene_from_state", "simulate", "_time_library_simulate", "_LibraryTrajectory", "gradient", "gradient_wrt", "_cancel_running", "optimize", "mpc", "_fatigue", "_fatigue_cell", "_fatigue_combine", "_reduced_north_atlantic", "_read_scatter", "_design", "_design_cell", "__version__"]

@final
class Scene:
    """A validated beam scene (the scene file format of docs/scene-format.md)."""

    @staticmethod
    def from_file(path: str | PathLike[str]) -> Scene: ...
    @staticmethod
    def from_toml(text: str, dir: str | PathLike[str] | None = None) -> Scene: ...
    def to_toml(self) -> str: ...
    def replace(self, changes: dict[str, Any]) -> Scene: ...
    def __getitem__(self, key: str, /) -> Any: ...
    def __contains__(self, key: str, /) -> bool: ...
    @property
    def n(self) -> int: ...
    @property
    def lengths(self) -> list[float]: ...
    @property
    def l1(self) -> float: ...
    @property
    def length(self) -> float: ...
    @property
    def duration(self) -> float: ...
    @property
    def section(self) -> dict[str, float] | None: ...
    @property
    def has_fatigue(self) -> bool: ...
    @property
    def has_waves(self) -> bool: ...
    @property
    def steps(self) -> int: ...
    @property
    def step(self) -> float: ...
    @property
    def is_spatial(self) -> bool: ...
    def __eq__(self, value: object, /) -> bool: ...
    def __reduce__(self) -> tuple[Any, tuple[str, str | None]]: ...

def _scene_from_state(text: str, dir: str | PathLike[str] | None = None) -> Scene: ...
@final
class _LibraryTrajectory:
    """A library trajectory held for ``_time_library_simulate`` (freed when dropped)."""

def _time_library_simulate(scene: Scene) -> tuple[float, _LibraryTrajectory]: ...
def simulate(
    scene: Scene,
    controls: NDArray[np.float64] | None = None,
    controls_x: NDArray[np.float64] | None = None,
) -> dict[str, NDArray[np.float64]]: ...
def gradient(
    scene: Scene,
    controls: NDArray[np.float64] | None = None,
    controls_x: NDArray[np.float64] | None = None,
    effort: float = 0.0,
) -> tuple[float, NDArray[np.float64], bool]: ...
def _cancel_running() -> int: ...
def gradient_wrt(
    scene: Scene,
    wrt: list[str],
    controls: NDArray[np.float64] | None = None,
    controls_x: NDArray[np.float64] | None = None,
    effort: float = 0.0,
) -> tuple[float, NDArray[np.float64] | None, list[float], bool]: ...
def optimize(
    scene: Scene,
    method: str = "auto",
    bound: float | None = None,
    lower: float | None = None,
    upper: float | None = None,
    starts: int = 1,
    seed: int = 0,
    max_iters: int | None = None,
    gtol: float | None = None,
    effort: float = 0.0,
    controls: NDArray[np.float64] | None = None,
    controls_x: NDArray[np.float64] | None = None,
    progress: Callable[[int, int], Any] | None = None,
) -> dict[str, Any]: ...
def mpc(
    scene: Scene,
    model: Scene | None = None,
    horizon: float | None = None,
    interval: float | None = None,
    iterations: int | None = None,
    solver: str = "auto",
    first_iterations: int = 50,
    bound: float | None = None,
    effort: float | None = None,
    rate_penalty: float = 0.0,
    baselines: bool = False,
    plan_pendulums: int | None = None,
    plan_step: float | None = None,
    progress: Callable[[int, int], Any] | None = None,
) -> dict[str, Any]: ...

_Cell = tuple[float, float, float, float | None]
_Run = tuple[
    float, float, float, float | None, list[float] | None, list[float], list[float] | None
]

def _fatigue(
    scene: Scene,
    scatter: list[_Cell] | None,
    controllers: list[str] | None,
    settings: dict[str, Any],
    progress: Callable[[int, int], Any] | None = None,
) -> dict[str, Any]: ...
def _fatigue_cell(
    scene: Scene,
    scatter: list[_Cell],
    index: int,
    controllers: list[str] | None,
    settings: dict[str, Any],
) -> list[_Run]: ...
def _fatigue_combine(
    scene: Scene,
    scatter: list[_Cell],
    controllers: list[str] | None,
    settings: dict[str, Any],
    runs: list[list[_Run]],
) -> dict[str, Any]: ...
def _reduced_north_atlantic() -> list[tuple[float, float, float]]: ...
def _read_scatter(path: str) -> list[tuple[float, float, float, float | None]]: ...
def _design(
    scene: Scene,
    scatter: list[_Cell] | None,
    sensitivities: bool,
    record: float | None,
    spin_up: float,
    runner: Callable[[list[str], list[float], bool], list[tuple[float, float, float, list[float]]]]
    | None = None,
    on_iterate: Callable[[dict[str, Any]], Any] | None = None,
) -> str: ...
def _design_cell(
    scene: Scene,
    scatter: list[_Cell] | None,
    index: int,
    names: list[str],
    values: list[float],
    gradient: bool,
    record: float | None,
    spin_up: float,
) -> tuple[float, float, float, list[float]]: ...
