"""The exceptions of chainbeam, raised with the Rust library's messages.

Every exception is a :class:`ChainbeamError` and carries ``kind``, the name of the library's
error variant (``"Scene"``, ``"NewtonNotConverged"``, ``"Folded"``, ...), and ``key``: the scene
key (``"beam.mass"``) or the argument (``"controls"``) the error names, or ``None``.

==============================  =====================  =====================================
exception                       also a                 raised for
==============================  =====================  =====================================
:class:`SceneError`             ``ValueError``         an invalid scene (``.key``, ``.file``)
:class:`InvalidArgumentError`   ``ValueError``         an invalid argument of a call
:class:`SimulationError`        ``RuntimeError``       a failed computation (the beam folds,
                                                       a singular constraint system, ...)
:class:`ConvergenceError`       ``RuntimeError``       an iteration that did not converge:
                                                       RATTLE's Newton solve, the statics, or
                                                       ``optimize`` (then ``.result`` holds
                                                       the result)
:class:`TrajectoryTooLargeError` ``MemoryError``       a trajectory over the memory budget
==============================  =====================  =====================================
"""

from __future__ import annotations

from typing import Any


class ChainbeamError(Exception):
    """Base class of chainbeam's errors (``kind``: the library's variant; ``key``: the key or
    argument the error names, or ``None``)."""

    def __init__(
        self, message: str, kind: str = "", key: str | None = None, file: str | None = None
    ) -> None:
        super().__init__(message, kind, key, file)
        self.message = message
        self.kind = kind
        self.key = key
        self.file = file

    def __str__(self) -> str:
        return self.message


class SceneError(ChainbeamError, ValueError):
    """An invalid scene; ``key`` names the offending key (``"beam.mass"``,
    ``"loads.point[0].node"``), ``file`` the scene file when it was read from one."""


class InvalidArgumentError(ChainbeamError, ValueError):
    """An invalid argument of a call; ``key`` names it (``"controls"``, ``"bound"``)."""


class SimulationError(ChainbeamError, RuntimeError):
    """A computation that failed: the beam folds, a singular constraint system, a non-finite
    value."""


class ConvergenceError(SimulationError):
    """An iteration that did not converge: RATTLE's Newton solve for the multipliers, the static
    equilibrium, or :func:`chainbeam.optimize` (``kind == "NotConverged"``; ``result`` then holds
    the :class:`chainbeam.OptimizeResult`)."""

    result: Any = None


class TrajectoryTooLargeError(ChainbeamError, MemoryError):
    """A trajectory that does not fit the library's memory budget (reduce ``time.steps``;
    ``key`` is ``"time.steps"`` when the run was refused before it started)."""


class ChainbeamWarning(UserWarning):
    """Base class of chainbeam's warnings: a result that a default may dominate."""


class StartUpWarning(ChainbeamWarning):
    """``fatigue`` counted the start of every record (``spin_up`` not given): the transient of
    a beam starting at rest under loads that ramp in, which can dominate the damage."""


__all__ = [
    "ChainbeamError",
    "SceneError",
    "InvalidArgumentError",
    "SimulationError",
    "ConvergenceError",
    "TrajectoryTooLargeError",
    "ChainbeamWarning",
    "StartUpWarning",
]
