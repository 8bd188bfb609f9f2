"""The notebook-facing API as examples/python/notebook_tour.py shows it: the script runs, and what
it prints is checked against what the scene and the calls say independently.

Reference numbers: the scene's own values (N = 200 steps, n = 6 pendulums of l₁ = 60/6 = 10 m,
so M_w/M₀ = l₁/2 = 5 exactly), the documented columns of each table, and mpc_riser.toml's step
(h = 0.01 s: 2 s are 201 samples per controller)."""

from __future__ import annotations

import subprocess
import sys

from conftest import ROOT


def run_tour() -> dict[str, str]:
    p = subprocess.run(
        [sys.executable, str(ROOT / "examples" / "python" / "notebook_tour.py")],
        capture_output=True, text=True, timeout=900, cwd=ROOT,
    )
    assert p.returncode == 0, p.stderr
    lines: dict[str, str] = {}
    for line in p.stdout.splitlines():
        key, sep, value = line.partition(": ")
        if sep:
            lines.setdefault(key, value)
    return lines


def test_notebook_tour_prints_what_the_api_promises() -> None:
    out = run_tour()
    assert out["l1 [m]"] == "10.0"
    assert out["duration [s]"] == "10.0"
    assert out["tension [N]"] == "1000000.0"
    assert out["trajectory"].startswith("chainbeam.Trajectory(N=200 steps")
    assert int(out["repr length"]) < 300
    assert out["frame shape"] == "(201, 5)"
    assert out["frame columns"] == "energy,moment,wellhead_moment,control,eta"
    assert out["frame index"] == "t"
    assert out["units of wellhead_moment"].startswith("N m")
    assert out["max |M_w| / max |M0|"] == "5.000000"
    assert out["positions frame shape"] == f"({201 * 6}, 3)"
    assert out["positions index"] == "t,node"
    if "not installed" not in out["xarray dims"]:
        assert out["xarray dims"] == "{'t': 201, 'node': 6, 'axis': 3}"
        assert out["xarray positions units"] == "m"
    assert out["fatigue"].startswith("chainbeam.FatigueResult(3 cell(s); none: ")
    assert out["fatigue table shape"] == "(3, 2)"
    assert out["fatigue table columns"] == "none,constant"
    assert out["cycles columns"] == "stress_range_MPa,mean_MPa,count"
    assert float(out["cycles counted"]) > 0
    assert out["mpc"].startswith("chainbeam.MpcResult(N=200 steps")
    assert out["mpc long shape"] == f"({4 * 201}, 6)"
    assert out["mpc controllers"] == "mpc,none,constant,pd"
