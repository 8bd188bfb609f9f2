"""`chainbeam.fatigue` against `chainbeam fatigue`'s JSON (the command line's numbers are the
shortest decimals that read back to the same doubles, so `json.loads` recovers every bit): plain,
over a scatter diagram, with controllers, and with the cells spread over executors; refusals."""

from __future__ import annotations

import csv
import json
import subprocess
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pandas as pd
import pytest

import chainbeam as cb
from conftest import ROOT, wave_riser_toml

# These calls compare with the command line, whose default --spin-up is 0: leaving spin_up out
# is that default, and its warning (cb.StartUpWarning, test_fatigue_tables.py) is not the point.
# A study counts 3-hour records by default (`record`, `--record`); the tests count the scene's
# own 10 s (its 200 steps of 0.05 s), less any spin-up.
pytestmark = pytest.mark.filterwarnings("ignore::chainbeam.StartUpWarning")

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

# The published diagram (IACS Rec. 34, North Atlantic) as committed for `--scatter`.
NORTH_ATLANTIC_CSV = ROOT / "examples" / "scatter" / "north_atlantic_iacs34.csv"

# Closed-loop settings in the scene (docs/scene-format.md "[mpc]"): every value differs from the
# default, and the interval divides the 10 s record.
MPC_TABLE = """
[mpc]
interval = 0.5
horizon = 1.0
iterations = 2
bound = 2e4
effort = 1e-3
objective = "sum"
"""


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
    # --spin-up 1.5: the first 1.5 s of the record not counted.
    late = cb.fatigue(cb.Scene.from_file(scene), spin_up=1.5)
    assert abs(late["duration_s"] - (got["duration_s"] - 1.5)) < 1e-12
    assert same(late, cli_json(cli, str(scene), "--spin-up", "1.5"))


def test_scatter_equals_cli(cli: str, files: tuple[Path, Path]) -> None:
    scene, scatter = files
    ref = cli_json(cli, str(scene), "--scatter", str(scatter), "--record", "10")
    s = cb.Scene.from_file(scene)
    got = cb.fatigue(s, scatter=scatter, record=10.0)
    assert same(got, ref)
    # The same cells as a DataFrame and as mappings.
    df = pd.DataFrame(DIAGRAM, columns=["hs", "tp", "probability"])
    assert same(cb.fatigue(s, scatter=df, record=10.0), ref)
    rows = [{"hs": hs, "tp": tp, "probability": p} for hs, tp, p in DIAGRAM]
    assert same(cb.fatigue(s, scatter=rows, record=10.0), ref)


def test_controllers_on_executors_equal_cli(cli: str, files: tuple[Path, Path]) -> None:
    """`none,constant` on three cells: serial, on threads and on 2 processes = the command
    line, bit for bit (each cell is the same deterministic code wherever it runs)."""
    scene, scatter = files
    ref = cli_json(cli, str(scene), "--scatter", str(scatter), "--controller", "none,constant",
                   "--record", "10")
    assert list(ref["controllers"]) == ["none", "constant"]
    s = cb.Scene.from_file(scene)
    serial = cb.fatigue(s, scatter=scatter, controllers="none,constant", record=10.0)
    assert same(serial, ref)
    with ThreadPoolExecutor(2) as ex:
        assert same(cb.fatigue(s, scatter=scatter, controllers=["constant"], executor=ex,
                               record=10.0), ref)
    with ProcessPoolExecutor(2) as ex:
        assert same(cb.fatigue(s, scatter=scatter, controllers="none,constant", executor=ex,
                               record=10.0), ref)


def test_reduced_north_atlantic_is_the_committed_csv() -> None:
    """`reduced_north_atlantic()` against examples/scatter/north_atlantic_iacs34.csv read here
    with the csv module (its rows are printed shortest round-trip, so `float` recovers every
    bit): the same 20 cells in the same order, bit for bit, their probabilities adding up to 1."""
    df = cb.reduced_north_atlantic()
    assert list(df.columns) == ["hs", "tp", "probability"]
    assert all(str(t) == "float64" for t in df.dtypes)
    lines = [ln for ln in NORTH_ATLANTIC_CSV.read_text().splitlines()
             if ln.strip() and not ln.startswith("#")]
    rows = list(csv.reader(lines))
    assert rows[0] == ["hs", "tp", "probability"]
    cells = [[float(x) for x in r] for r in rows[1:]]
    assert len(cells) == 20
    assert same(df.values.tolist(), cells)
    assert abs(df["probability"].sum() - 1.0) < 1e-12
    # A fresh DataFrame each call: changing one does not change the next.
    df.loc[0, "hs"] = 99.0
    assert cb.reduced_north_atlantic()["hs"][0] == cells[0][0]


def test_reduced_north_atlantic_equals_cli_scatter(cli: str, files: tuple[Path, Path]) -> None:
    """The DataFrame as `scatter` = `chainbeam fatigue --scatter` of the committed CSV, bit for
    bit: the 20 cells, their damages and the total."""
    scene, _ = files
    ref = cli_json(cli, str(scene), "--scatter", str(NORTH_ATLANTIC_CSV), "--record", "10")
    got = cb.fatigue(cb.Scene.from_file(scene), scatter=cb.reduced_north_atlantic(), record=10.0)
    assert len(got["cells"]) == 20 and got["damage_per_year"] > 0
    assert same(got, ref)


