"""`chainbeam.fatigue` against `chainbeam fatigue`'s JSON (the command line's numbers are the
shortest decimals that read back to the same doubles, so `json.loads` recovers every bit): plain,
over a scatter diagram, with controllers, and with the cells spread over executors; refusals."""

from __future__ import annotations

import json
import subprocess
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pandas as pd
import pytest

import chainbeam as cb
from conftest import wave_riser_toml

# The 60 m riser of conftest.py (waves from 0°), a control at node 3, curve D in seawater with CP.
SCENE = wave_riser_toml(
    tail="""
[control]
node = 3
kind = "constant"
values = [0.0]

[fatigue]
outer_diameter = 0.5334
wall_thickness = 0.0222
"""
)

DIAGRAM = [(1.5, 7.0, 0.5), (3.0, 9.0, 0.3), (5.0, 11.0, 0.2)]


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


def cli_json(cli: str, *args: str) -> Any:
    p = subprocess.run([cli, "--quiet", "fatigue", *args], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout)


@pytest.fixture()
def files(tmp_path: Path) -> tuple[Path, Path]:
    scene = tmp_path / "w.toml"
    scene.write_text(SCENE)
    scatter = tmp_path / "d.csv"
    scatter.write_text("# three cells\nhs,tp,probability\n"
                       + "".join(f"{hs},{tp},{p}\n" for hs, tp, p in DIAGRAM))
    return scene, scatter


def test_plain_equals_cli(cli: str, files: tuple[Path, Path]) -> None:
    scene, _ = files
    ref = cli_json(cli, str(scene))
    got = cb.fatigue(cb.Scene.from_file(scene))
    assert list(got) == ["cycles", "damage", "duration_s", "damage_per_year", "life_years"]
    assert got["damage"] > 0 and len(got["cycles"]) > 0
    assert same(got, ref)


def test_scatter_equals_cli(cli: str, files: tuple[Path, Path]) -> None:
    scene, scatter = files
    ref = cli_json(cli, str(scene), "--scatter", str(scatter))
    s = cb.Scene.from_file(scene)
    got = cb.fatigue(s, scatter=scatter)
    assert same(got, ref)
    # The same cells as a DataFrame and as mappings.
    df = pd.DataFrame(DIAGRAM, columns=["hs", "tp", "probability"])
    assert same(cb.fatigue(s, scatter=df), ref)
    rows = [{"hs": hs, "tp": tp, "probability": p} for hs, tp, p in DIAGRAM]
    assert same(cb.fatigue(s, scatter=rows), ref)


def test_controllers_on_executors_equal_cli(cli: str, files: tuple[Path, Path]) -> None:
    """`none,constant` on three cells: serial, on threads and on 2 processes = the command
    line, bit for bit (each cell is the same deterministic code wherever it runs)."""
    scene, scatter = files
    ref = cli_json(cli, str(scene), "--scatter", str(scatter), "--controller", "none,constant")
    assert list(ref["controllers"]) == ["none", "constant"]
    s = cb.Scene.from_file(scene)
    serial = cb.fatigue(s, scatter=scatter, controllers="none,constant")
    assert same(serial, ref)
    with ThreadPoolExecutor(2) as ex:
        assert same(cb.fatigue(s, scatter=scatter, controllers=["constant"], executor=ex), ref)
    with ProcessPoolExecutor(2) as ex:
        assert same(cb.fatigue(s, scatter=scatter, controllers="none,constant", executor=ex), ref)


def test_refusals(files: tuple[Path, Path]) -> None:
    scene, scatter = files
    s = cb.Scene.from_file(scene)
    no_table = cb.Scene.from_toml(SCENE.split("[fatigue]")[0])
    with pytest.raises(cb.SceneError) as e:
        cb.fatigue(no_table)
    assert e.value.key == "fatigue"
    with pytest.raises(cb.InvalidArgumentError) as a:
        cb.fatigue(s, controllers="none,lqr")
    assert a.value.key == "controllers" and "lqr" in str(a.value)
    with pytest.raises(cb.InvalidArgumentError) as a:
        cb.fatigue(s, scatter=[{"hs": 3.0, "tp": 9.0, "probability": 1.5}])
    assert a.value.key == "scatter" and "probability" in str(a.value)
    with pytest.raises(cb.InvalidArgumentError) as a:
        cb.fatigue(s, scatter=[{"hs": 3.0, "tp": 9.0, "probability": 0.7}] * 2)
    assert a.value.key == "scatter"
