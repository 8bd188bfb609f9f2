"""The Python calls equal the command line's outputs bit for bit (reference: `chainbeam
simulate` CSV, `chainbeam gradient` / `optimize` JSON; their numbers are the shortest decimals
that read back to the same doubles, so float() recovers every bit)."""

from __future__ import annotations

import csv
import io
import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

import chainbeam as cb
from conftest import wave_riser_toml


def run(cli: str, *args: str, status: int = 0) -> str:
    p = subprocess.run([cli, "--quiet", *args], capture_output=True, text=True)
    assert p.returncode == status, p.stderr
    return p.stdout


def bits(a: object) -> np.ndarray:
    return np.ascontiguousarray(np.asarray(a, dtype=np.float64)).view(np.int64)


def read_csv(text: str) -> dict[str, np.ndarray]:
    rows = list(csv.reader(io.StringIO(text)))
    header, body = rows[0], rows[1:]
    cols = np.array([[float(v) for v in r] for r in body])
    return {h: cols[:, j] for j, h in enumerate(header)}


def assert_trajectory_equal(traj: cb.Trajectory, cols: dict[str, np.ndarray]) -> None:
    n = traj.positions.shape[1]
    for name in ("t", "energy", "moment", "control"):
        assert np.array_equal(bits(getattr(traj, name)), bits(cols[name])), name
    for i in range(n):
        for c, axis in zip("xyz", range(3)):
            assert np.array_equal(bits(traj.positions[:, i, axis]), bits(cols[f"{c}{i + 1}"]))
    if "moment_x" in cols:
        assert traj.moment_x is not None and traj.control_x is not None
        assert np.array_equal(bits(traj.moment_x), bits(cols["moment_x"]))
        assert np.array_equal(bits(traj.control_x), bits(cols["control_x"]))
    else:
        assert traj.moment_x is None
    if "eta" in cols:
        assert traj.eta is not None
        assert np.array_equal(bits(traj.eta), bits(cols["eta"]))
    else:
        assert traj.eta is None


@pytest.mark.parametrize(
    "name", ["riser_5.toml", "thesis_cantilever.toml", "oblique_riser.toml", "wave_series.toml"]
)
def test_simulate_equals_cli_csv(cli: str, scenes: Path, name: str) -> None:
    path = scenes / name
    cols = read_csv(run(cli, "simulate", str(path)))
    traj = cb.simulate(cb.Scene.from_file(path))
    assert traj.positions.shape == (len(cols["t"]), traj.positions.shape[1], 3)
    assert_trajectory_equal(traj, cols)


@pytest.mark.parametrize("direction", [0.0, 30.0])
def test_simulate_with_waves_equals_cli_csv(cli: str, tmp_path: Path, direction: float) -> None:
    """A scene with [loads.waves] (at 30° the spatial model): `eta` and every other column equal
    the command line's CSV bit for bit."""
    path = tmp_path / "waves.toml"
    path.write_text(wave_riser_toml(direction))
    cols = read_csv(run(cli, "simulate", str(path)))
    assert "eta" in cols
    traj = cb.simulate(cb.Scene.from_file(path))
    assert traj.eta is not None and traj.eta.shape == (201,)
    assert traj.is_spatial == (direction != 0.0)
    assert_trajectory_equal(traj, cols)


def test_simulate_with_controls_equals_cli(cli: str, scenes: Path, tmp_path: Path) -> None:
    path = scenes / "riser_5.toml"
    scene = cb.Scene.from_file(path)
    u = np.linspace(-3.0, 1.0, scene.steps + 1)
    f = tmp_path / "u.json"
    f.write_text(json.dumps({"controls": u.tolist()}))
    cols = read_csv(run(cli, "simulate", str(path), "--controls", str(f)))
    assert_trajectory_equal(cb.simulate(scene, u), cols)


@pytest.mark.parametrize("name", ["riser_5.toml", "oblique_control.toml"])
def test_gradient_equals_cli_json(cli: str, scenes: Path, name: str) -> None:
    path = scenes / name
    ref = json.loads(run(cli, "gradient", str(path)))
    c, g = cb.gradient(cb.Scene.from_file(path))
    assert bits(c) == bits(ref["objective"])
    assert np.array_equal(bits(g), bits(ref["gradient"]))


