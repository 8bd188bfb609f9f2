"""`scripts/headline --merge`: the headline's long runs go in parts over disjoint cells of the
diagram, and the merge recombines them into what one call over all the cells gives. The reference
is chainbeam's own JSON of that one call (the command line computes its totals in Rust): the merge
of two calls over the cells {0} and {1, 2} must equal the call over {0, 1, 2}, every number to
1e-12 relative (the sums are taken in another order) and every key the same; so must parts over
disjoint seeds, and parts that ran other controllers over the same cells and seeds; the refusals
say what differs."""

from __future__ import annotations

import json
import subprocess
from importlib.machinery import SourceFileLoader
from importlib.util import module_from_spec, spec_from_loader
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from conftest import ROOT
from test_fatigue import SCENE as FATIGUE_SCENE

# The harness is a script without a .py suffix: loaded by path.
_loader = SourceFileLoader("headline", str(ROOT / "scripts" / "headline"))
_spec = spec_from_loader("headline", _loader)
assert _spec is not None
headline = module_from_spec(_spec)
_loader.exec_module(headline)

# test_fatigue.py's scene (the 60 m riser of conftest.py with a control at node 3, curve D in
# seawater with CP) with two hot spots: the merge recombines each hot spot's damage and names the
# critical one.
SCENE = FATIGUE_SCENE + """
[[fatigue.hotspot]]
name = "low"
elevation = 5.0

[[fatigue.hotspot]]
name = "mid"
elevation = 30.0
"""

def scene_text(seed: int) -> str:
    """SCENE with its waves' seed replaced (a part over other seeds runs such a scene)."""
    assert SCENE.count("seed = 7\n") == 1
    return SCENE.replace("seed = 7\n", f"seed = {seed}\n")


DIAGRAM = [(1.5, 7.0, 0.5), (3.0, 9.0, 0.3), (5.0, 11.0, 0.2)]


def close(a: Any, b: Any, path: str = "") -> None:
    """Equal structures, floats to 1e-12 relative."""
    if isinstance(a, dict):
        assert list(a) == list(b), (path, list(a), list(b))
        for k in a:
            close(a[k], b[k], f"{path}/{k}")
    elif isinstance(a, list):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            close(x, y, f"{path}[{i}]")
    elif isinstance(a, float) or isinstance(b, float):
        assert abs(a - b) <= 1e-12 * max(abs(a), abs(b)), (path, a, b)
    else:
        assert a == b, (path, a, b)


def study(cli: str, tmp: Path, rows: list[int], seeds: int = 2, seed: int = 7) -> Any:
    scene = tmp / "w.toml"
    scene.write_text(scene_text(seed))
    scatter = tmp / f"cells_{'_'.join(map(str, rows))}.csv"
    scatter.write_text("hs,tp,probability\n"
                       + "".join("{},{},{}\n".format(*DIAGRAM[i]) for i in rows))
    p = subprocess.run(
        [cli, "--quiet", "fatigue", str(scene), "--scatter", str(scatter), "--controller",
         "none,constant", "--seeds", str(seeds), "--record", "8", "--spin-up", "2"],
        capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout)


def test_merge_of_parts_equals_one_call(cli: str, tmp_path: Path) -> None:
    whole = study(cli, tmp_path, [0, 1, 2])
    parts = [study(cli, tmp_path, [0]), study(cli, tmp_path, [2, 1])]
    merged, rows = headline.merge_reports(parts, [[0], [2, 1]], "test")
    assert rows == [0, 1, 2]
    # The check means something: the parts' own totals differ from the whole's.
    assert parts[0]["controllers"]["none"]["damage_per_year"] < (
        whole["controllers"]["none"]["damage_per_year"])
    assert len(whole["controllers"]["none"]["hotspots"]) == 2
    assert "life_years_seeds" in whole["controllers"]["constant"]
    close(merged, whole)


