"""Checks of the comparison's own arithmetic (numpy only; moordyn and the chain are not needed):

    target/peer-venv/bin/python -m pytest -q -p no:cacheprovider scripts/peers/moordyn/test_pipe.py

- the sea taken apart from a periodic η record gives back its amplitudes and phases;
- the kinematics built by inverse FFTs equal the Airy sums evaluated directly;
- the dispersion relation holds at the wavenumbers;
- the riser's derived numbers are the ones of examples/scenes/riser_300m.toml's comments.
"""

from __future__ import annotations

import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from pipe import G, Riser, Sea, wavenumbers  # noqa: E402


def a_sea(components: int = 40, period: float = 100.0) -> Sea:
    rng = np.random.default_rng(7)
    j = np.arange(1, components + 1)
    amp = rng.uniform(0.1, 1.0, components) * np.exp(2j * math.pi * rng.uniform(size=components))
    return Sea(omega=2.0 * math.pi * j / period, amplitude=amp, period=period)


def test_dft_gives_back_the_components() -> None:
    sea = a_sea()
    step = 0.05
    t = np.arange(int(round(sea.period / step))) * step
    back = Sea.from_elevation(sea.elevation(t), step, len(sea.omega))
    # Reference: the components the record was made of (exact DFT of a periodic record).
    assert np.max(np.abs(back.amplitude - sea.amplitude)) < 1e-12
    assert np.max(np.abs(back.omega - sea.omega)) < 1e-12


def test_a_component_above_the_count_is_refused() -> None:
    sea = a_sea()
    step = 0.05
    t = np.arange(int(round(sea.period / step))) * step
    try:
        Sea.from_elevation(sea.elevation(t), step, len(sea.omega) - 1)
    except ValueError as e:
        assert "above bin" in str(e)
    else:
        raise AssertionError("a record with more components than said was accepted")


def test_kinematics_by_fft_equal_the_direct_sums() -> None:
    sea = a_sea()
    depth = 120.0
    heights = np.array([0.0, 30.0, 90.0, 119.0, 120.0])
    step, shift = 0.05, 0.025
    u, a = sea.kinematics_series(heights, depth, step, shift)
    k = wavenumbers(sea.omega, depth)
    for row in (0, 17, 1999):
        t = shift + row * step
        for col, y in enumerate(heights):
            # Reference: Airy's u = Re Σ ω c cosh(ky)/sinh(kd) e^{iωt}, u̇ its time derivative.
            prof = np.cosh(k * y) / np.sinh(k * depth)
            e = np.exp(1j * sea.omega * t)
            u_direct = np.real(np.sum(sea.omega * sea.amplitude * prof * e))
            a_direct = np.real(np.sum(1j * sea.omega**2 * sea.amplitude * prof * e))
            assert abs(u[row, col] - u_direct) < 1e-12 * np.sum(np.abs(sea.omega * sea.amplitude))
            assert abs(a[row, col] - a_direct) < 1e-12 * np.sum(
                np.abs(sea.omega**2 * sea.amplitude)
            )


def test_dispersion() -> None:
    omega = np.linspace(0.05, 5.0, 50)
    for depth in (10.0, 300.0):
        k = wavenumbers(omega, depth)
        assert np.max(np.abs(G * k * np.tanh(k * depth) / omega**2 - 1.0)) < 1e-13


def test_riser_numbers() -> None:
    r = Riser()
    # Reference: riser_300m.toml's comments: w = 3149.1 N/m, μ = 779.2 kg/m (with added mass),
    # T = 1.3 · 3149.1 · 300 = 1.228 MN.
    assert abs(r.submerged_weight - 3149.1) < 0.1
    mu = r.structural_mass + r.added_mass_coefficient * r.water_density * r.outer_area
    assert abs(mu - 779.2) < 0.1
    assert abs(r.top_tension - 1.228e6) < 1e3
