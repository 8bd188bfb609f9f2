"""simulate, gradient, optimize and mpc: thin wrappers around the Rust library.

Each call runs the same library code as the command line (``chainbeam simulate``, ``gradient``,
``optimize``, ``mpc``) on the same floats, with the GIL released; Ctrl-C raises
``KeyboardInterrupt`` within 50 ms (the abandoned computation finishes on its worker thread in the
background and is discarded). Results are plain dataclasses of numpy arrays: picklable.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _chainbeam
from ._chainbeam import Scene
from ._errors import ConvergenceError, InvalidArgumentError

Array = NDArray[np.float64]


def _split_controls(controls: ArrayLike | None) -> tuple[Array | None, Array | None]:
    """(u_z, u_x) of ``controls``: ``None``; one value or N + 1 values (shape (m,)); or pairs
    [u_x, u_z] of a 2-axis control (shape (m, 2))."""
    if controls is None:
        return None, None
    a = np.asarray(controls, dtype=np.float64)
    if a.ndim == 0:
        a = a.reshape(1)
    if a.ndim == 1:
        return np.ascontiguousarray(a), None
    if a.ndim == 2 and a.shape[1] == 2:
        return np.ascontiguousarray(a[:, 1]), np.ascontiguousarray(a[:, 0])
    raise InvalidArgumentError(
        f"controls: expected one value, N + 1 values u_0..u_N (shape (m,)) or pairs "
        f"[u_x, u_z] (shape (m, 2)), got an array of shape {a.shape}",
        "InvalidArgument",
        "controls",
    )


@dataclass(frozen=True)
class Trajectory:
    """A simulated trajectory, k = 0..N (the columns of ``chainbeam simulate``'s CSV).

    Attributes:
        t: times t_k = k h [s], shape (N + 1,).
        energy: total energy H(q_k, p_k; t_k, u_k) [J].
        moment: base bending moment M₀(t_k) = 2 k₁ z₁ / l₁² [Nm] (thesis eq. 3.1.3).
        positions: node positions [m], shape (N + 1, n, 3), columns x, y, z (x = 0 for a planar
            scene; the beam lies along +y).
        control: the control force u_k [N] (its z component for a 2-axis control; 0 without
            a control).
        moment_x: the x component M₀ₓ(t_k) of the base moment (spatial scenes only, else None).
        control_x: the x component u_x,k of the control (spatial scenes only, else None).
        eta: the surface elevation η(t_k) [m] at x = z = 0 of a scene with ``[loads.waves]``
            (the command line's ``eta`` column), else None.
    """

    t: Array
    energy: Array
    moment: Array
    positions: Array
    control: Array
    moment_x: Array | None = None
    control_x: Array | None = None
    eta: Array | None = None

    @property
    def is_spatial(self) -> bool:
        """Whether the spatial model ran (``moment_x`` and ``control_x`` are then arrays)."""
        return self.moment_x is not None


def simulate(scene: Scene, controls: ArrayLike | None = None) -> Trajectory:
    """Simulates ``scene`` from the straight beam at rest with RATTLE (h = ``time.step``,
    N = ``time.steps``) under its own ``[control]`` or ``controls``.

    ``controls``: one value (a constant force), N + 1 values u_0..u_N, or an (m, 2) array of
    pairs [u_x, u_z] (a 2-axis control), acting at ``control.node`` (default: the tip) — what
    ``chainbeam simulate --controls`` takes. Bit for bit the command line's numbers.

    Raises:
        SceneError, InvalidArgumentError, SimulationError, ConvergenceError.
    """
    z, x = _split_controls(controls)
    d = _chainbeam.simulate(scene, z, x)
    return Trajectory(**d)


def gradient(
    scene: Scene, controls: ArrayLike | None = None, *, effort: float = 0.0
) -> tuple[float, Array]:
    """The objective J(θ) of the scene's ``[objective]`` (default ``"final"``: M₀(t_N)², thesis
    eq. 3.3.2; ``"sum"``: Σ M₀(t_k)², eq. 3.3.4; plus ρ h Σ u_k² with ``effort`` ρ) and its
    exact gradient by the discrete adjoint, at the scene's ``control.values`` or ``controls``.

    The gradient has θ's layout: one entry per value, or shape (m, 2) of [dJ/du_x, dJ/du_z]
    for a 2-axis control. Bit for bit ``chainbeam gradient``'s JSON.
    """
    z, x = _split_controls(controls)
    c, g, two_axis = _chainbeam.gradient(scene, z, x, effort)
    if two_axis:
        m = g.shape[0] // 2
        g = np.stack([g[:m], g[m:]], axis=1)
    return c, g


@dataclass(frozen=True)
class OptimizeResult:
    """The result of :func:`optimize` (the JSON of ``chainbeam optimize``).

    Attributes:
        controls: the optimal θ, laid out as ``control.values`` (shape (m, 2) for a 2-axis
            control).
        forces: the forces u_0..u_N of θ (z components for a 2-axis control).
        objective: J at ``controls``.
        converged: whether a convergence test was met.
        termination: how the run ended, in words.
        iterations, gradient_norm, projected_gradient_norm, initial_gradient_norm,
        initial_objective, active_bounds, method, starts, minima_found, failed_starts: as in
        the command line's JSON.
    """

    controls: Array
    forces: Array
    objective: float
    converged: bool
    termination: str
    iterations: int
    gradient_norm: float
    projected_gradient_norm: float
    initial_gradient_norm: float
    initial_objective: float
    active_bounds: list[int]
    method: str
    starts: int
    minima_found: int
    failed_starts: int


def optimize(
    scene: Scene,
    method: Literal["auto", "lbfgs", "trust-region", "riccati", "condensed"] = "auto",
    bound: float | None = None,
    starts: int = 1,
    *,
    lower: float | None = None,
    upper: float | None = None,
    seed: int = 0,
    max_iters: int | None = None,
    gtol: float | None = None,
    effort: float = 0.0,
    controls: ArrayLike | None = None,
    check: bool = True,
) -> OptimizeResult:
    """Minimises the scene's objective over its controls from ``control.values`` (or
    ``controls``): ``chainbeam optimize`` with the same flags and defaults.

    ``method``: ``"auto"`` (default: the command line's ``--method auto``, a choice by the
    problem's shape, the structured solvers behind an L-BFGS fallback; ``result.method`` says
    which ran), ``"lbfgs"``, ``"trust-region"``, ``"riccati"`` or ``"condensed"`` (planar
    scenes). ``bound``: |u| ≤ bound [N]; or a box ``lower``/``upper``. ``starts`` > 1:
    the scene's start plus ``starts`` − 1 Latin-hypercube starts in [−600, 600] N drawn with
    ``seed``; the best result (results do not depend on the number of threads).

    A run that did not converge raises :class:`ConvergenceError` (``kind == "NotConverged"``,
    the message says why, ``.result`` holds the result), as the command line exits with status
    3; with ``check=False`` the result is returned and ``result.converged`` is ``False``.
    """
    z, x = _split_controls(controls)
    d = _chainbeam.optimize(
        scene, method, bound, lower, upper, starts, seed, max_iters, gtol, effort, z, x
    )
    theta = d.pop("theta")
    if d.pop("two_axis"):
        m = theta.shape[0] // 2
        theta = np.stack([theta[:m], theta[m:]], axis=1)
    r = OptimizeResult(controls=theta, **d)
    if check and not r.converged:
        rel = (
            f"relative gradient ‖∇c‖/‖∇c(start)‖ = {r.projected_gradient_norm / r.initial_gradient_norm:.3e}"
            if r.initial_gradient_norm > 0
            else "the gradient was zero at the start"
        )
        its = r.iterations
        e = ConvergenceError(
            f"the optimiser did not converge: {r.termination}; after {its} "
            f"iteration{'' if its == 1 else 's'}, {rel} (optimize(..., check=False) returns "
            f"the result)",
            "NotConverged",
        )
        e.result = r
        raise e
    return r


@dataclass(frozen=True)
class MpcResult:
    """The closed loop of :func:`mpc` (``chainbeam mpc``'s CSV and JSON summary).

    Attributes:
        t, moment, control, tip: t_k [s], M₀(t_k) [Nm], the applied force u_k [N] and the tip
            displacement z_n(t_k) [m] under MPC, k = 0..N.
        summary: c_sum, max_abs_moment, max_abs_control, effort, decisions, re-plan times,
            real-time factors (``chainbeam mpc --summary``'s per-controller keys).
        baselines: with ``baselines=True`` the summaries of no control, the best constant force
            and the tuned PD law; ``moment_none``, ``moment_constant``, ``control_constant``,
            ``moment_pd``, ``control_pd`` their arrays and ``pd_gains`` [bias, K_p, K_d].
    """

    t: Array
    moment: Array
    control: Array
    tip: Array
    summary: dict[str, Any]
    baselines: list[dict[str, Any]] = field(default_factory=list)
    moment_none: Array | None = None
    moment_constant: Array | None = None
    control_constant: Array | None = None
    moment_pd: Array | None = None
    control_pd: Array | None = None
    pd_gains: list[float] | None = None


def mpc(
    scene: Scene,
    *,
    model: Scene | None = None,
    horizon: float | None = None,
    interval: float | None = None,
    iterations: int | None = None,
    solver: Literal["auto", "condensed", "riccati"] = "auto",
    first_iterations: int = 50,
    bound: float | None = None,
    effort: float | None = None,
    rate_penalty: float = 0.0,
    baselines: bool = False,
    plan_pendulums: int | None = None,
    plan_step: float | None = None,
) -> MpcResult:
    """Receding-horizon control of ``scene`` in closed loop: ``chainbeam mpc`` with the same
    flags and defaults (a plan over ``horizon`` s every ``interval`` s on ``model``, default the
    scene itself; the plan's first force applied at ``control.node``), planar scenes.
    ``baselines=True`` also runs no control, the best constant force and a tuned PD law.
    ``horizon``, ``interval``, ``iterations``, ``bound``, ``effort``, ``plan_pendulums``,
    ``plan_step``: ``None`` takes the scene's ``[mpc]`` key, else the command line's default
    (3 s, 0.1 s, 1, 5 N, 0.01, off, off); the table's ``objective`` and the model's
    ``[objective]`` set what the plans minimise, as on the command line."""
    d = _chainbeam.mpc(
        scene,
        model,
        horizon,
        interval,
        iterations,
        solver,
        first_iterations,
        bound,
        effort,
        rate_penalty,
        baselines,
        plan_pendulums,
        plan_step,
    )
    return MpcResult(**d)
