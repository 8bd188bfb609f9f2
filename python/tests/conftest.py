"""Shared fixtures: the repository's scenes and the command line they are compared with."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "examples" / "scenes"


@pytest.fixture(scope="session")
def cli() -> str:
    """The `chainbeam` command line: $CHAINBEAM_CLI, else target/debug or target/release of the
    repository, else `chainbeam` on PATH. The comparisons need it, so its absence fails."""
    env = os.environ.get("CHAINBEAM_CLI")
    candidates = [env] if env else []
    candidates += [str(ROOT / "target" / p / "chainbeam") for p in ("debug", "release")]
    for c in candidates:
        if c and Path(c).is_file() and os.access(c, os.X_OK):
            return c
    found = shutil.which("chainbeam")
    if found:
        return found
    pytest.fail(
        "the chainbeam command line is needed for the comparisons: build it with "
        "`cargo build --bin chainbeam` or set CHAINBEAM_CLI"
    )


@pytest.fixture(scope="session")
def scenes() -> Path:
    return SCENES


# The 60 m riser of tests/cli/cli_fatigue_study.rs: 6 pendulums, a JONSWAP sea (seed 7) from
# `direction` degrees (0: the planar model), a uniform 0.3 m/s current, 10 s of 0.05 s.
WAVE_RISER = """[beam]
pendulums = 6
support = "riser"

[pipe]
length = 60.0
outer_diameter = 0.5334
wall_thickness = 0.0222

[water]
depth = 60.0

[loads]
tension = 1e6
drag = 1e-4

[loads.current]
profile = "uniform"
speed = 0.3

[loads.waves]
spectrum = "jonswap"
hs = 3.0
tp = 9.0
seed = 7
direction = {direction!r}

[time]
step = 0.05
steps = 200
"""


def wave_riser_toml(direction: float = 0.0, tail: str = "") -> str:
    """The wave riser's scene text with its waves from `direction`, then `tail` (more tables)."""
    return WAVE_RISER.format(direction=direction) + tail
