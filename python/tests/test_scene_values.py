"""Scene values from Python: ``scene["dotted.key"]``, the derived quantities (l₁, n, T, the
pipe's section), ``replace`` merging nested tables (never dropping a key silently), and
``duration=`` in seconds where a call takes ``time.steps``.

Reference numbers: the scene files themselves (riser_5.toml, riser_300m.toml) and the closed
forms of the pipe's section quoted in docs/scene-format.md "[pipe]" (A_s = π/4 (D_o² − D_i²),
I = π/64 (D_o⁴ − D_i⁴)), computed here from the file's D_o and t."""

from __future__ import annotations

import math

import numpy as np
import pytest

import chainbeam as cb

from conftest import SCENES


def test_getitem_reads_the_scene_file_values() -> None:
    s = cb.Scene.from_file(SCENES / "riser_5.toml")
    assert s["loads.drag"] == 0.0
    assert s["beam.base_stiffness"] == 2000.0
    assert s["loads.point[0].force"] == 2.0
    assert s["loads.point[0].node"] == 5
    assert s["time"] == {"step": 0.01, "steps": 10}
    assert "loads.point" in s and "loads.waves" not in s
    with pytest.raises(KeyError) as e:
        s["loads.tensoin"]
    assert "loads.tensoin" in str(e.value) and "drag" in str(e.value)
    with pytest.raises(KeyError, match="out of range"):
        s["loads.point[3].force"]


def test_derived_quantities() -> None:
    s = cb.Scene.from_file(SCENES / "riser_300m.toml")
    assert s.n == 80
    assert s.l1 == 300.0 / 80 == s.lengths[0]
    assert math.isclose(s.length, 300.0, rel_tol=1e-12)
    assert s.duration == s.steps * s.step == 600.0
    assert s["loads.tension"] == 1.228e6
    sec = s.section
    assert sec is not None
    do, t = 0.5334, 0.022225
    di = do - 2 * t
    assert sec["outer_diameter"] == do and sec["wall_thickness"] == t
    assert math.isclose(sec["steel_area"], math.pi / 4 * (do**2 - di**2), rel_tol=1e-12)
    assert math.isclose(sec["second_moment"], math.pi / 64 * (do**4 - di**4), rel_tol=1e-12)
    # The file's axial_weight is the pipe's submerged weight to its 5 digits (its comment).
    assert math.isclose(sec["submerged_weight"], s["loads.axial_weight"], rel_tol=1e-4)
    assert s.has_fatigue and s.has_waves
    assert s["fatigue"] == {
        "outer_diameter": do, "wall_thickness": t, "scf": 1.2, "curve": "F1",
        "environment": "seawater-cp", "reference_thickness": 0.025, "dff": 10.0,
    }
    assert cb.Scene.from_file(SCENES / "riser_5.toml").section is None
    assert "duration=600 s" in repr(s)


def test_replace_merges_a_nested_table() -> None:
    s = cb.Scene.from_file(SCENES / "riser_5.toml")
    merged = s.replace({"loads": {"drag": 1.0}})
    assert merged["loads.drag"] == 1.0
    # The point load (and every other key of [loads]) is kept, as with a dotted key.
    assert merged["loads.point"] == s["loads.point"]
    assert merged == s.replace({"loads.drag": 1.0})
    deep = s.replace({"loads": {"point": [{"node": 5, "force": 3.0}]}, "time": {"steps": 20}})
    assert deep["loads.point[0].force"] == 3.0 and deep.steps == 20 and deep.step == s.step


def test_replace_refuses_a_dict_for_a_value_and_a_value_for_a_table() -> None:
    s = cb.Scene.from_file(SCENES / "riser_5.toml")
    with pytest.raises(cb.SceneError) as e:
        s.replace({"loads.drag": {"x": 1.0}})
    assert e.value.key == "loads.drag" and "cannot be merged" in str(e.value)
    with pytest.raises(cb.SceneError) as e:
        s.replace({"loads": 1.0})
    assert e.value.key == "loads" and "is a table" in str(e.value)
    with pytest.raises(cb.SceneError) as e:
        s.replace({"loads": {"drag": 1.0, "dragg": 2.0}})
    assert "dragg" in str(e.value)


def test_duration_in_seconds() -> None:
    s = cb.Scene.from_file(SCENES / "riser_5.toml")
    t = cb.simulate(s, duration=0.25)
    assert t.t.shape == (26,) and t.t[-1] == 25 * 0.01
    np.testing.assert_array_equal(
        t.moment, cb.simulate(s.replace({"time.steps": 25})).moment
    )
    with pytest.raises(cb.InvalidArgumentError) as e:
        cb.simulate(s, duration=0.255)
    assert e.value.key == "duration" and "whole number of steps" in str(e.value)
    with pytest.raises(cb.InvalidArgumentError):
        cb.gradient(s, duration=-1.0)


def test_wellhead_moment_is_m0_l1_over_2() -> None:
    """M_w = M₀·l₁/2 (docs/conventions.md "The wellhead moment M_w"): 0.5·M₀ at l₁ = 1 m."""
    s = cb.Scene.from_file(SCENES / "riser_5.toml")
    t = cb.simulate(s)
    np.testing.assert_array_equal(t.wellhead_moment, t.moment * 0.5)
    assert t.l1 == 1.0


def test_trajectory_over_the_memory_budget_is_the_documented_error() -> None:
    s = cb.Scene.from_file(SCENES / "riser_5.toml").replace({"time.steps": 10_000_000, "beam.pendulums": 40})
    with pytest.raises(cb.TrajectoryTooLargeError) as e:
        cb.simulate(s)
    assert e.value.key == "time.steps" and isinstance(e.value, MemoryError)
    with pytest.raises(cb.TrajectoryTooLargeError):
        cb.gradient(s)
