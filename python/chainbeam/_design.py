"""Design for fatigue (``chainbeam design``): the exact sensitivities of the wellhead's expected
annual damage over a scatter diagram with respect to the scene's ``[design]`` parameters, and
the bounded (projected) L-BFGS design that maximises its life, optionally with the cells spread over an
executor.

``design(scene, scatter=None, *, sensitivities=False, record=None, spin_up=None, executor=None,
progress=False, on_iterate=None, check=True)`` returns the command line's JSON as a dict:
``json.load`` of ``chainbeam design SCENE [--scatter FILE] [--sensitivities] [--record S]
[--spin-up S]``'s output equals it bit for bit, but for ``seconds`` (the wall time). Its fields
(docs/python.md "Design for fatigue"; ``chainbeam design --help``): ``sensitivities``
(``{name: dD_y/dp}`` [1/year per unit of p] at the scene's design, keyed by the parameter's
name: ``loads.tension``, ``beam.base_stiffness``, ...), ``relative_sensitivities``
(``{name: dlnL/dlnp}``), ``roles``, ``scene_design`` (``values``, ``damage_per_year``,
``life_years``), ``design`` (``{name: value}``, the optimised design; not with
``sensitivities=True``), ``damage_per_year``, ``life_years``, ``iterates`` (every iterate, the
start first: ``iteration``, ``design``, ``damage_per_year``, ``life_years``,
``gradient_norm``, ``simulations``, ``adjoint_sweeps``, ``forward_runs``), ``converged``,
``termination``, ``simulations`` (cell runs: ``adjoint_sweeps``, each a forward and a reverse
pass, plus ``forward_runs``, line-search trials that need the value alone), ``adjoint_sweeps``,
``forward_runs``, ``seconds``, ``record_s``, ``spin_up_s`` and ``cells`` (``hs``, ``tp``
[, ``direction``], ``probability``, ``damage``, ``duration_s`` at the reported design).

``scatter``: as :func:`chainbeam.fatigue`'s (a CSV path, a DataFrame, a sequence of mappings;
``None``: the scene's own sea, probability 1). ``record`` [s]: the seconds counted after the
spin-up in every cell (``--record``; ``None``: 10800, 3 hours); ``spin_up`` [s]: the start of
every record left out of the count (``--spin-up``; ``None``: 0 with a
:class:`StartUpWarning`, as ``fatigue``).

``executor``: anything with ``submit(fn, *args)`` (``ProcessPoolExecutor``,
``ThreadPoolExecutor``, a ``dask.distributed.Client``); every evaluation of the diagram (the
start's sensitivities and each of the optimiser's) sends each cell as one task (one adjoint
sweep), gathers the cells in the diagram's order and combines them as the command line does,
so the damage, its gradient, every iterate and the design do not depend on where the cells ran,
bit for bit. Without an executor the cells run on this process's threads, as on the command
line.

``progress``: ``True`` for a bar over the iterations (tqdm, else lines on standard error) that
shows each iterate's damage per year, life, gradient norm and design; a callable is called as
``progress(iteration, max_iterations)``. ``on_iterate``: a callable given each iterate as a dict
(the fields of ``iterates``) as it is accepted. Both are called from the thread that runs the
optimiser (with the GIL). ``check``: an optimisation that did not converge raises
:class:`ConvergenceError` (``kind == "NotConverged"``, ``.result`` the dict), as the command
line exits with status 3; ``check=False`` returns the dict with ``converged`` False.
"""

from __future__ import annotations

import json
import math
import warnings
from collections.abc import Callable, Sequence
from typing import Any, Optional

from . import _chainbeam
from ._chainbeam import Scene
from ._errors import ConvergenceError, InvalidArgumentError, StartUpWarning
from ._fatigue import Cell, _cells
from ._progress import ProgressArg, Reporter
from ._sweep import ExecutorLike, _gather

CellResult = tuple[float, float, float, list[float]]


def _number(value: Any, name: str, ok: Callable[[float], bool], what: str) -> Optional[float]:
    """``value`` as a float (None: not given); anything else raises ``InvalidArgumentError``
    naming the argument ``name``."""
    if value is None:
        return None
    try:
        v = float(value)
    except (TypeError, ValueError, OverflowError):
        v = math.nan
    if isinstance(value, bool) or not ok(v):
        raise InvalidArgumentError(f"{name}: expected {what}, got {value!r}", "InvalidArgument",
                                   name, None)
    return v