def test_mpc_table_settings_equal_cli(cli: str, tmp_path: Path) -> None:
    """A scene with an `[mpc]` table: `fatigue`'s settings (and every number) equal the command
    line's JSON, which reads the same table; an argument overrides its key as the flag does."""
    path = tmp_path / "m.toml"
    path.write_text(SCENE + MPC_TABLE)
    s = cb.Scene.from_file(path)
    ref = cli_json(cli, str(path), "--controller", "constant,mpc", "--spin-up", "1.0",
                   "--record", "9")
    got = cb.fatigue(s, controllers="constant,mpc", spin_up=1.0, record=9.0)
    assert got["settings"] == {"interval": 0.5, "horizon": 1.0, "iterations": 2,
                               "bound": 2e4, "effort": 1e-3, "spin_up": 1.0,
                               "mpc_objective": "sum", "record": 9.0, "seeds": 1,
                               "observe": "state"}
    assert same(got, ref)
    ref = cli_json(cli, str(path), "--controller", "mpc", "--horizon", "1.5",
                   "--mpc-objective", "power", "--record", "10")
    got = cb.fatigue(s, controllers="mpc", horizon=1.5, mpc_objective="power", record=10.0)
    assert got["settings"]["horizon"] == 1.5 and got["settings"]["bound"] == 2e4
    assert got["settings"]["mpc_objective"] == "power"
    assert same(got, ref)
    # Without the table, the defaults (the command line's).
    plain = cb.Scene.from_toml(SCENE)
    assert cb.fatigue(plain, controllers="none", record=10.0)["settings"] == {
        "interval": 0.1, "horizon": 3.0, "iterations": 1, "bound": 5.0, "effort": 0.01,
        "spin_up": 0.0, "mpc_objective": "power", "record": 10.0, "seeds": 1,
        "observe": "state"}


def test_mpc_table_refusals() -> None:
    """A table value that does not fit the run names `mpc.KEY` (SceneError); the same value as
    an argument names the argument; the table's own checks refuse on reading the scene."""
    bad = cb.Scene.from_toml(SCENE + "\n[mpc]\ninterval = 0.07\n")
    with pytest.raises(cb.SceneError) as e:
        cb.fatigue(bad, controllers="mpc", record=10.0)
    assert e.value.key == "mpc.interval"
    with pytest.raises(cb.InvalidArgumentError) as a:
        cb.fatigue(cb.Scene.from_toml(SCENE), controllers="mpc", interval=0.07, record=10.0)
    assert a.value.key == "interval"
    with pytest.raises(cb.SceneError) as e:
        cb.Scene.from_toml(SCENE + "\n[mpc]\nhorizon = -1.0\n")
    assert e.value.key == "mpc.horizon"
    with pytest.raises(cb.InvalidArgumentError) as a:
        cb.fatigue(cb.Scene.from_toml(SCENE), controllers="mpc", mpc_objective="cubic")
    assert a.value.key == "mpc_objective"
    with pytest.raises(cb.InvalidArgumentError) as a:
        cb.fatigue(cb.Scene.from_toml(SCENE), spin_up=60.0)
    assert a.value.key == "spin_up"


def test_refusals(files: tuple[Path, Path]) -> None:
    scene, scatter = files
    s = cb.Scene.from_file(scene)
    # Without `[fatigue]` a `[pipe]` scene is assessed at the pipe's own section with the table's
    # defaults (curve D, seawater with CP, SCF 1, DFF 1): the same damage as a table that gives
    # only that section.
    no_table = cb.Scene.from_toml(SCENE.split("[fatigue]")[0])
    pipe = no_table["pipe"]
    section = cb.Scene.from_toml(
        SCENE.split("[fatigue]")[0]
        + f"[fatigue]\nouter_diameter = {pipe['outer_diameter']!r}\n"
        + f"wall_thickness = {pipe['wall_thickness']!r}\n"
    )
    assert cb.fatigue(no_table, spin_up=0.0)["damage_per_year"] == cb.fatigue(
        section, spin_up=0.0
    )["damage_per_year"]
    with pytest.raises(cb.InvalidArgumentError) as a:
        cb.fatigue(s, controllers="none,lqr")
    assert a.value.key == "controllers" and "lqr" in str(a.value)
    with pytest.raises(cb.InvalidArgumentError) as a:
        cb.fatigue(s, scatter=[{"hs": 3.0, "tp": 9.0, "probability": 1.5}])
    assert a.value.key == "scatter" and "probability" in str(a.value)
    with pytest.raises(cb.InvalidArgumentError) as a:
        cb.fatigue(s, scatter=[{"hs": 3.0, "tp": 9.0, "probability": 0.7}] * 2)
    assert a.value.key == "scatter"


