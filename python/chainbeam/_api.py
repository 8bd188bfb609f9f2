"""simulate, gradient, optimize and mpc: thin wrappers around the Rust library.

Each call runs the same library code as the command line (``chainbeam simulate``, ``gradient``,
``optimize``, ``mpc``) on the same floats, with the GIL released; Ctrl-C raises
``KeyboardInterrupt`` within 50 ms and stops the computation within a batch of steps (it is
cancelled, not left running in the background). Results are plain dataclasses of numpy arrays:
picklable, with ``to_pandas()`` (and ``Trajectory.to_xarray()``), short reprs and notebook HTML.

``duration=`` [s], where a call takes the scene's ``time.steps``, runs the scene for that long
instead: N = duration / h, which must be a whole number of steps.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, overload

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from . import _chainbeam, _tables
from ._chainbeam import Scene
from ._errors import ConvergenceError, InvalidArgumentError
from ._progress import ProgressArg, Reporter

Array = NDArray[np.float64]


def _with_duration(scene: Scene, duration: float | None) -> Scene:
    """``scene`` run for ``duration`` seconds: ``time.steps`` = duration / ``time.step``, which
    must be a whole number (to 1e-9 relative) of at least 1."""
    if duration is None:
        return scene
    h = scene.step
    try:
        d = float(duration)
    except (TypeError, ValueError):
        d = math.nan
    steps = round(d / h) if math.isfinite(d) and d > 0 else 0
    if steps < 1 or abs(steps * h - d) > 1e-9 * d:
        raise InvalidArgumentError(
            f"duration: {duration!r} s is not a positive whole number of steps of "
            f"time.step = {h} s (the nearest are {max(steps, 1)} steps = {max(steps, 1) * h} s)",
            "InvalidArgument",
            "duration",
        )
    return scene.replace({"time.steps": steps})


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


@dataclass(frozen=True, repr=False)
class Trajectory:
    """A simulated trajectory, k = 0..N (the columns of ``chainbeam simulate``'s CSV).

    Attributes:
        t: times t_k = k h [s], shape (N + 1,).
        energy: total energy H(q_k, p_k; t_k, u_k) [J].
        moment: the thesis's base bending moment M₀(t_k) = 2 k₁ z₁ / l₁² (eq. 3.1.3; unit N:
            k₁ [N m/rad] z₁ [m] / l₁² [m²]). It is the thesis's objective, not the moment the
            wellhead carries: that is :attr:`wellhead_moment` M_w = M₀·l₁/2 [N m], the moment
            the fatigue assessment counts (docs/conventions.md "The wellhead moment M_w").
        positions: node positions [m], shape (N + 1, n, 3), columns x, y, z (x = 0 for a planar
            scene; the beam lies along +y).
        control: the control force u_k [N] (its z component for a 2-axis control; 0 without
            a control).
        moment_x: the x component M₀ₓ(t_k) of the base moment (spatial scenes only, else None).
        control_x: the x component u_x,k of the control (spatial scenes only, else None).
        eta: the surface elevation η(t_k) [m] at x = z = 0 of a scene with ``[loads.waves]``
            (the command line's ``eta`` column), else None.
        l1: the base pendulum's length l₁ [m] of the scene (``scene.l1``).
    """

    t: Array
    energy: Array
    moment: Array
    positions: Array
    control: Array
    moment_x: Array | None = None
    control_x: Array | None = None
    eta: Array | None = None
    l1: float = math.nan

    @property
    def is_spatial(self) -> bool:
        """Whether the spatial model ran (``moment_x`` and ``control_x`` are then arrays)."""
        return self.moment_x is not None

    @property
    def wellhead_moment(self) -> Array:
        """The wellhead bending moment M_w(t_k) = k₁z₁/l₁ = M₀(t_k)·l₁/2 [N m]: the base
        spring's torque, the moment ``fatigue`` counts cycles of (1.875·M₀ on riser_300m.toml,
        l₁ = 3.75 m; M₀/2 on the thesis's scenes, l₁ = 1 m)."""
        return self.moment * (0.5 * self.l1)

    @property
    def wellhead_moment_x(self) -> Array | None:
        """The x component of :attr:`wellhead_moment` (spatial scenes only, else None)."""
        return None if self.moment_x is None else self.moment_x * (0.5 * self.l1)

    def _columns(self) -> dict[str, Array]:
        cols: dict[str, Array] = {
            "energy": self.energy,
            "moment": self.moment,
            "wellhead_moment": self.wellhead_moment,
            "control": self.control,
        }
        for name in ("moment_x", "wellhead_moment_x", "control_x", "eta"):
            v = getattr(self, name)
            if v is not None:
                cols[name] = v
        return cols

    def to_pandas(self, positions: bool = False) -> pd.DataFrame:
        """The trajectory as a DataFrame indexed by time ``t`` [s], one row per step: the columns
        ``energy``, ``moment``, ``wellhead_moment``, ``control`` (and ``moment_x``,
        ``wellhead_moment_x``, ``control_x`` of a spatial run, ``eta`` with waves); units in
        ``df.attrs["units"]``. ``positions=True`` returns the node positions instead in long
        form: index (``t``, ``node``), nodes 1..n the pendulums' ends from the base up (the
        base, node 0, is fixed at the origin), columns ``x``, ``y``, ``z`` [m]."""
        if positions:
            steps, n, _ = self.positions.shape
            index = pd.MultiIndex.from_product(
                [self.t, np.arange(1, n + 1)], names=["t", "node"]
            )
            df = pd.DataFrame(
                self.positions.reshape(steps * n, 3), index=index, columns=["x", "y", "z"]
            )
            df.attrs["units"] = {"t": "s", "x": "m", "y": "m", "z": "m"}
            return df
        cols = self._columns()
        df = pd.DataFrame(cols, index=pd.Index(self.t, name="t"))
        df.attrs["units"] = _tables.units_of(["t", *cols])
        df.attrs["l1"] = self.l1
        return df

    def to_xarray(self) -> Any:
        """The trajectory as an ``xarray.Dataset`` (needs xarray): the dimensions ``t`` [s],
        ``node`` (1..n, the pendulums' ends from the base up) and ``axis`` (``"x"``, ``"y"``, ``"z"``); ``positions``
        (t, node, axis) and the columns of :meth:`to_pandas` over ``t``; every variable's
        ``attrs["units"]``, and the dataset's ``attrs["l1"]``."""
        try:
            import xarray as xr
        except ImportError as e:
            raise ImportError(
                "Trajectory.to_xarray needs xarray (pip install xarray); "
                "Trajectory.to_pandas() needs only pandas"
            ) from e
        n = self.positions.shape[1]
        data: dict[str, Any] = {
            "positions": (("t", "node", "axis"), self.positions, {"units": "m"}),
        }
        for name, v in self._columns().items():
            data[name] = (("t",), v, {"units": _tables.UNITS[name]})
        return xr.Dataset(
            data,
            coords={
                "t": ("t", self.t, {"units": "s"}),
                "node": np.arange(1, n + 1),
                "axis": ["x", "y", "z"],
            },
            attrs={"l1": self.l1, "l1_units": "m"},
        )

    def __repr__(self) -> str:
        steps = self.t.shape[0] - 1
        h = self.t[1] - self.t[0] if steps > 0 else math.nan
        return (
            f"chainbeam.Trajectory(N={steps} steps of h={_tables.fmt(h)} s to "
            f"t={_tables.fmt(self.t[-1])} s, n={self.positions.shape[1]}, "
            f"spatial={self.is_spatial}, wellhead_moment {_tables.span(self.wellhead_moment)} "
            f"N m, control {_tables.span(self.control)} N)"
        )

    def _repr_html_(self) -> str:
        return _tables.html_table(
            "chainbeam.Trajectory",
            [
                ("steps N", self.t.shape[0] - 1),
                ("t [s]", _tables.span(self.t)),
                ("pendulums n", self.positions.shape[1]),
                ("spatial", self.is_spatial),
                ("wellhead moment M_w [N m]", _tables.span(self.wellhead_moment)),
                ("M₀ [N]", _tables.span(self.moment)),
                ("control [N]", _tables.span(self.control)),
                ("energy [J]", _tables.span(self.energy)),
            ],
        )


def simulate(
    scene: Scene, controls: ArrayLike | None = None, *, duration: float | None = None
) -> Trajectory:
    """Simulates ``scene`` from its start with RATTLE (h = ``time.step``, N = ``time.steps``, or
    ``duration`` / h) under its own ``[control]`` or ``controls``. The start is the scene's
    ``[time] initial``: the straight beam at rest (``"rest"``, the default) or at rest in the
    static equilibrium of its steady loads (``"static"``).

    ``controls``: one value (a constant force), N + 1 values u_0..u_N, the θ that
    :func:`gradient` or :func:`optimize` return for the scene (one value per piece of a
    piecewise ``[control]``), or an (m, 2) array of pairs [u_x, u_z] (a 2-axis control),
    acting at ``control.node`` (default: the tip) — what ``chainbeam simulate --controls``
    takes. Bit for bit the command line's numbers.

    Raises:
        SceneError, InvalidArgumentError, SimulationError, ConvergenceError,
        TrajectoryTooLargeError (the run does not fit the memory budget; ``.key`` is
        ``"time.steps"``).
    """
    scene = _with_duration(scene, duration)
    z, x = _split_controls(controls)
    d = _chainbeam.simulate(scene, z, x)
    return Trajectory(**d, l1=scene.l1)


def _theta_layout(g: Array, two_axis: bool) -> Array:
    if two_axis:
        m = g.shape[0] // 2
        return np.stack([g[:m], g[m:]], axis=1)
    return g


@overload
def gradient(
    scene: Scene,
    controls: ArrayLike | None = None,
    *,
    effort: float = 0.0,
    wrt: None = None,
    duration: float | None = None,
) -> tuple[float, Array]: ...
@overload
def gradient(
    scene: Scene,
    controls: ArrayLike | None = None,
    *,
    effort: float = 0.0,
    wrt: Sequence[str],
    duration: float | None = None,
) -> tuple[float, dict[str, Any]]: ...
def gradient(
    scene: Scene,
    controls: ArrayLike | None = None,
    *,
    effort: float = 0.0,
    wrt: Sequence[str] | None = None,
    duration: float | None = None,
) -> tuple[float, Array] | tuple[float, dict[str, Any]]:
    """The objective J(θ) of the scene's ``[objective]`` (default ``"final"``: M₀(t_N)², thesis
    eq. 3.3.2; ``"sum"``: Σ M₀(t_k)², eq. 3.3.4; plus ρ h Σ u_k² with ``effort`` ρ) and its
    exact gradient by the discrete adjoint, at the scene's ``control.values`` or ``controls``.

    The gradient has θ's layout: one entry per value, or shape (m, 2) of [dJ/du_x, dJ/du_z]
    for a 2-axis control; it (and θ) can be passed back as ``controls``. Bit for bit
    ``chainbeam gradient``'s JSON.

    ``wrt``: the gradient with respect to physical parameters too, by their scene keys: returns
    ``(J, {key: dJ/dkey})`` in ``wrt``'s order, ``"controls"`` giving the θ-shaped array.
    Every parameter of the library: ``"loads.tension"``, ``"loads.drag"``,
    ``"loads.axial_weight"``, ``"loads.current.speed"``, ``"beam.base_stiffness"``,
    ``"beam.tip_stiffness"``, ``"loads.point[i].force"`` (F_z; ``force[0]`` F_x),
    ``"loads.point[i].harmonic[j].amplitude"`` and ``.phase``, and the keys that set many
    values at once, differentiated with respect to their common value (the sum of the partial
    derivatives): ``"beam.stiffness"`` (k₂..kₙ), ``"beam.mass"``, ``"beam.joint_damping"``.
    A parameter the scene does not have (no tension, no current) raises
    InvalidArgumentError (``kind == "NoSuchParameter"``).
    """
    scene = _with_duration(scene, duration)
    z, x = _split_controls(controls)
    if wrt is None:
        c, g, two_axis = _chainbeam.gradient(scene, z, x, effort)
        return c, _theta_layout(g, two_axis)
    if isinstance(wrt, str):
        wrt = [wrt]
    keys = [str(k) for k in wrt]
    c, gt, dp, two_axis = _chainbeam.gradient_wrt(scene, keys, z, x, effort)
    params = iter(dp)
    out: dict[str, Any] = {}
    for k in keys:
        if k == "controls":
            assert gt is not None
            out[k] = _theta_layout(gt, two_axis)
        else:
            out[k] = next(params)
    return c, out


@dataclass(frozen=True, repr=False)
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

    def __repr__(self) -> str:
        return (
            f"chainbeam.OptimizeResult(objective={_tables.fmt(self.objective)}, "
            f"converged={self.converged}, method={self.method!r}, iterations={self.iterations}, "
            f"controls: {self.controls.shape[0]} values {_tables.span(self.controls)} N, "
            f"termination={self.termination!r})"
        )

    def _repr_html_(self) -> str:
        return _tables.html_table(
            "chainbeam.OptimizeResult",
            [
                ("objective", self.objective),
                ("initial objective", self.initial_objective),
                ("converged", self.converged),
                ("termination", self.termination),
                ("method", self.method),
                ("iterations", self.iterations),
                ("projected gradient norm", self.projected_gradient_norm),
                ("controls [N]", f"{self.controls.shape[0]} values, {_tables.span(self.controls)}"),
            ],
        )


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
    progress: ProgressArg = False,
    duration: float | None = None,
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

    ``progress``: ``True`` for a bar (tqdm, else lines on standard error) or a callable
    ``progress(done, total)``: the iterations out of ``max_iters`` (with ``starts`` > 1, the
    starts done). ``result.controls`` has the layout ``controls=`` takes.
    """
    scene = _with_duration(scene, duration)
    z, x = _split_controls(controls)
    with Reporter(progress, "optimize", "it") as bar:
        d = _chainbeam.optimize(
            scene, method, bound, lower, upper, starts, seed, max_iters, gtol, effort, z, x,
            bar.callback,
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


@dataclass(frozen=True, repr=False)
class MpcResult:
    """The closed loop of :func:`mpc` (``chainbeam mpc``'s CSV and JSON summary).

    Attributes:
        t, moment, control, tip: t_k [s], M₀(t_k) [N] (``wellhead_moment`` M_w = M₀·l₁/2
            [N m]), the applied force u_k [N] and the tip displacement z_n(t_k) [m] under MPC,
            k = 0..N.
        summary: c_sum, max_abs_moment, max_abs_control, effort, decisions, re-plan times,
            ``mean_iterations`` and ``mean_rollouts`` (the plan model's simulations per
            re-plan), real-time factors (``chainbeam mpc --summary``'s per-controller keys); its
            ``controller`` is ``"mpc"`` (the baselines': ``"none"``, ``"constant"``, ``"pd"``,
            the names ``fatigue`` takes).
        baselines: with ``baselines=True`` the summaries of no control, the best constant force
            and the tuned PD law; ``moment_none``, ``moment_constant``, ``control_constant``,
            ``moment_pd``, ``control_pd`` their arrays and ``pd_gains`` [bias, K_p, K_d].
        l1: the scene's base pendulum length l₁ [m].
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
    l1: float = math.nan

    @property
    def wellhead_moment(self) -> Array:
        """M_w(t_k) = M₀(t_k)·l₁/2 [N m] under MPC (:attr:`Trajectory.wellhead_moment`)."""
        return self.moment * (0.5 * self.l1)

    def controllers(self) -> list[str]:
        """The controllers run: ``["mpc"]``, and ``"none"``, ``"constant"``, ``"pd"`` with
        baselines."""
        return ["mpc"] + (["none", "constant", "pd"] if self.moment_none is not None else [])

    def to_pandas(self) -> pd.DataFrame:
        """The closed loops in long form: one row per (controller, t_k), columns
        ``controller``, ``t`` [s], ``moment`` M₀ [N], ``wellhead_moment`` [N m], ``control`` [N]
        (no control: 0) and ``tip`` [m] (MPC's only; NaN for the baselines); units in
        ``df.attrs["units"]``. ``df.pivot(index="t", columns="controller", values="moment")``
        gives the wide table."""
        half = 0.5 * self.l1
        zeros = np.zeros_like(self.t)
        nan = np.full_like(self.t, np.nan)
        runs: list[tuple[str, Array, Array, Array]] = [
            ("mpc", self.moment, self.control, self.tip)
        ]
        if self.moment_none is not None:
            assert self.moment_constant is not None and self.moment_pd is not None
            assert self.control_constant is not None and self.control_pd is not None
            runs += [
                ("none", self.moment_none, zeros, nan),
                ("constant", self.moment_constant, self.control_constant, nan),
                ("pd", self.moment_pd, self.control_pd, nan),
            ]
        frames = [
            pd.DataFrame(
                {
                    "controller": name,
                    "t": self.t,
                    "moment": m,
                    "wellhead_moment": m * half,
                    "control": u,
                    "tip": tip,
                }
            )
            for name, m, u, tip in runs
        ]
        df = pd.concat(frames, ignore_index=True)
        df["controller"] = pd.Categorical(df["controller"], categories=[r[0] for r in runs])
        df.attrs["units"] = _tables.units_of(df.columns)
        return df

    def summary_frame(self) -> pd.DataFrame:
        """The summaries (MPC's and the baselines'), one row per controller (index
        ``controller``): ``c_sum``, ``max_abs_moment``, ``max_abs_control``, ...."""
        rows = [self.summary, *self.baselines]
        return pd.DataFrame(rows).set_index("controller")

    def __repr__(self) -> str:
        s = self.summary
        base = (
            ", baselines " + ", ".join(
                f"{b['controller']} c_sum={_tables.fmt(b['c_sum'])}" for b in self.baselines
            )
            if self.baselines
            else ""
        )
        return (
            f"chainbeam.MpcResult(N={self.t.shape[0] - 1} steps to t={_tables.fmt(self.t[-1])} s, "
            f"mpc c_sum={_tables.fmt(s['c_sum'])}, max|u|={_tables.fmt(s['max_abs_control'])} N"
            f"{base})"
        )

    def _repr_html_(self) -> str:
        table = self.summary_frame()[["c_sum", "max_abs_moment", "max_abs_control"]]
        return "<b>chainbeam.MpcResult</b>" + str(table.to_html(float_format="{:.4g}".format))


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
    progress: ProgressArg = False,
    duration: float | None = None,
) -> MpcResult:
    """Receding-horizon control of ``scene`` in closed loop: ``chainbeam mpc`` with the same
    flags and defaults (a plan over ``horizon`` s every ``interval`` s on ``model``, default the
    scene itself; the plan's first force applied at ``control.node``), planar scenes.
    ``baselines=True`` also runs no control, the best constant force and a tuned PD law.
    ``horizon``, ``interval``, ``iterations``, ``bound``, ``effort``, ``plan_pendulums``,
    ``plan_step``: ``None`` takes the scene's ``[mpc]`` key, else the command line's default
    (3 s, 0.1 s, 1, 5 N, 0.01, off, off); the table's ``objective`` and the model's
    ``[objective]`` set what the plans minimise, as on the command line.

    ``progress``: ``True`` for a bar (tqdm, else lines on standard error) or a callable
    ``progress(done, total)``: the decisions of every closed loop run (four with baselines).
    ``duration`` [s]: the run's length instead of the scene's ``time.steps``."""
    scene = _with_duration(scene, duration)
    with Reporter(progress, "mpc", "decision") as r:
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
            r.callback,
        )
    return MpcResult(**d, l1=scene.l1)
