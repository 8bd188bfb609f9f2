"""``fatigue``'s result as tables (cells × controllers, long form, cycles with named columns),
its reprs, and the warning when the start of every record is counted by default.

Reference numbers: the result's own dict (the command line's JSON, which test_fatigue.py
compares bit for bit): every table entry is checked to be the dict's value."""

from __future__ import annotations

import pickle
import warnings

import pytest

import chainbeam as cb
from conftest import wave_riser_toml

SCENE = wave_riser_toml(tail="\n[fatigue]\nouter_diameter = 0.5334\nwall_thickness = 0.0222\n")
CELLS = [{"hs": 2.0, "tp": 8.0, "probability": 0.6}, {"hs": 3.0, "tp": 9.0, "probability": 0.4}]


def test_cells_by_controllers() -> None:
    s = cb.Scene.from_toml(SCENE)
    r = cb.fatigue(s, scatter=CELLS, controllers="none,constant", spin_up=1.0, record=9.0)
    assert isinstance(r, dict) and isinstance(r, cb.FatigueResult)
    t = r.to_pandas()
    assert list(t.columns) == ["none", "constant"]
    assert list(t.index.names) == ["hs", "tp"]
    for name in ("none", "constant"):
        for i, cell in enumerate(r["controllers"][name]["cells"]):
            assert t[name].iloc[i] == cell["damage_per_year"]
            assert t.index[i] == (cell["hs"], cell["tp"])
    assert r.to_pandas("damage")["none"].iloc[1] == r["controllers"]["none"]["cells"][1]["damage"]
    with pytest.raises(KeyError, match="damages"):
        r.to_pandas("damages")
    long = r.cells_frame()
    assert len(long) == 4 and list(long["controller"]) == ["none", "none", "constant", "constant"]
    summary = r.summary_frame()
    assert summary.loc["constant", "life_extension"] == r["life_extension"]["constant"]
    assert "none:" in repr(r) and len(repr(r)) < 200
    assert "<table" in r._repr_html_()
    assert pickle.loads(pickle.dumps(r)) == r


def test_plain_cycles_have_named_columns() -> None:
    r = cb.fatigue(cb.Scene.from_toml(SCENE), spin_up=0.0)
    c = r.cycles_frame()
    assert list(c.columns) == ["stress_range_MPa", "mean_MPa", "count"]
    assert c.values.tolist() == r["cycles"]
    assert r.to_pandas()["damage"].iloc[0] == r["damage"]


def test_upper_case_controller_names_are_accepted() -> None:
    s = cb.Scene.from_toml(SCENE)
    assert cb.fatigue(s, controllers="NONE", spin_up=1.0, record=9.0) == cb.fatigue(
        s, controllers="none", spin_up=1.0, record=9.0
    )


def test_counting_the_start_by_default_warns() -> None:
    s = cb.Scene.from_toml(SCENE)
    with pytest.warns(cb.StartUpWarning, match="spin_up"):
        default = cb.fatigue(s)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        explicit = cb.fatigue(s, spin_up=0.0)
    assert default == explicit


def test_mpc_names_are_lower_case_and_long_form() -> None:
    s = cb.Scene.from_toml(SCENE.replace("steps = 200", "steps = 100"))
    loop = cb.mpc(s, baselines=True, interval=0.5, horizon=1.0)
    assert loop.summary["controller"] == "mpc"
    assert [b["controller"] for b in loop.baselines] == ["none", "constant", "pd"]
    long = loop.to_pandas()
    assert len(long) == 4 * 101
    pd_rows = long[long["controller"] == "pd"]
    assert pd_rows["moment"].tolist() == loop.moment_pd.tolist()
    assert pd_rows["wellhead_moment"].tolist() == (loop.moment_pd * s.l1 / 2).tolist()
    assert loop.summary_frame().loc["mpc", "c_sum"] == loop.summary["c_sum"]
    assert len(repr(loop)) < 300
