"""Scenes, results and exceptions survive pickling unchanged (they travel to workers)."""

from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np

import chainbeam as cb


def same(a: object, b: object) -> bool:
    if isinstance(a, np.ndarray):
        return isinstance(b, np.ndarray) and np.array_equal(a.view(np.int64), b.view(np.int64))
    return a == b


def test_scene_round_trips(scenes: Path) -> None:
    for name in ("riser_5.toml", "wave_series.toml", "oblique_control.toml"):
        s = cb.Scene.from_file(scenes / name)
        back = pickle.loads(pickle.dumps(s))
        assert back == s and back.to_toml() == s.to_toml()


def test_results_round_trip(scenes: Path) -> None:
    s = cb.Scene.from_file(scenes / "oblique_riser.toml")
    t = cb.simulate(s)
    back = pickle.loads(pickle.dumps(t))
    for f in ("t", "energy", "moment", "positions", "control", "moment_x", "control_x"):
        assert same(getattr(t, f), getattr(back, f)), f
    r = cb.optimize(cb.Scene.from_file(scenes / "riser_5.toml"))
    rb = pickle.loads(pickle.dumps(r))
    assert same(r.controls, rb.controls) and r.objective == rb.objective
    assert r.termination == rb.termination


def test_exceptions_round_trip() -> None:
    try:
        cb.Scene.from_toml("[beam]\npendulums = 0\n")
    except cb.SceneError as e:
        back = pickle.loads(pickle.dumps(e))
        assert type(back) is cb.SceneError
        assert (str(back), back.key, back.kind) == (str(e), e.key, e.kind)
    else:
        raise AssertionError("no SceneError")
