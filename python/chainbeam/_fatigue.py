"""The wellhead fatigue assessment (``chainbeam fatigue``): plain, over a scatter diagram
(``--scatter``) and with controllers (``--controller``), optionally spread over an executor.

``fatigue(scene, scatter=None, controllers=None, executor=None, *, interval=None, horizon=None,
iterations=None, bound=None, effort=None, plan_pendulums=None, plan_step=None, pd_training=None,
mpc_objective=None, spin_up=None, progress=False, duration=None, record=None, seeds=1)`` returns the command line's
JSON as a :class:`FatigueResult` (a dict with the same fields, and tables: ``to_pandas()``,
``cells_frame()``, ``summary_frame()``, ``cycles_frame()``)
(``json.load`` of ``chainbeam fatigue``'s output equals it, bit for bit, the keyword arguments
being the flags of the same names). The controllers' settings take the command line's
precedence: an argument given (not ``None``) overrides the scene's ``[mpc]`` table
(docs/scene-format.md), and a key given in neither takes the default (``interval`` 0.1 s,
``horizon`` 3 s, ``iterations`` 1, ``bound`` 5 N, ``effort`` 0.01, ``mpc_objective`` "power",
the others off); a bad value from the table raises ``SceneError`` with ``.key`` ``mpc.KEY``, a
bad argument ``InvalidArgumentError`` with ``.key`` the argument:

- neither ``scatter`` nor ``controllers``: ``cycles`` ([[stress_range_MPa, mean_MPa, count], …]),
  ``damage``, ``duration_s``, ``damage_per_year``, ``life_years`` (None: no damage);
- ``scatter`` alone: ``damage_per_year``, ``life_years`` and ``cells`` (each ``hs``, ``tp``
  [, ``direction``], ``probability``, ``damage_per_year`` = the cell's weighted contribution,
  ``damage``, ``duration_s``);
- ``controllers``: ``controllers`` (keyed by name: ``damage_per_year``, ``life_years``,
  ``cells``), ``life_extension`` (keyed by name: its life over the life without control) and
  ``settings`` (``interval``, ``horizon``, ``iterations``, ``bound``, ``effort``, ``spin_up``,
  ``mpc_objective``, ``record``, ``seeds``, ``observe``: the values the run used, from the arguments or the
  scene's ``[mpc]``).

A study (``scatter``, ``controllers`` or ``seeds`` > 1) runs each cell for ``spin_up`` +
``record`` seconds, ``record`` by default 10800 s (3 hours, the practice for a sea state; the
command line's ``--record``): give a short ``record`` to explore quickly. ``seeds=K`` runs K
seas per cell (the scene's ``[loads.waves]`` seed s, s+1, …, s+K−1, the same K in every cell):
each cell's ``damage`` is the mean over its seeds and, with K > 1, the cell also has
``seed_damages``, ``damage_std`` (sample, K − 1), ``damage_min``, ``damage_max``, and the totals
``life_years_seeds``, ``life_years_min``, ``life_years_max``. A scene with
``[[fatigue.hotspot]]`` entries gets ``hotspots`` (each ``name``, ``elevation``,
``damage_per_year``, ``life_years``) and ``critical`` (the shortest-lived one's name), with or
without an executor. A closed loop's cell with ``none`` in the study has
``damage_ratio_to_none`` (above 1: worse than no control). ``duration`` [s] sets the length of
the plain run (neither ``scatter``, ``controllers`` nor ``seeds``).

``reduced_north_atlantic()``: the published scatter diagram of the headline as a DataFrame
(``hs``, ``tp``, ``probability``), ready for ``scatter=``.

``scatter``: a path to the command line's CSV (header ``hs,tp,probability[,direction]``), a
pandas DataFrame with those columns, or a sequence of mappings with those keys. Every cell sets
the scene's ``[loads.waves]`` hs, tp (direction) and keeps its seed. ``controllers``: a comma
list or a sequence of ``none``, ``constant``, ``pd``, ``mpc`` (``none`` is always run).

``executor``: anything with ``submit(fn, *args)`` (``ProcessPoolExecutor``, a
``dask.distributed.Client`` or its ``get_executor()``); each scatter cell (all its seeds and
controllers) is one task, and the cells are combined as the command line combines them, so the result does
not depend on the executor or the number of workers, bit for bit. Without ``scatter`` the whole
assessment is one task. A Ctrl-C (or any exception) while waiting cancels the tasks not yet
started.

``spin_up`` [s]: the start of every record left out of the count. Every run starts from the
scene's ``[time] initial`` (by default the straight beam at rest, its loads ramping in; with
``"static"`` the static equilibrium of its steady loads, the sea still starting at t = 0), a
transient that can dominate the damage of a short record; not giving ``spin_up`` counts it (``spin_up=0``, the command line's default) and
warns (:class:`StartUpWarning`); give ``spin_up=0.0`` to count the start without the warning.

``progress``: ``True`` for a bar (tqdm, else lines on standard error) or a callable
``progress(done, total)``, over the (cell, controller) runs (with an executor: over the tasks).
"""

