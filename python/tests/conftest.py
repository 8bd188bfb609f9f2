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