def test_merge_refuses_what_is_not_one_diagram(cli: str, tmp_path: Path) -> None:
    one, other = study(cli, tmp_path, [0]), study(cli, tmp_path, [1])
    with pytest.raises(SystemExit, match="share cells"):
        headline.merge_reports([one, one], [[0], [0]], "test")
    with pytest.raises(SystemExit, match="different settings or seeds"):
        headline.merge_reports([one, study(cli, tmp_path, [1], seeds=3)], [[0], [1]], "test")
    merged, _ = headline.merge_reports([one, other], [[0], [1]], "test")
    assert merged["controllers"]["none"]["damage_per_year"] == pytest.approx(
        one["controllers"]["none"]["damage_per_year"]
        + other["controllers"]["none"]["damage_per_year"], rel=1e-15)


def test_merge_writes_no_output_on_its_inputs(tmp_path: Path) -> None:
    part = tmp_path / "part"
    part.mkdir()
    (part / "scene.toml").write_text("# a part\n")
    (part / "none.json").write_text("{}")
    before = {f.name: f.read_text() for f in part.iterdir()}
    args = SimpleNamespace(merge=[str(part)], out=str(part), scatter="", forecast_error=None)
    with pytest.raises(SystemExit, match="is one of the parts"):
        headline.merge(args)
    assert {f.name: f.read_text() for f in part.iterdir()} == before
    args = SimpleNamespace(merge=[str(tmp_path)], out=str(tmp_path / "out"), scatter="",
                           forecast_error=None)
    with pytest.raises(SystemExit, match="not an output of scripts/headline"):
        headline.merge(args)


def seed_part(report: Any, rows: list[int], seed: int, keep: set[int] | None = None) -> Any:
    """A part as the merge loads it from a directory (load_part): its seeds from its JSON or its
    scene, its report restricted to the rows `keep`."""
    if keep is not None:
        report, rows = headline.restrict(report, rows, keep, "test")
    return {"scene": scene_text(seed), "reports": {"test": report}, "rows": {"test": rows},
            "seeds": headline.part_seeds(report, scene_text(seed), "part")}


def test_merge_over_seeds_equals_one_call(cli: str, tmp_path: Path) -> None:
    """Seed 7 alone over the three cells, and seeds 8, 9 in two calls over disjoint cells, merged:
    the call over the three cells with seeds 7, 8, 9 (each seed's record is the same whichever
    call runs it: the seed is the scene's `[loads.waves] seed`, s..s+K−1)."""
    whole = study(cli, tmp_path, [0, 1, 2], seeds=3)
    parts = [seed_part(study(cli, tmp_path, [0, 1, 2], seeds=1), [0, 1, 2], 7),
             seed_part(study(cli, tmp_path, [0], seed=8), [0], 8),
             seed_part(study(cli, tmp_path, [2, 1], seed=8), [2, 1], 8)]
    assert [p["seeds"] for p in parts] == [[7], [8, 9], [8, 9]]
    merged, rows, seeds = headline.merge_parts(parts, ["test"])
    assert (rows, seeds) == ([0, 1, 2], [7, 8, 9])
    assert whole["seeds"] == [7, 8, 9]
    # The check means something: seed 7's own totals are not the three seeds'.
    seven = parts[0]["reports"]["test"]["controllers"]["constant"]["damage_per_year"]
    assert abs(seven / whole["controllers"]["constant"]["damage_per_year"] - 1) > 1e-3
    close(merged["test"], whole)


def test_merge_of_some_cells_of_a_part(cli: str, tmp_path: Path) -> None:
    """`--cells`: seed 7 run over the three cells, restricted to rows 1, 2, and seed 8 over rows
    1, 2, merged: the call over rows 1, 2 with seeds 7, 8, but for the hot spots (not given per
    cell: dropped, the acted-on moment's damage is each cell's own)."""
    whole = study(cli, tmp_path, [1, 2], seeds=2)
    for c in whole["controllers"].values():
        del c["hotspots"], c["critical"]
    parts = [seed_part(study(cli, tmp_path, [0, 1, 2], seeds=1), [0, 1, 2], 7, keep={1, 2}),
             seed_part(study(cli, tmp_path, [1, 2], seeds=1, seed=8), [1, 2], 8)]
    merged, rows, seeds = headline.merge_parts(parts, ["test"])
    assert (rows, seeds) == ([1, 2], [7, 8])
    close(merged["test"], whole)


