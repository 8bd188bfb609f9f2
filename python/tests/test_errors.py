"""Typed errors with the library's messages: a bad scene names the key; a non-converged optimize
says so (reference: the command line exits with status 3 on the same settings)."""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest

import chainbeam as cb

GOOD = """
[beam]
pendulums = 3
length = 1.0
mass = 1.0
stiffness = 100.0
support = "cantilever"
[time]
step = 0.01
steps = 10
"""


def test_bad_value_names_key() -> None:
    with pytest.raises(cb.SceneError) as e:
        cb.Scene.from_toml(GOOD.replace("mass = 1.0", "mass = -1.0"))
    assert e.value.key == "beam.mass"
    assert isinstance(e.value, ValueError) and e.value.kind == "Scene"
    # The library's message (its doc example in src/lib.rs).
    assert str(e.value) == "invalid scene: key `beam.mass`: must be positive and finite, got -1"


def test_unknown_key_and_file_are_named(tmp_path: Path) -> None:
    f = tmp_path / "s.toml"
    f.write_text(GOOD.replace("steps = 10", "steps = 10\nstepz = 3"))
    with pytest.raises(cb.SceneError) as e:
        cb.Scene.from_file(f)
    assert e.value.key == "time.stepz" and e.value.file == str(f)
    assert str(f) in str(e.value)


def test_replace_errors_name_the_key() -> None:
    s = cb.Scene.from_toml(GOOD)
    with pytest.raises(cb.SceneError) as e:
        s.replace({"loads.drag": -2.0})
    assert e.value.key == "loads.drag"
    with pytest.raises(cb.SceneError) as e:
        s.replace({"beam.stifness": 3.0})
    assert e.value.key == "beam.stifness"
    with pytest.raises(cb.SceneError) as e:
        s.replace({"beam.mass.x": 3.0})
    assert e.value.key == "beam.mass"
    with pytest.raises(cb.SceneError) as e:
        s.replace({"time.steps": object()})
    assert e.value.key == "time.steps"
    # A valid change reads back: the key now holds the value.
    assert cb.Scene.from_toml(s.replace({"loads.drag": 12.0}).to_toml()).to_toml().count(
        "drag = 12.0"
    ) == 1


def test_round_trip_to_toml(scenes: Path) -> None:
    for f in sorted(scenes.glob("*.toml")):
        s = cb.Scene.from_file(f)
        assert cb.Scene.from_toml(s.to_toml(), dir=f.parent) == s, f.name


def test_wrong_controls_are_invalid_arguments() -> None:
    s = cb.Scene.from_toml(GOOD)
    with pytest.raises(cb.InvalidArgumentError) as e:
        cb.simulate(s, np.zeros(5))
    assert e.value.key == "controls" and "N + 1 = 11" in str(e.value)
    with pytest.raises(cb.InvalidArgumentError):
        cb.simulate(s, [np.nan])
    with pytest.raises(cb.InvalidArgumentError) as e:
        cb.optimize(s, method="newton")  # type: ignore[arg-type]
    assert e.value.key == "method"


def test_newton_failure_is_a_convergence_error(cli: str, tmp_path: Path) -> None:
    """Thesis §2.2.4: the cantilever's Newton solve fails at h = 0.02 s. The exception carries
    the library's message, the one the command line prints after the file name."""
    s = cb.Scene.from_file(Path(__file__).parents[2] / "examples/scenes/thesis_cantilever.toml")
    bad = s.replace({"time.step": 0.02, "time.steps": 40})
    with pytest.raises(cb.ConvergenceError) as e:
        cb.simulate(bad)
    assert e.value.kind == "NewtonNotConverged" and "time.step" in str(e.value)
    f = tmp_path / "bad.toml"
    f.write_text(bad.to_toml())
    p = subprocess.run([cli, "-q", "simulate", str(f)], capture_output=True, text=True)
    assert p.returncode == 1
    assert p.stderr == f"error: {f}: {e.value}\n"


def test_non_converged_optimize_says_so(cli: str, scenes: Path) -> None:
    path = scenes / "riser_5.toml"
    p = subprocess.run(
        [cli, "-q", "optimize", str(path), "--max-iters", "1", "--effort", "1e-9"],
        capture_output=True,
        text=True,
    )
    assert p.returncode == 3, p.stderr  # the command line's "did not converge"
    scene = cb.Scene.from_file(path)
    with pytest.raises(cb.ConvergenceError) as e:
        cb.optimize(scene, max_iters=1, effort=1e-9)
    assert e.value.kind == "NotConverged" and "did not converge" in str(e.value)
    assert e.value.result is not None and not e.value.result.converged
    r = cb.optimize(scene, max_iters=1, effort=1e-9, check=False)
    assert not r.converged and r.termination == e.value.result.termination