def test_gradient_with_effort_and_controls_equals_cli(
    cli: str, scenes: Path, tmp_path: Path
) -> None:
    path = scenes / "riser_5.toml"
    scene = cb.Scene.from_file(path)
    u = np.cos(np.arange(scene.steps + 1.0))
    f = tmp_path / "u.json"
    f.write_text(json.dumps({"controls": u.tolist()}))
    ref = json.loads(run(cli, "gradient", str(path), "--controls", str(f), "--effort", "0.5"))
    c, g = cb.gradient(scene, u, effort=0.5)
    assert bits(c) == bits(ref["objective"])
    assert np.array_equal(bits(g), bits(ref["gradient"]))


def test_optimize_equals_cli_json(cli: str, scenes: Path) -> None:
    path = scenes / "riser_5.toml"
    ref = json.loads(run(cli, "optimize", str(path), "--bound", "100"))
    r = cb.optimize(cb.Scene.from_file(path), bound=100.0)
    assert r.converged and ref["converged"]
    assert bits(r.objective) == bits(ref["objective"])
    assert np.array_equal(bits(r.controls), bits(ref["controls"]))
    assert r.termination == ref["termination"] and r.iterations == ref["iterations"]


def test_optimize_multistart_equals_cli_json(cli: str, scenes: Path) -> None:
    path = scenes / "riser_7.toml"
    ref = json.loads(run(cli, "optimize", str(path), "--starts", "4", "--seed", "3"))
    r = cb.optimize(cb.Scene.from_file(path), starts=4, seed=3)
    assert bits(r.objective) == bits(ref["objective"])
    assert np.array_equal(bits(r.controls), bits(ref["controls"]))
    assert r.minima_found == ref["minima_found"]


def test_mpc_reads_the_mpc_table_like_cli(cli: str, scenes: Path, tmp_path: Path) -> None:
    """A scene with an `[mpc]` table: `mpc` takes its keys where no argument is given, as
    `chainbeam mpc` takes them where no flag is given (the same closed loop, bit for bit), and an
    argument overrides its key as the flag does."""
    short = cb.Scene.from_file(scenes / "mpc_riser.toml").replace({"time.steps": 200})
    path = tmp_path / "table.toml"
    path.write_text(short.to_toml()
                    + "\n[mpc]\ninterval = 0.2\nhorizon = 0.6\nbound = 3.0\neffort = 0.02\n")
    scene = cb.Scene.from_file(path)
    for flags, kwargs in [((), {}), (("--horizon", "0.4"), {"horizon": 0.4})]:
        cols = read_csv(run(cli, "mpc", str(path), *flags))
        r = cb.mpc(scene, **kwargs)
        for name in ("t", "moment", "control", "tip"):
            assert np.array_equal(bits(getattr(r, name)), bits(cols[name])), (flags, name)
        assert r.summary["decisions"] == 10  # 2 s at the table's 0.2 s
        assert r.summary["max_abs_control"] <= 3.0


def test_mpc_equals_cli_csv(cli: str, scenes: Path, tmp_path: Path) -> None:
    # A short closed loop of the MPC scene (its first 2 s), so the test stays quick.
    scene = cb.Scene.from_file(scenes / "mpc_riser.toml").replace({"time.steps": 200})
    path = tmp_path / "short.toml"
    path.write_text(scene.to_toml())
    summary = tmp_path / "summary.json"
    cols = read_csv(run(cli, "mpc", str(path), "--horizon", "1.0", "--summary", str(summary)))
    r = cb.mpc(scene, horizon=1.0)
    for name in ("t", "moment", "control", "tip"):
        assert np.array_equal(bits(getattr(r, name)), bits(cols[name])), name
    # What the re-plans cost, counted (not timed): the same in both.
    ref = json.loads(summary.read_text())["mpc"]
    for key in ("decisions", "mean_iterations", "mean_rollouts"):
        assert r.summary[key] == ref[key], key
    assert r.summary["mean_rollouts"] >= r.summary["mean_iterations"] > 0