def test_merge_over_seeds_refuses_what_no_call_runs(cli: str, tmp_path: Path) -> None:
    seven = seed_part(study(cli, tmp_path, [0, 1], seeds=1), [0, 1], 7)
    nine = seed_part(study(cli, tmp_path, [0, 1], seeds=1, seed=9), [0, 1], 9)
    with pytest.raises(SystemExit, match="not s, s"):
        headline.merge_parts([seven, nine], ["test"])
    eight = seed_part(study(cli, tmp_path, [1], seeds=1, seed=8), [1], 8)
    with pytest.raises(SystemExit, match="cover the rows"):
        headline.merge_parts([seven, eight], ["test"])
    both = seed_part(study(cli, tmp_path, [0, 1], seeds=2), [0, 1], 7)
    with pytest.raises(SystemExit, match="overlap"):
        headline.merge_parts([seven, both], ["test"])


def call_dir(cli: str, tmp: Path, name: str, rows: list[int], commands: list[str],
             cpu: dict[str, float], flags: dict[str, list[str]] | None = None) -> str:
    """A directory as one `scripts/headline` call leaves it: the scene, one JSON per command
    (`chainbeam fatigue --controller C`, which also runs no control), and cpu.json (the CPU
    seconds given: the merge's arithmetic on them is what is checked, not a timing). `flags`:
    further flags per command, keyed by the JSON's name (`pd_mean`: the PD law's command
    with `--moment-about mean`, as the harness names it)."""
    d = tmp / name
    d.mkdir()
    (d / "scene.toml").write_text(scene_text(7))
    scatter = d / "cells.csv"
    scatter.write_text("hs,tp,probability\n"
                       + "".join("{},{},{}\n".format(*DIAGRAM[i]) for i in rows))
    for c in commands:
        p = subprocess.run(
            [cli, "--quiet", "fatigue", str(d / "scene.toml"), "--scatter", str(scatter),
             "--controller", c.partition("_")[0], "--seeds", "2", "--record", "8",
             "--spin-up", "2", "--output", str(d / f"{c}.json"), *(flags or {}).get(c, [])],
            capture_output=True, text=True)
        assert p.returncode == 0, p.stderr
    scatter.unlink()
    (d / "cpu.json").write_text(json.dumps({"cpu": cpu, "simulated": 0.0}))
    return str(d)


def merge_dirs(tmp: Path, dirs: list[str], out: str) -> Path:
    scatter = tmp / "diagram.csv"
    scatter.write_text("hs,tp,probability\n" + "".join("{},{},{}\n".format(*r) for r in DIAGRAM))
    headline.merge(SimpleNamespace(merge=dirs, out=str(tmp / out), scatter=str(scatter),
                                   forecast_error=None, cells="all"))
    return tmp / out


def test_merge_over_controllers_equals_one_call(cli: str, tmp_path: Path) -> None:
    """The constant thrust run in two calls over disjoint cells and PD in a third call over all
    three, merged: one call's JSON of none, constant and PD over the three cells (each command's
    JSON as chainbeam writes it for the three cells, to 1e-12), and each controller's own CPU
    (its parts' CPU less their `none`'s) in the table and in cpu.json."""
    whole = call_dir(cli, tmp_path, "whole", [0, 1, 2], ["none", "constant", "pd"],
                     {"none": 1.0, "constant": 2.0, "pd": 3.0})
    dirs = [call_dir(cli, tmp_path, "c0", [0], ["none", "constant"],
                     {"none": 1.0, "constant": 5.0}),
            call_dir(cli, tmp_path, "c21", [2, 1], ["none", "constant"],
                     {"none": 2.0, "constant": 4.0}),
            call_dir(cli, tmp_path, "pd", [0, 1, 2], ["none", "pd"], {"none": 4.0, "pd": 10.0})]
    out = merge_dirs(tmp_path, dirs, "out")
    for c in ["none", "constant", "pd"]:
        close(json.loads((out / f"{c}.json").read_text()),
              json.loads((Path(whole) / f"{c}.json").read_text()))
    # Own CPU: constant (5 − 1) + (4 − 2) = 6, PD 10 − 4 = 6; no control the first group's 3.
    assert json.loads((out / "cpu.json").read_text())["cpu"] == {
        "none": 3.0, "constant": 9.0, "pd": 9.0}
    table = (out / "headline.md").read_text()
    assert "| constant | — |" in table and "| pd | — |" in table
    assert [l.split("|")[8].strip() for l in table.splitlines()
            if l.startswith(("| none |", "| constant |", "| pd |"))] == ["3.0", "6.0", "6.0"]