from __future__ import annotations

import math
import os
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Optional

import pandas as pd

from . import _chainbeam
from ._api import _with_duration
from ._chainbeam import Scene
from ._errors import InvalidArgumentError, StartUpWarning
from ._fatigue_result import FatigueResult
from ._progress import ProgressArg, Reporter
from ._sweep import ExecutorLike, _gather

Cell = tuple[float, float, float, Optional[float]]

_COLUMNS = ("hs", "tp", "probability", "direction")


def _bad(message: str) -> InvalidArgumentError:
    return InvalidArgumentError(message, "InvalidArgument", "scatter", None)


def _number(value: Any, where: str, what: str, ok: Any) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise _bad(f"scatter: {where}: `{value}` is not {what}") from None
    if not ok(v):
        raise _bad(f"scatter: {where}: `{value}` is not {what}")
    return v


def _cell(row: Mapping[str, Any], where: str) -> Cell:
    unknown = sorted(set(row) - set(_COLUMNS))
    if unknown:
        raise _bad(f"scatter: {where}: unknown column {unknown[0]!r} (hs, tp, probability"
                   "[, direction])")
    for key in _COLUMNS[:3]:
        if key not in row:
            raise _bad(f"scatter: {where}: no `{key}` (hs, tp, probability[, direction])")
    positive = lambda v: math.isfinite(v) and v > 0.0  # noqa: E731
    direction = row.get("direction")
    return (
        _number(row["hs"], f"{where}, `hs`", "a positive number (H_s, m)", positive),
        _number(row["tp"], f"{where}, `tp`", "a positive number (T_p, s)", positive),
        _number(row["probability"], f"{where}, `probability`", "a probability in [0, 1]",
                lambda v: 0.0 <= v <= 1.0),
        None if direction is None else _number(
            direction, f"{where}, `direction`", "a finite angle (degrees)", math.isfinite),
    )


def _read_csv(path: Path) -> list[Cell]:
    """The command line's scatter CSV, read by the library's reader (the bounded reader of every
    input file: ``/dev/zero``, a huge file, a directory, a missing or non-UTF-8 file raise
    ``InvalidArgumentError`` naming ``scatter`` and the file, never read for ever)."""
    cells: list[Cell] = _chainbeam._read_scatter(os.fspath(path))
    return cells


def _cells(scatter: Any) -> list[Cell]:
    if isinstance(scatter, (str, os.PathLike)):
        return _read_csv(Path(scatter))
    if hasattr(scatter, "to_dict") and hasattr(scatter, "columns"):  # a pandas DataFrame
        records = scatter.to_dict("records")
        return [_cell({k: v for k, v in r.items() if not (k == "direction" and v is None)},
                      f"row {i}") for i, r in enumerate(records)]
    if isinstance(scatter, Sequence):
        return [_cell(r, f"cell {i}") for i, r in enumerate(scatter)]
    raise _bad("scatter: expected a CSV path, a DataFrame or a sequence of mappings with "
               f"hs, tp, probability[, direction], got {type(scatter).__name__}")


