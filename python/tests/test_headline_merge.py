"""`scripts/headline --merge`: the headline's long runs go in parts over disjoint cells of the
diagram, and the merge recombines them into what one call over all the cells gives. The reference
is chainbeam's own JSON of that one call (the command line computes its totals in Rust): the merge
of two calls over the cells {0} and {1, 2} must equal the call over {0, 1, 2}, every number to
1e-12 relative (the sums are taken in another order) and every key the same; the refusals say
what differs."""

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


def study(cli: str, tmp: Path, rows: list[int], seeds: int = 2) -> Any:
    scene = tmp / "w.toml"
    scene.write_text(SCENE)
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
