"""chainbeam: a differentiable simulator of slender beams as a chain of rigid pendulums
(RATTLE, exact discrete adjoint, optimal control, MPC), from Python.

Quickstart::

    import chainbeam as cb
    scene = cb.Scene.from_file("examples/scenes/riser_5.toml")
    traj = cb.simulate(scene)                  # traj.t, traj.moment, traj.positions (N+1, n, 3)
    traj.wellhead_moment                       # M_w = M₀·l₁/2 [N m]; traj.to_pandas()
    c, g = cb.gradient(scene)                  # objective and exact adjoint gradient
    c, d = cb.gradient(scene, wrt=["loads.drag"])  # dJ/dD (every physical parameter)
    best = cb.optimize(scene)                  # best.controls, best.objective, best.converged
    drag = scene.replace({"loads.drag": 12.0}) # a changed copy (errors name the key)

Every call runs the Rust library's code (the command line's, bit for bit) with the GIL released:
two threads simulate at once. Ctrl-C raises ``KeyboardInterrupt`` promptly and stops the work
(within a batch of steps). ``progress=True`` draws a bar on ``fatigue``, ``mpc``, ``optimize``
and ``sweep`` (tqdm when installed), or pass a callable ``progress(done, total)``. Scenes and results
pickle, so they travel to process pools and clusters; :func:`sweep` runs parameter studies on any
executor (``ProcessPoolExecutor``, ``dask.distributed.Client``).

Fork safety: the calls that use threads (``optimize`` with ``starts`` > 1 or a structured method,
``mpc``) start a thread pool of their own per call instead of rayon's global pool, so a process
forked after such a call (``multiprocessing`` with the ``fork`` start method, a
``ProcessPoolExecutor`` on Linux) runs them normally (python/tests/test_fork.py).

The wellhead fatigue assessment (:func:`fatigue`: ``chainbeam fatigue``'s JSON as a dict) runs
plain, over a scatter diagram and with controllers, its cells optionally spread over an executor
(``fatigue(scene, scatter=..., controllers=..., executor=client)``), bit for bit the command
line's numbers; :func:`reduced_north_atlantic` is the published scatter diagram (IACS Rec. 34)
of the headline as a DataFrame to pass as ``scatter``. The controllers' settings default to the
scene's ``[mpc]`` table, as on the command line.

Design for fatigue (:func:`design`: ``chainbeam design``'s JSON as a dict): the exact
sensitivities of the wellhead's annual damage over a scatter diagram with respect to the
scene's ``[design]`` parameters, and the bounded design that maximises its life, the cells of
every evaluation optionally spread over an executor (``design(scene, scatter=...,
executor=client)``) with the same numbers bit for bit.
"""

from __future__ import annotations

from ._api import (
    MpcResult,
    OptimizeResult,
    Trajectory,
    gradient,
    mpc,
    optimize,
    simulate,
)
from ._chainbeam import Scene, __version__
from ._design import design
from ._fatigue import fatigue, reduced_north_atlantic
from ._fatigue_result import FatigueResult
from ._errors import (
    ChainbeamError,
    ChainbeamWarning,
    ConvergenceError,
    InvalidArgumentError,
    SceneError,
    SimulationError,
    StartUpWarning,
    TrajectoryTooLargeError,
)
from ._sweep import sweep, to_parquet

__all__ = [
    "Scene",
    "simulate",
    "gradient",
    "optimize",
    "mpc",
    "fatigue",
    "reduced_north_atlantic",
    "design",
    "sweep",
    "to_parquet",
    "Trajectory",
    "OptimizeResult",
    "MpcResult",
    "FatigueResult",
    "ChainbeamError",
    "SceneError",
    "InvalidArgumentError",
    "SimulationError",
    "ConvergenceError",
    "TrajectoryTooLargeError",
    "ChainbeamWarning",
    "StartUpWarning",
    "__version__",
]