# The scene with two hot spots along the riser (docs/scene-format.md "[[fatigue.hotspot]]").
HOTSPOTS = """
[[fatigue.hotspot]]
name = "wellhead"
elevation = 0.0
scf = 1.3

[[fatigue.hotspot]]
name = "weld 20 m"
elevation = 20.0
curve = "F1"
"""


def test_seeds_and_hot_spots_on_executors_equal_cli(cli: str, tmp_path: Path) -> None:
    """Two seeds per cell and two hot spots, `none,constant` on two cells: serial and on 2
    processes = `chainbeam fatigue --seeds 2` bit for bit (the executor's cells return every
    seed's and hot spot's Miner sums, combined by the library's own combination); the seeds'
    spread and the hot spots are in the result, and each cell's damage is its seeds' mean."""
    path = tmp_path / "h.toml"
    path.write_text(SCENE + HOTSPOTS)
    scatter = tmp_path / "d.csv"
    scatter.write_text("hs,tp,probability\n2.0,8.0,0.6\n3.0,9.0,0.4\n")
    ref = cli_json(cli, str(path), "--scatter", str(scatter), "--controller", "none,constant",
                   "--seeds", "2", "--record", "5", "--spin-up", "1")
    s = cb.Scene.from_file(path)
    kw: dict[str, Any] = dict(scatter=scatter, controllers="none,constant", seeds=2, record=5.0,
                              spin_up=1.0)
    serial = cb.fatigue(s, **kw)
    assert same(serial, ref)
    with ProcessPoolExecutor(2) as ex:
        assert same(cb.fatigue(s, executor=ex, **kw), ref)
    none = serial["controllers"]["none"]
    assert [h["name"] for h in none["hotspots"]] == ["wellhead", "weld 20 m"]
    assert none["critical"] in ("wellhead", "weld 20 m")
    assert len(none["life_years_seeds"]) == 2
    for cell in none["cells"]:
        a, b = cell["seed_damages"]
        assert a != b and cell["damage"] == (a + b) / 2
        assert cell["damage_min"] == min(a, b) and cell["damage_max"] == max(a, b)


# Two hot spots on the 60 m riser: a weld between joints (F1, SCF 1.3, DFF 3) and the top.
HOTSPOTS_ACTED_ON = """
[[fatigue.hotspot]]
name = "weld"
elevation = 25.0
scf = 1.3
curve = "F1"
dff = 3.0

[[fatigue.hotspot]]
name = "top"
elevation = 60.0
"""


def test_hotspot_equals_cli(cli: str, tmp_path: Path) -> None:
    """`hotspot=` = `chainbeam fatigue --hotspot`, bit for bit: every controller acts on the weld's
    moment, the totals are the weld's `hotspots` entry, and `settings.hotspot` names it; an
    unknown name raises InvalidArgumentError naming `hotspot`."""
    path = tmp_path / "h.toml"
    path.write_text(SCENE + HOTSPOTS_ACTED_ON)
    s = cb.Scene.from_file(path)
    ref = cli_json(cli, str(path), "--controller", "constant,pd", "--hotspot", "weld",
                   "--interval", "0.5", "--bound", "2e4", "--spin-up", "1.0", "--record", "9")
    got = cb.fatigue(s, controllers="constant,pd", hotspot="weld", interval=0.5, bound=2e4,
                     spin_up=1.0, record=9.0)
    assert got["settings"]["hotspot"] == "weld"
    for c in ("none", "constant", "pd"):
        totals = got["controllers"][c]
        assert totals["hotspots"][0]["name"] == "weld"
        assert totals["life_years"] == totals["hotspots"][0]["life_years"]
    assert same(got, ref)
    with pytest.raises(cb.InvalidArgumentError) as a:
        cb.fatigue(s, controllers="constant", hotspot="nope", record=9.0)
    assert a.value.key == "hotspot"


def test_moment_about_is_read_and_checked(tmp_path: Path) -> None:
    """`moment_about=` (`--moment-about`): an unknown name raises InvalidArgumentError naming
    `moment_about`, as does "mean" without a hot spot (MPC plans about the mean at a hot spot
    only); "zero" with a hot spot is the run without the argument, bit for bit, and
    `settings.moment_about` is absent for it (the JSON as before)."""
    path = tmp_path / "h.toml"
    path.write_text(SCENE + HOTSPOTS_ACTED_ON)
    s = cb.Scene.from_file(path)
    for bad in ("median", "Mean"):
        with pytest.raises(cb.InvalidArgumentError) as a:
            cb.fatigue(s, controllers="constant", hotspot="weld", moment_about=bad, record=9.0,
                       spin_up=1.0)
        assert a.value.key == "moment_about"
    with pytest.raises(cb.InvalidArgumentError) as a:
        cb.fatigue(s, controllers="constant", moment_about="mean", record=9.0, spin_up=1.0)
    assert a.value.key == "moment_about"
    kw = dict(controllers="constant", hotspot="weld", interval=0.5, bound=2e4, spin_up=1.0,
              record=9.0)
    zero = cb.fatigue(s, moment_about="zero", **kw)
    plain = cb.fatigue(s, **kw)
    assert "moment_about" not in zero["settings"]
    assert same(zero, plain)
