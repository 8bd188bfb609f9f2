"""The chain's side: the scene file for the riser of pipe.py, and a `chainbeam simulate` run."""

from __future__ import annotations

import os
import subprocess
from dataclasses import dataclass

import numpy as np

from pipe import Riser


@dataclass(frozen=True)
class Current:
    """A current along +z: `"uniform"` (speed everywhere) or `"linear"` (speed at the surface
    to bottom_speed at the wellhead, the chain's `[loads.current]` profiles)."""

    profile: str = "uniform"
    speed: float = 0.5
    bottom_speed: float = 0.0

    def at(self, heights: np.ndarray, surface: float) -> np.ndarray:
        """U(y) on the straight riser's heights (docs/scene-format.md `[loads.current]`)."""
        if self.profile == "uniform":
            return np.full(len(heights), self.speed)
        depth = surface - heights
        return self.speed + (self.bottom_speed - self.speed) * depth / surface

    def toml(self) -> str:
        lines = ["[loads.current]", f'profile = "{self.profile}"', f"speed = {self.speed!r}"]
        if self.profile == "linear":
            lines.append(f"bottom_speed = {self.bottom_speed!r}")
        return "\n".join(lines) + "\n"


@dataclass(frozen=True)
class Waves:
    """A JONSWAP sea on the chain. T_r = N T_p/6 (N = components; ω_c = 6 ω_p) is the sea's
    repeat period; T_p/6 a whole number of chain steps and MoorDyn coupling steps makes one
    period of the `eta` column an exact DFT of the sea."""

    hs: float = 4.9
    tp: float = 9.9
    gamma: float = 3.3
    seed: int = 1
    components: int = 425

    @property
    def period(self) -> float:
        return self.components * self.tp / 6.0

    def toml(self) -> str:
        return (
            "[loads.waves]\n"
            'spectrum = "jonswap"\n'
            f"hs = {self.hs!r}\n"
            f"tp = {self.tp!r}\n"
            f"gamma = {self.gamma!r}\n"
            f"seed = {self.seed}\n"
            f"components = {self.components}\n"
            'lumping = "node"          # the Airy velocity at each node\'s height (what MoorDyn is given)\n'
        )


def scene_toml(
    riser: Riser, current: Current, waves: Waves | None, step: float, steps: int, title: str
) -> str:
    """The chain's scene: the pipe held by a still vessel (top pinned: tip_stiffness = 0),
    clamped at the wellhead, Morison's drag node by node."""
    return (
        f"# {title}\n"
        "# Written by scripts/peers/moordyn/compare.py (the peer comparison with MoorDyn v2; its\n"
        "# README says how to rerun it). The riser of examples/scenes/riser_300m.toml, its top held\n"
        "# laterally in place and pinned (support = \"vessel\" without [vessel], no upper flex joint),\n"
        "# Morison's drag node by node.\n"
        "[beam]\n"
        f"pendulums = {riser.segments}\n"
        'support = "vessel"\n'
        "tip_stiffness = 0.0        # a pinned top, as MoorDyn's coupled point\n\n"
        "[pipe]\n"
        f"length = {riser.length!r}\n"
        f"outer_diameter = {riser.outer_diameter!r}\n"
        f"wall_thickness = {riser.wall_thickness!r}\n"
        f"youngs_modulus = {riser.youngs_modulus!r}\n"
        f"steel_density = {riser.steel_density!r}\n"
        f"contents_density = {riser.contents_density!r}\n"
        f"drag_coefficient = {riser.drag_coefficient!r}\n"
        f"added_mass_coefficient = {riser.added_mass_coefficient!r}\n"
        'drag_model = "morison"\n\n'
        "[water]\n"
        f"depth = {riser.length!r}\n"
        f"density = {riser.water_density!r}\n\n"
        "[loads]\n"
        f"tension = {riser.top_tension!r}     # N: 1.3 × the pipe's submerged weight\n"
        f"axial_weight = {riser.submerged_weight!r}  # N/m: g (ρ_s A_s + ρ_c A_i − ρ_w A_o)\n\n"
        + current.toml()
        + "\n"
        + (waves.toml() + "\n" if waves else "")
        + "[time]\n"
        f"step = {step!r}\n"
        f"steps = {steps}\n"
    )


@dataclass
class ChainRun:
    """Columns of a `chainbeam simulate` run: t, the wellhead moment k₁θ₁, the nodes' z
    (nodes 1..n; node 0 is the wellhead at z = 0) and η (NaN without waves)."""

    t: np.ndarray
    moment: np.ndarray
    offsets: np.ndarray  # (samples, n + 1): z of nodes 0..n
    eta: np.ndarray
    cpu_seconds: float


def run(
    binary: str, riser: Riser, scene: str, path: str, waves: bool, every: int = 1
) -> ChainRun:
    """Write the scene to `path` and run `chainbeam simulate` on it (npy output)."""
    with open(path, "w", encoding="utf-8") as f:
        f.write(scene)
    n = riser.segments
    columns = ["t", "y1"] + [f"z{i}" for i in range(1, n + 1)] + (["eta"] if waves else [])
    out = os.path.splitext(path)[0] + ".npy"
    start = os.times()
    subprocess.run(
        [binary, "simulate", path, "--columns", ",".join(columns), "--every", str(every),
         "--output", out],
        check=True,
    )
    end = os.times()
    cpu = (end.children_user - start.children_user) + (end.children_system - start.children_system)
    a = np.load(out)
    z = np.zeros((len(a), n + 1))
    z[:, 1:] = a[:, 2 : 2 + n]
    return ChainRun(
        t=a[:, 0],
        moment=riser.wellhead_moment_chain(a[:, 2], a[:, 1]),
        offsets=z,
        eta=a[:, -1] if waves else np.full(len(a), np.nan),
        cpu_seconds=cpu,
    )