def _controllers(controllers: Any) -> list[str] | None:
    """The controllers' names, lower-case (the one spelling: ``"MPC"`` is ``"mpc"``)."""
    if controllers is None:
        return None
    if isinstance(controllers, str):
        return [controllers.lower()]
    return [str(c).lower() for c in controllers]


def _fatigue_task(
    scene: Scene, cells: list[Cell] | None, names: list[str] | None, settings: dict[str, Any]
) -> dict[str, Any]:
    """The whole assessment in one task (module level: it pickles)."""
    return _chainbeam._fatigue(scene, cells, names, settings)


def _cell_task(
    scene: Scene, cells: list[Cell], index: int, names: list[str] | None,
    settings: dict[str, Any]
) -> list[Any]:
    """Every seed and controller on cell ``index`` of ``cells`` (module level: it pickles)."""
    return _chainbeam._fatigue_cell(scene, cells, index, names, settings)


def _optional(value: Any, kind: Any, name: str) -> Any:
    """``value`` converted by ``kind`` (None: not given); a value that does not convert raises
    ``InvalidArgumentError`` naming the argument ``name``."""
    if value is None:
        return None
    try:
        return kind(value)
    except (TypeError, ValueError, OverflowError):
        what = {int: "an integer", float: "a number"}.get(kind, "a string")
        raise InvalidArgumentError(f"{name}: expected {what}, got {value!r}", "InvalidArgument",
                                   name, None) from None


def reduced_north_atlantic() -> pd.DataFrame:
    """The North Atlantic wave scatter diagram of IACS Recommendation No. 34 ("Standard Wave
    Data", as printed in Korean Register, Guidance RA-03-E (2025), Pt 3, Annex 3-2, Table 3;
    derived from BMT's Global Wave Statistics), reduced to 20 cells: 5 x 5 groups of adjacent
    classes, H_s the group's RMS, T_p = (5*pi/4)^(1/4) times its mean T_z (the table's
    Pierson-Moskowitz sea: run it with ``gamma = 1``), the groups below 0.1 % of the time dropped
    and the rest renormalised to 1 (``chainbeam::fatigue::scatter::reduced_north_atlantic``,
    src/fatigue/scatter/north_atlantic.rs; examples/scatter/README.md).

    Returns:
        A DataFrame with the columns ``hs`` [m], ``tp`` [s] and ``probability``, one row per
        cell, H_s slowest: the rows of examples/scatter/north_atlantic_iacs34.csv, the same
        doubles. Pass it as ``fatigue(scene, scatter=...)``.
    """
    return pd.DataFrame(_chainbeam._reduced_north_atlantic(), columns=["hs", "tp", "probability"])


