"""The riser both codes model, and the sea they both see.

One uniform pipe, the 21-inch drilling riser joint of examples/scenes/riser_300m.toml (bare joint,
12 ppg mud inside), 300 m from the wellhead (clamped) to the top (held laterally, pinned, under
the tensioner's constant tension), Morison's drag and inertia node by node. Everything here is
plain numbers in SI units; the two drivers (chain.py, peer.py) read them from this one place.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

G = 9.80665  # m/s², the chain's g (docs/conventions.md "Waves"); MoorDyn is given the same


@dataclass(frozen=True)
class Riser:
    """The pipe, the water and the discretisation shared by both codes."""

    length: float = 300.0  # m, wellhead to top; also the water depth (top node at the surface)
    outer_diameter: float = 0.5334  # m (21 in)
    wall_thickness: float = 0.022225  # m (0.875 in)
    youngs_modulus: float = 207e9  # Pa
    steel_density: float = 7850.0  # kg/m³
    contents_density: float = 1437.912  # kg/m³ (12 ppg mud)
    water_density: float = 1025.0  # kg/m³
    drag_coefficient: float = 1.0
    added_mass_coefficient: float = 1.0
    tension_factor: float = 1.3  # top tension = 1.3 × the submerged weight of the whole pipe
    segments: int = 80  # chain pendulums = MoorDyn segments

    @property
    def inner_diameter(self) -> float:
        return self.outer_diameter - 2.0 * self.wall_thickness

    @property
    def steel_area(self) -> float:
        return math.pi / 4.0 * (self.outer_diameter**2 - self.inner_diameter**2)

    @property
    def outer_area(self) -> float:
        return math.pi / 4.0 * self.outer_diameter**2

    @property
    def inner_area(self) -> float:
        return math.pi / 4.0 * self.inner_diameter**2

    @property
    def bending_stiffness(self) -> float:
        """EI [N m²]."""
        second_moment = math.pi / 64.0 * (self.outer_diameter**4 - self.inner_diameter**4)
        return self.youngs_modulus * second_moment

    @property
    def axial_stiffness(self) -> float:
        """EA [N] of the steel wall (MoorDyn's line is extensible; the chain is not)."""
        return self.youngs_modulus * self.steel_area

    @property
    def structural_mass(self) -> float:
        """Steel + contents per length [kg/m] (MoorDyn's Mass/m; added mass comes from Ca)."""
        return self.steel_density * self.steel_area + self.contents_density * self.inner_area

    @property
    def submerged_weight(self) -> float:
        """w = g (ρ_s A_s + ρ_c A_i − ρ_w A_o) [N/m]."""
        return G * (self.structural_mass - self.water_density * self.outer_area)

    @property
    def top_tension(self) -> float:
        """The tensioner's constant vertical force at the top [N]."""
        return self.tension_factor * self.submerged_weight * self.length

    @property
    def segment_length(self) -> float:
        return self.length / self.segments

    def node_heights(self) -> np.ndarray:
        """Heights of nodes 0..n on the straight riser [m] above the wellhead (the chain's y_k)."""
        return np.arange(self.segments + 1) * self.segment_length

    def wellhead_moment_chain(self, z1: np.ndarray, y1: np.ndarray) -> np.ndarray:
        """The chain's base joint torque k₁θ₁, k₁ = 2EI/l, θ₁ = atan2(z₁, y₁) [N m]."""
        k1 = 2.0 * self.bending_stiffness / self.segment_length
        return k1 * np.arctan2(z1, y1)


def wavenumbers(omega: np.ndarray, depth: float) -> np.ndarray:
    """k from ω² = g k tanh(k d) by Newton's method (the exact finite-depth dispersion)."""
    k = omega**2 / G  # deep-water start
    for _ in range(100):
        t = np.tanh(k * depth)
        f = G * k * t - omega**2
        df = G * t + G * k * depth * (1.0 - t * t)
        step = f / df
        k = k - step
        if np.all(np.abs(step) <= 1e-15 * k):
            break
    return k


@dataclass(frozen=True)
class Sea:
    """η(t) = Re Σⱼ cⱼ e^{i ωⱼ t}, cⱼ = aⱼ e^{i φⱼ}, periodic with period `period`."""

    omega: np.ndarray  # rad/s
    amplitude: np.ndarray  # complex cⱼ [m]
    period: float  # s

    @staticmethod
    def from_elevation(eta: np.ndarray, step: float, components: int) -> "Sea":
        """The components j = 1..N of a periodic record η(kh), k = 0..M−1, M h one period
        (an exact DFT: cⱼ = (2/M) Σₖ η(kh) e^{−2πi jk/M}). Every bin above N must be round-off
        (below 1e-12 of the largest), else the record is not the sea it is said to be."""
        m = len(eta)
        spectrum = np.fft.rfft(eta) * (2.0 / m)
        above = np.abs(spectrum[components + 1 :])
        largest = np.max(np.abs(spectrum))
        if len(above) and np.max(above) > 1e-12 * largest:
            raise ValueError(
                f"the record has a component above bin {components}: "
                f"{np.max(above) / largest:.1e} of the largest"
            )
        period = m * step
        j = np.arange(1, components + 1)
        return Sea(omega=2.0 * math.pi * j / period, amplitude=spectrum[j], period=period)

    def elevation(self, t: np.ndarray) -> np.ndarray:
        return np.real(np.exp(1j * np.outer(t, self.omega)) @ self.amplitude)

    def kinematics_series(
        self, heights: np.ndarray, depth: float, step: float, shift: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """Airy velocity u and acceleration u̇ at the given heights above the seabed, on the grid
        t = shift + k·step over one period (inverse FFT; `step` must divide the period):
        u = Re Σ ωⱼ cⱼ cosh(kⱼ y)/sinh(kⱼ d) e^{iωⱼ t}, u̇ = Re Σ i ωⱼ² cⱼ (…) e^{iωⱼ t}.
        Returns arrays of shape (samples, len(heights))."""
        samples = int(round(self.period / step))
        if abs(samples * step - self.period) > 1e-9 * self.period:
            raise ValueError(f"step {step} s does not divide the sea's period {self.period} s")
        k = wavenumbers(self.omega, depth)
        bins = np.rint(self.omega * self.period / (2.0 * math.pi)).astype(int)
        phase = np.exp(1j * self.omega * shift)
        u = np.empty((samples, len(heights)))
        a = np.empty((samples, len(heights)))
        for col, y in enumerate(heights):
            # cosh(k y)/sinh(k d) without overflow: exp(k(y−d)) (1 + e^{−2ky}) / (1 − e^{−2kd})
            profile = np.exp(k * (y - depth)) * (1.0 + np.exp(-2.0 * k * y)) / (
                1.0 - np.exp(-2.0 * k * depth)
            )
            cu = self.omega * self.amplitude * profile * phase
            ca = 1j * self.omega * cu
            full_u = np.zeros(samples // 2 + 1, dtype=complex)
            full_a = np.zeros(samples // 2 + 1, dtype=complex)
            full_u[bins] = cu
            full_a[bins] = ca
            u[:, col] = np.fft.irfft(full_u, n=samples) * samples / 2.0
            a[:, col] = np.fft.irfft(full_a, n=samples) * samples / 2.0
        return u, a
