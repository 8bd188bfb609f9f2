"""The wellhead fatigue assessment (``chainbeam fatigue``): plain, over a scatter diagram
(``--scatter``) and with controllers (``--controller``), optionally spread over an executor.

``fatigue(scene, scatter=None, controllers=None, executor=None, *, interval=0.1, horizon=3.0,
iterations=1, bound=5.0, effort=0.01)`` returns the command line's JSON as a dict with the same
fields (``json.load`` of ``chainbeam fatigue``'s output equals it, bit for bit, for a scene
without an ``[mpc]`` table and the command line without ``--spin-up``/``--mpc-objective``: the
package runs the library's defaults for those, no spin-up and MPC on the fatigue proxy, and
reports them as ``settings["spin_up"]`` and ``settings["mpc_objective"]``):

- neither ``scatter`` nor ``controllers``: ``cycles`` ([[stress_range_MPa, mean_MPa, count], …]),
  ``damage``, ``duration_s``, ``damage_per_year``, ``life_years`` (None: no damage);
- ``scatter`` alone: ``damage_per_year``, ``life_years`` and ``cells`` (each ``hs``, ``tp``
  [, ``direction``], ``probability``, ``damage_per_year`` = the cell's weighted contribution,
  ``damage``, ``duration_s``);
- ``controllers``: ``controllers`` (keyed by name: ``damage_per_year``, ``life_years``,
  ``cells``), ``life_extension`` (keyed by name: its life over the life without control) and
  ``settings``.

``scatter``: a path to the command line's CSV (header ``hs,tp,probability[,direction]``), a
pandas DataFrame with those columns, or a sequence of mappings with those keys. Every cell sets
the scene's ``[loads.waves]`` hs, tp (direction) and keeps its seed. ``controllers``: a comma
list or a sequence of ``none``, ``constant``, ``pd``, ``mpc`` (``none`` is always run).

``executor``: anything with ``submit(fn, *args)`` (``ProcessPoolExecutor``, a
``dask.distributed.Client`` or its ``get_executor()``); each scatter cell (all its controllers)
is one task, and the cells are combined as the command line combines them, so the result does
not depend on the executor or the number of workers, bit for bit. Without ``scatter`` the whole
assessment is one task.
"""

from __future__ import annotations

import csv
import io
import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Optional

from . import _chainbeam
from ._chainbeam import Scene
from ._errors import InvalidArgumentError
from ._sweep import ExecutorLike

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
    """The command line's scatter CSV: a header, # comments, fields trimmed."""
    text = path.read_text()
    lines = [ln for ln in text.splitlines() if not ln.lstrip().startswith("#")]
    rows = list(csv.reader(io.StringIO("\n".join(lines))))
    rows = [[f.strip() for f in r] for r in rows if r and any(f.strip() for f in r)]
    if not rows:
        raise _bad(f"scatter: {path}: no header")
    header = rows[0]
    cells = [_cell(dict(zip(header, r)), f"{path}, row {i}") for i, r in enumerate(rows[1:], 1)]
    if not cells:
        raise _bad(f"scatter: {path}: no cells (rows after the header)")
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
    if controllers is None:
        return None
    if isinstance(controllers, str):
        return [controllers]
    return [str(c) for c in controllers]


def _fatigue_task(
    scene: Scene, cells: list[Cell] | None, names: list[str] | None, settings: dict[str, Any]
) -> dict[str, Any]:
    """The whole assessment in one task (module level: it pickles)."""
    return _chainbeam._fatigue(scene, cells, names, settings)


def _cell_task(
    scene: Scene, cell: Cell, index: int, names: list[str] | None, settings: dict[str, Any]
) -> list[Any]:
    """Every controller on one cell (module level: it pickles)."""
    return _chainbeam._fatigue_cell(scene, cell, index, names, settings)


def fatigue(
    scene: Scene,
    scatter: Any = None,
    controllers: str | Sequence[str] | None = None,
    executor: ExecutorLike | None = None,
    *,
    interval: float = 0.1,
    horizon: float = 3.0,
    iterations: int = 1,
    bound: float = 5.0,
    effort: float = 0.01,
) -> dict[str, Any]:
    """The wellhead's fatigue damage and life (``chainbeam fatigue``'s JSON as a dict; module
    docs). ``interval``, ``horizon``, ``iterations``, ``bound``, ``effort``: the closed-loop
    settings of the ``constant``, ``pd`` and ``mpc`` controllers (the flags of the same names).

    Raises:
        SceneError (no ``[fatigue]`` table, key ``fatigue``), InvalidArgumentError (``scatter``,
        ``controllers`` or a setting, named in ``.key``), SimulationError, ConvergenceError.
    """
    settings = {"interval": float(interval), "horizon": float(horizon),
                "iterations": int(iterations), "bound": float(bound), "effort": float(effort)}
    cells = None if scatter is None else _cells(scatter)
    names = _controllers(controllers)
    if executor is None:
        return _chainbeam._fatigue(scene, cells, names, settings)
    if cells is None:
        out: dict[str, Any] = executor.submit(_fatigue_task, scene, None, names, settings).result()
        return out
    futures = [executor.submit(_cell_task, scene, c, i, names, settings)
               for i, c in enumerate(cells)]
    runs = [f.result() for f in futures]
    return _chainbeam._fatigue_combine(scene, cells, names, settings, runs)


__all__ = ["fatigue"]