def fatigue(
    scene: Scene,
    scatter: Any = None,
    controllers: str | Sequence[str] | None = None,
    executor: ExecutorLike | None = None,
    *,
    interval: float | None = None,
    horizon: float | None = None,
    iterations: int | None = None,
    bound: float | None = None,
    effort: float | None = None,
    plan_pendulums: int | None = None,
    plan_step: float | None = None,
    pd_training: float | None = None,
    mpc_objective: str | None = None,
    forecast: str | None = None,
    forecast_error: float | None = None,
    observe: str | None = None,
    hotspot: str | None = None,
    moment_about: str | None = None,
    spin_up: float | None = None,
    progress: ProgressArg = False,
    duration: float | None = None,
    record: float | None = None,
    seeds: int = 1,
) -> FatigueResult:
    """The wellhead's fatigue damage and life (``chainbeam fatigue``'s JSON as a dict; module
    docs). ``interval``, ``horizon``, ``iterations``, ``bound``, ``effort``, ``plan_pendulums``,
    ``plan_step``, ``pd_training``, ``mpc_objective`` (``"power"`` or ``"sum"``), ``forecast``
    (``"perfect"``, ``"none"`` or ``"noisy"``: what MPC's plan knows of the sea ahead),
    ``forecast_error`` (the noisy forecast's error growth e: each wave component's relative
    amplitude and phase errors have the standard deviation min(e·τ/T_p, 1/√2) at lead time τ;
    ``--forecast-error``), ``observe``
    (``"state"`` or ``"sensors"``: what MPC's plan starts from, the plant's state or a Kalman
    filter's estimate from the riser's sensors), ``hotspot`` (the ``name`` of a
    ``[[fatigue.hotspot]]``: every controller acts on its moment and the controllers' damages and
    lives are its, docs/cli.md "The moment the controllers act on"), ``moment_about``
    (``"zero"`` or ``"mean"``: MPC plans on the hot spot's moment about zero, h·Σ|M|^m, or about
    the plan's own mean, h·Σ|M − M̄|^m, and the PD law feeds back M, or M − M̄ with M̄ the
    moment's running mean; ``"mean"`` needs ``hotspot``): the closed-loop settings of the ``constant``, ``pd`` and ``mpc`` controllers (the flags of the
    same names; ``None``: the scene's ``[mpc]`` key, else the default); ``spin_up`` [s]: the
    start of every record left out of the count (``--spin-up``; not given: 0 with a
    :class:`StartUpWarning`); ``progress``: a bar or a callback over the runs (module docs);
    ``duration`` [s]: the plain run's length instead of the scene's ``time.steps``;
    ``record`` [s]: the seconds counted after the spin-up in every run of a study (``--record``;
    not given: 10800, 3 hours); ``seeds``: seas per cell (``--seeds``; module docs).

    Raises:
        SceneError (no ``[fatigue]`` table, key ``fatigue``; a setting of the ``[mpc]`` table
        that does not fit the run, key ``mpc.KEY``), InvalidArgumentError (``scatter``,
        ``controllers`` or a setting, named in ``.key``), SimulationError, ConvergenceError.
    """
    settings = {
        "interval": _optional(interval, float, "interval"),
        "horizon": _optional(horizon, float, "horizon"),
        "iterations": _optional(iterations, int, "iterations"),
        "bound": _optional(bound, float, "bound"),
        "effort": _optional(effort, float, "effort"),
        "plan_pendulums": _optional(plan_pendulums, int, "plan_pendulums"),
        "plan_step": _optional(plan_step, float, "plan_step"),
        "pd_training": _optional(pd_training, float, "pd_training"),
        "mpc_objective": _optional(mpc_objective, str, "mpc_objective"),
        "forecast": _optional(forecast, str, "forecast"),
        "forecast_error": _optional(forecast_error, float, "forecast_error"),
        "observe": _optional(observe, str, "observe"),
        "hotspot": _optional(hotspot, str, "hotspot"),
        "moment_about": _optional(moment_about, str, "moment_about"),
        "spin_up": 0.0 if spin_up is None else _optional(spin_up, float, "spin_up"),
        "record": _optional(record, float, "record"),
        "seeds": _optional(seeds, int, "seeds"),
    }
    if spin_up is None:
        warnings.warn(
            "fatigue: spin_up not given, so the start of every record is counted: the beam "
            "starts straight and at rest and its loads ramp in, a transient that can dominate "
            "the damage of a record (the headline leaves out 60 s: spin_up=60.0). Give "
            "spin_up=0.0 to count the start on purpose.",
            StartUpWarning,
            stacklevel=2,
        )
    scene = _with_duration(scene, duration)
    cells = None if scatter is None else _cells(scatter)
    names = _controllers(controllers)
    with Reporter(progress, "fatigue", "run") as r:
        if executor is None:
            return FatigueResult(_chainbeam._fatigue(scene, cells, names, settings, r.callback))
        if cells is None:
            futures = [executor.submit(_fatigue_task, scene, None, names, settings)]
            (out,) = _gather(futures, r.callback)
            return FatigueResult(out)
        futures = [executor.submit(_cell_task, scene, cells, i, names, settings)
                   for i in range(len(cells))]
        runs = _gather(futures, r.callback)
    return FatigueResult(_chainbeam._fatigue_combine(scene, cells, names, settings, runs))


__all__ = ["fatigue", "reduced_north_atlantic", "FatigueResult"]
