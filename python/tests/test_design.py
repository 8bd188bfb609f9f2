"""`chainbeam.design` against `chainbeam design`'s JSON (the command line writes the shortest
decimals that read back to the same doubles, so `json.loads` recovers every bit): the
sensitivities and an optimisation, serially and with the cells on executors (a thread pool, a
process pool and a Dask LocalCluster give the same gradient, iterates and design bit for bit as
the serial run); progress per iteration; refusals naming the key.

The scene is the README's design example (examples/scenes/riser_300m_design.toml: 10 pendulums
at h = 0.1 s, `[design]` freeing the tension and the lower flex joint's stiffness) with at most
3 iterations, on a two-cell diagram with 20 s records after a 10 s spin-up: a few seconds per
run."""

from __future__ import annotations

import json
import subprocess
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest

import chainbeam as cb
from conftest import SCENES

RECORD, SPIN_UP = 20.0, 10.0
DIAGRAM = [(1.5, 7.0, 0.6), (3.0, 9.0, 0.4)]


def same(a: Any, b: Any) -> bool:
    """Equal structures with bit-equal floats (ints and floats of equal value compare as the
    JSON reader gives them)."""
    if isinstance(a, dict) and isinstance(b, dict):
        return list(a) == list(b) and all(same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    if isinstance(a, float) or isinstance(b, float):
        return float(a).hex() == float(b).hex()
    return bool(a == b)


def without_seconds(d: dict[str, Any]) -> dict[str, Any]:
    """The report without its wall time (the one field that is not a result)."""
    return {k: v for k, v in d.items() if k != "seconds"}


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    d = tmp_path_factory.mktemp("design")
    text = (SCENES / "riser_300m_design.toml").read_text()
    assert "max_iterations = 20" in text
    scene = d / "design.toml"
    scene.write_text(text.replace("max_iterations = 20", "max_iterations = 3"))
    scatter = d / "cells.csv"
    scatter.write_text("hs,tp,probability\n" + "".join(f"{h},{t},{p}\n" for h, t, p in DIAGRAM))
    return scene, scatter


def cli_json(cli: str, *args: str) -> Any:
    """`chainbeam design ARGS`'s JSON (exit status 0, or 3 when the optimiser did not converge:
    the JSON is written all the same)."""
    p = subprocess.run([cli, "--quiet", "design", *args], capture_output=True, text=True)
    assert p.returncode in (0, 3), p.stderr
    return json.loads(p.stdout)


def flags(scatter: Path) -> list[str]:
    return ["--scatter", str(scatter), "--record", str(RECORD), "--spin-up", str(SPIN_UP)]


@pytest.fixture(scope="module")
def serial(files: tuple[Path, Path]) -> dict[str, Any]:
    scene, scatter = files
    return cb.design(cb.Scene.from_file(scene), scatter, record=RECORD, spin_up=SPIN_UP,
                     check=False)


def test_sensitivities_equal_cli(cli: str, files: tuple[Path, Path]) -> None:
    scene, scatter = files
    ref = cli_json(cli, str(scene), "--sensitivities", *flags(scatter))
    got = cb.design(cb.Scene.from_file(scene), str(scatter), sensitivities=True, record=RECORD,
                    spin_up=SPIN_UP)
    assert same(without_seconds(got), without_seconds(ref))
    assert "design" not in got
    # Keyed by the [design] table's parameter names.
    assert sorted(got["sensitivities"]) == ["beam.base_stiffness", "loads.tension"]
    assert got["sensitivities"]["loads.tension"] != 0.0


def test_optimisation_equals_cli(cli: str, files: tuple[Path, Path],
                                 serial: dict[str, Any]) -> None:
    scene, scatter = files
    ref = cli_json(cli, str(scene), *flags(scatter))
    assert same(without_seconds(serial), without_seconds(ref))
    assert sorted(serial["design"]) == ["beam.base_stiffness", "loads.tension"]
    assert serial["iterates"][0]["design"] == serial["scene_design"]["values"]
    assert serial["life_years"] >= serial["scene_design"]["life_years"]


def test_threads_and_processes_equal_serial(files: tuple[Path, Path],
                                            serial: dict[str, Any]) -> None:
    scene, scatter = files
    s = cb.Scene.from_file(scene)
    for ex in (ThreadPoolExecutor(max_workers=2), ProcessPoolExecutor(max_workers=2)):
        with ex:
            got = cb.design(s, scatter, record=RECORD, spin_up=SPIN_UP, executor=ex,
                            check=False)
        assert same(without_seconds(got), without_seconds(serial)), type(ex).__name__


def test_dask_local_cluster_gradient_equals_serial(files: tuple[Path, Path],
                                                   serial: dict[str, Any]) -> None:
    """The issue's must-be-shown: the cells on a Dask LocalCluster (two worker processes) give
    the same gradient (the sensitivities at the scene's design), the same iterates and the same
    design as the serial run, bit for bit."""
    from dask import distributed

    scene, scatter = files
    s = cb.Scene.from_file(scene)
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        sens = cb.design(s, scatter, sensitivities=True, record=RECORD, spin_up=SPIN_UP,
                         executor=client)
        got = cb.design(s, scatter, record=RECORD, spin_up=SPIN_UP, executor=client,
                        check=False)
    assert same(sens["sensitivities"], serial["sensitivities"])
    assert same(without_seconds(got), without_seconds(serial))


def test_progress_per_iteration(files: tuple[Path, Path], serial: dict[str, Any]) -> None:
    scene, scatter = files
    calls: list[tuple[int, int]] = []
    seen: list[dict[str, Any]] = []
    got = cb.design(cb.Scene.from_file(scene), scatter, record=RECORD, spin_up=SPIN_UP,
                    progress=lambda done, total: calls.append((done, total)),
                    on_iterate=seen.append, check=False)
    assert same(without_seconds(got), without_seconds(serial))
    # One call per iterate, out of the table's max_iterations (3), with the iterates' numbers.
    assert calls == [(it["iteration"], 3) for it in got["iterates"]]
    assert same(seen, got["iterates"])


def test_errors_name_the_key(files: tuple[Path, Path]) -> None:
    scene, scatter = files
    s = cb.Scene.from_file(scene)
    with pytest.raises(cb.InvalidArgumentError) as e:
        cb.design(s, scatter, record=-1.0, spin_up=SPIN_UP)
    assert e.value.key == "record"
    with pytest.raises(cb.InvalidArgumentError) as e:
        cb.design(s, scatter, record=RECORD, spin_up=float("nan"))
    assert e.value.key == "spin_up"
    with pytest.raises(cb.InvalidArgumentError) as e:
        cb.design(s, [{"hs": 1.0, "tp": 8.0, "prob": 1.0}], record=RECORD, spin_up=SPIN_UP)
    assert e.value.key == "scatter"
    with pytest.raises(cb.InvalidArgumentError) as e:
        cb.design(s, scatter, record=RECORD, spin_up=SPIN_UP, executor=object())
    assert e.value.key == "executor"
    # A spin-up so long that spin-up + record exceed the scene's step limit: the library refuses
    # the run's length, which it reports under the record's key with the step count and the limit
    # (fatigue_study::with_record, as `chainbeam design --record` does).
    with pytest.raises(cb.InvalidArgumentError) as e:
        cb.design(s, scatter, record=RECORD, spin_up=1e9)
    assert e.value.key == "record"
    assert "time.steps' limit" in str(e.value)
    # No [design] table: nothing to optimise (SceneError naming `design`).
    plain = cb.Scene.from_toml((SCENES / "riser_300m_design.toml").read_text()
                               .split("\n[design]\n")[0])
    with pytest.raises(cb.SceneError) as e:
        cb.design(plain, scatter, record=RECORD, spin_up=SPIN_UP)
    assert e.value.key == "design"
    # A bad [design] value is refused when the scene is built, naming the key.
    bad = (SCENES / "riser_300m_design.toml").read_text().replace("upper = 1.0e9",
                                                                  "upper = 1.0e5")
    with pytest.raises(cb.SceneError) as e:
        cb.Scene.from_toml(bad)
    assert e.value.key is not None and e.value.key.startswith("design.parameter[1]")


def added_parameter_matches_cli(cli: str, tmp_path: Path, table: str, name: str) -> None:
    """The README's riser system (examples/scenes/riser_300m_system_design.toml) with `table`
    (one more `[[design.parameter]]`) appended: the parameter `name` passes through `cb.design`
    and its sensitivity equals the command line's JSON bit for bit (as does the whole JSON but
    its timings), and is not zero, on one cell of 20 s after a 10 s spin-up (the README's
    records)."""
    text = (SCENES / "riser_300m_system_design.toml").read_text()
    scene = tmp_path / "system.toml"
    scene.write_text(text + table)
    scatter = tmp_path / "cells.csv"
    scatter.write_text("hs,tp,probability\n1.44,7.66,1.0\n")
    args = ["--scatter", str(scatter), "--record", "20", "--spin-up", "10"]
    ref = cli_json(cli, str(scene), "--sensitivities", *args)
    got = cb.design(cb.Scene.from_file(scene), str(scatter), sensitivities=True, record=20.0,
                    spin_up=10.0)
    assert same(without_seconds(got), without_seconds(ref))
    assert name in got["sensitivities"]
    assert same(got["sensitivities"][name], ref["sensitivities"][name])
    assert got["sensitivities"][name] != 0.0


def test_vessel_offset_sensitivity_equals_cli(cli: str, tmp_path: Path) -> None:
    """The vessel's mean offset as a design parameter (`vessel.offset`, signed bounds):
    see `added_parameter_matches_cli`."""
    added_parameter_matches_cli(
        cli, tmp_path,
        '\n[[design.parameter]]\nname = "vessel.offset"\nlower = -10.0\nupper = 10.0\n',
        "vessel.offset")


def test_buoyancy_diameter_sensitivity_equals_cli(cli: str, tmp_path: Path) -> None:
    """The buoyancy modules' outer diameter of a named segment as a design parameter
    (`stackup.segment.riser_buoyant_1.buoyancy_diameter`, its gradient by the adjoint):
    see `added_parameter_matches_cli`."""
    name = "stackup.segment.riser_buoyant_1.buoyancy_diameter"
    added_parameter_matches_cli(
        cli, tmp_path, f'\n[[design.parameter]]\nname = "{name}"\nlower = 0.6\nupper = 1.5\n',
        name)