def test_merge_over_controllers_refuses_other_records(cli: str, tmp_path: Path) -> None:
    """Controllers join only over the same records: the same cells and seeds, no control's
    damages equal, and each command in one kind of part."""
    cpu = {"none": 1.0, "constant": 2.0, "pd": 3.0}
    constant = call_dir(cli, tmp_path, "c", [0, 1], ["none", "constant"], cpu)
    pd_one = call_dir(cli, tmp_path, "p1", [1], ["none", "pd"], cpu)
    with pytest.raises(SystemExit, match="over the same cells"):
        merge_dirs(tmp_path, [constant, pd_one], "o1")
    both = call_dir(cli, tmp_path, "cp", [0, 1], ["none", "constant", "pd"], cpu)
    with pytest.raises(SystemExit, match="in parts of two kinds"):
        merge_dirs(tmp_path, [constant, both], "o2")
    pd_two = call_dir(cli, tmp_path, "p2", [0, 1], ["none", "pd"], cpu)
    merge_dirs(tmp_path, [constant, pd_two], "o3")
    none = json.loads((Path(pd_two) / "none.json").read_text())
    none["controllers"]["none"]["cells"][1]["seed_damages"][0] *= 1.01
    (Path(pd_two) / "none.json").write_text(json.dumps(none))
    with pytest.raises(SystemExit, match="not the same records"):
        merge_dirs(tmp_path, [constant, pd_two], "o4")
    # A refused merge writes nothing.
    assert not any((tmp_path / o).exists() for o in ("o1", "o2", "o4"))


def test_merge_joins_the_pd_law_about_the_mean(cli: str, tmp_path: Path) -> None:
    """The PD law about zero and about its moment's running mean (`--moment-about mean`, which the
    harness writes as pd_mean.json) in two calls over the same cells and hot spot: one table with
    a row for each, the second labelled "about mean", each JSON as its call wrote it; the two
    laws decide differently (their damages differ)."""
    hot = ["--hotspot", "mid"]
    zero = call_dir(cli, tmp_path, "zero", [0, 1, 2], ["none", "pd"], {"none": 1.0, "pd": 2.0},
                    {"none": hot, "pd": hot})
    mean = call_dir(cli, tmp_path, "mean", [0, 1, 2], ["none", "pd_mean"],
                    {"none": 1.0, "pd_mean": 3.0},
                    {"none": hot, "pd_mean": hot + ["--moment-about", "mean"]})
    out = merge_dirs(tmp_path, [zero, mean], "out")
    for d, c in [(zero, "pd"), (mean, "pd_mean")]:
        close(json.loads((out / f"{c}.json").read_text()),
              json.loads((Path(d) / f"{c}.json").read_text()))
    about = json.loads((out / "pd_mean.json").read_text())
    assert about["settings"]["moment_about"] == "mean"
    plain = json.loads((out / "pd.json").read_text())
    assert plain["controllers"]["pd"]["damage_per_year"] != \
        about["controllers"]["pd"]["damage_per_year"]
    table = (out / "headline.md").read_text()
    rows = [l for l in table.splitlines() if l.startswith("| pd |")]
    assert [r.split("|")[2].strip() for r in rows] == ["—", "—, about mean"], rows
