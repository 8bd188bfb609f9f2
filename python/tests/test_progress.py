"""Progress of the long calls: a callback receives (done, total) on the calling thread, rising
to total; ``progress=True`` draws a tqdm bar when tqdm is installed and plain lines on standard
error otherwise.

Reference numbers: what the calls are documented to count — fatigue: cells × controllers runs;
mpc: T/interval decisions per closed loop (4 loops with baselines); optimize: iterations out of
max_iters; sweep: cases."""

from __future__ import annotations

import concurrent.futures as cf
from typing import Any

import pytest

import chainbeam as cb
from chainbeam import _progress

from conftest import SCENES, wave_riser_toml

FATIGUE = "\n[fatigue]\nouter_diameter = 0.5334\nwall_thickness = 0.0222\n"


class Log:
    def __init__(self) -> None:
        self.calls: list[tuple[int, int]] = []

    def __call__(self, done: int, total: int) -> None:
        self.calls.append((done, total))

    def check(self, total: int) -> None:
        assert self.calls, "the callback was never called"
        assert self.calls[-1] == (total, total), self.calls
        done = [d for d, _ in self.calls]
        assert done == sorted(done), "done never decreases"
        assert all(t == total for _, t in self.calls if t), self.calls


def test_fatigue_counts_cells_times_controllers() -> None:
    s = cb.Scene.from_toml(wave_riser_toml(tail=FATIGUE))
    scatter = [{"hs": 2.0, "tp": 8.0, "probability": 0.5}, {"hs": 3.0, "tp": 9.0, "probability": 0.5}]
    log = Log()
    cb.fatigue(s, scatter=scatter, controllers="none,constant", spin_up=1.0, record=9.0,
               progress=log)
    log.check(4)
    # On an executor: one task per cell.
    log = Log()
    with cf.ThreadPoolExecutor(2) as ex:
        cb.fatigue(s, scatter=scatter, controllers="none", spin_up=1.0, record=9.0, executor=ex,
                   progress=log)
    log.check(2)


def test_mpc_counts_decisions() -> None:
    s = cb.Scene.from_file(SCENES / "mpc_riser.toml")
    log = Log()
    cb.mpc(s, duration=2.0, interval=0.1, horizon=0.5, progress=log)
    log.check(20)


def test_optimize_counts_iterations() -> None:
    s = cb.Scene.from_file(SCENES / "riser_5.toml")
    log = Log()
    r = cb.optimize(s, method="lbfgs", max_iters=50, progress=log)
    assert log.calls and log.calls[-1][1] == 50
    assert log.calls[-1][0] == r.iterations


def test_sweep_counts_cases() -> None:
    log = Log()
    df = cb.sweep(_double, [{"x": 1}, {"x": 2}, {"x": 3}], progress=log)
    assert list(df["y"]) == [2, 4, 6]
    log.check(3)


def _double(case: dict[str, Any]) -> dict[str, Any]:
    return {"y": 2 * case["x"]}


def test_progress_true_plain_fallback(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setattr(_progress, "_tqdm", lambda: None)
    cb.sweep(_double, [{"x": 1}, {"x": 2}], progress=True)
    err = capsys.readouterr().err
    assert "sweep: 2/2 case (100 %)" in err


def test_progress_true_tqdm(capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("tqdm")
    cb.sweep(_double, [{"x": 1}, {"x": 2}], progress=True)
    err = capsys.readouterr().err
    assert "sweep" in err and "2/2" in err


def test_progress_must_be_bool_or_callable() -> None:
    with pytest.raises(cb.InvalidArgumentError) as e:
        cb.sweep(_double, [{"x": 1}], progress="yes")  # type: ignore[arg-type]
    assert e.value.key == "progress"


def test_a_raising_callback_stops_the_call() -> None:
    def stop(done: int, total: int) -> None:
        if done > 0:
            raise RuntimeError("enough")

    s = cb.Scene.from_file(SCENES / "mpc_riser.toml")
    with pytest.raises(RuntimeError, match="enough"):
        cb.mpc(s, duration=20.0, interval=0.1, horizon=0.5, progress=stop)