def _design_cell_task(
    scene: Scene, cells: Optional[list[Cell]], index: int, names: list[str],
    values: list[float], gradient: bool, record: Optional[float], spin_up: float
) -> CellResult:
    """Cell ``index`` at the design ``names = values`` (module level: it pickles)."""
    return _chainbeam._design_cell(scene, cells, index, names, values, gradient, record,
                                   spin_up)


def _iterate_line(it: dict[str, Any]) -> str:
    """An iterate as the command line's progress line."""
    life = it["life_years"]
    norm = it["gradient_norm"]
    values = "  ".join(f"{k}={v:.6e}" for k, v in it["design"].items())
    return (f"iter {it['iteration']:>3}  damage/yr {it['damage_per_year']:.6e}  life "
            f"{math.inf if life is None else life:.6e} y  |g| "
            f"{math.nan if norm is None else norm:.3e}  sims {it['simulations']}  {values}")


def design(
    scene: Scene,
    scatter: Any = None,
    *,
    sensitivities: bool = False,
    record: float | None = None,
    spin_up: float | None = None,
    executor: ExecutorLike | None = None,
    progress: ProgressArg = False,
    on_iterate: Callable[[dict[str, Any]], Any] | None = None,
    check: bool = True,
) -> dict[str, Any]:
    """The design that maximises the wellhead's fatigue life over a scatter diagram, or the
    sensitivities of its annual damage at the scene's design (``chainbeam design``'s JSON as a
    dict; module docs).

    Raises:
        SceneError (no ``[design]`` table or design choice: key ``design``; no ``[fatigue]``:
        key ``fatigue``), InvalidArgumentError (``scatter``, ``record``, ``spin_up``,
        ``executor``, ``progress``, ``on_iterate``, named in ``.key``), SimulationError,
        ConvergenceError (``check`` and the optimiser did not converge; ``.result``).
    """
    if not isinstance(scene, Scene):
        raise InvalidArgumentError(f"scene: expected a chainbeam.Scene, got "
                                   f"{type(scene).__name__}", "InvalidArgument", "scene", None)
    record_s = _number(record, "record", lambda v: math.isfinite(v) and v > 0.0,
                       "a positive number of seconds")
    spin = _number(spin_up, "spin_up", lambda v: math.isfinite(v) and v >= 0.0,
                   "a non-negative number of seconds")
    if spin is None:
        warnings.warn(
            "design: spin_up not given, so the start of every record is counted: the beam "
            "starts straight and at rest and its loads ramp in, a transient that can dominate "
            "the damage of a record. Give spin_up=0.0 to count the start on purpose.",
            StartUpWarning,
            stacklevel=2,
        )
        spin = 0.0
    if executor is not None and not callable(getattr(executor, "submit", None)):
        raise InvalidArgumentError(
            f"executor: expected an object with submit(fn, *args), got {type(executor).__name__}",
            "InvalidArgument", "executor", None)
    if on_iterate is not None and not callable(on_iterate):
        raise InvalidArgumentError(
            f"on_iterate: expected a callable on_iterate(dict), got {type(on_iterate).__name__}",
            "InvalidArgument", "on_iterate", None)
    cells = None if scatter is None else _cells(scatter)
    runner = None
    if executor is not None:
        def runner(names: list[str], values: list[float], gradient: bool) -> list[CellResult]:
            n = 1 if cells is None else len(cells)
            futures = [executor.submit(_design_cell_task, scene, cells, i, names, values,
                                       gradient, record_s, spin) for i in range(n)]
            return _gather(futures)

    max_iterations = _max_iterations(scene)
    with Reporter(progress, "design", "iteration") as r:
        hook = None
        if r.callback is not None or on_iterate is not None:
            def hook(it: dict[str, Any]) -> None:
                if on_iterate is not None:
                    on_iterate(it)
                if r.callback is not None:
                    r.note(_iterate_line(it))
                    r.callback(it["iteration"], max_iterations)

        text = _chainbeam._design(scene, cells, bool(sensitivities), record_s, spin, runner,
                                  hook)
    out: dict[str, Any] = json.loads(text)
    if check and out.get("converged") is False:
        e = ConvergenceError(
            f"design: the optimiser did not converge: {out.get('termination')} (the result is "
            "in .result)", "NotConverged", None, None)
        e.result = out
        raise e
    return out


def _max_iterations(scene: Scene) -> int:
    """The ``[design]`` table's ``max_iterations`` (its default, 30, without one)."""
    try:
        value = scene["design.max_iterations"]
    except Exception:
        return 30
    return int(value) if isinstance(value, (int, float)) else 30


__all__ = ["design"]
