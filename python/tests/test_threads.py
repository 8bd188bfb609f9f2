"""The GIL is released during a computation; Ctrl-C interrupts a long run; a process forked after
a call that used threads computes normally (rayon's global pool would not survive the fork)."""

from __future__ import annotations

import multiprocessing as mp
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

import chainbeam as cb

ROOT = Path(__file__).resolve().parents[2]
RISER = ROOT / "examples" / "scenes" / "riser_5.toml"


def long_scene() -> cb.Scene:
    return cb.Scene.from_file(RISER).replace({"time.steps": 100_000})


def test_python_runs_while_a_simulation_runs() -> None:
    """While one thread simulates, the main thread keeps executing Python code: the call has
    released the GIL (with the GIL held the counter would stay at 0 until the call ends)."""
    scene = long_scene()
    done = threading.Event()
    result: list[cb.Trajectory] = []

    def work() -> None:
        result.append(cb.simulate(scene))
        done.set()

    t = threading.Thread(target=work)
    t.start()
    ticks = 0
    while not done.is_set():
        ticks += 1
        time.sleep(0.001)
    t.join()
    assert ticks > 10
    # And two threads at once compute the same bits as one.
    out: list[cb.Trajectory] = []
    threads = [threading.Thread(target=lambda: out.append(cb.simulate(scene))) for _ in range(2)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    for o in out:
        assert np.array_equal(o.moment.view(np.int64), result[0].moment.view(np.int64))


def test_ctrl_c_interrupts_a_long_run() -> None:
    """SIGINT during a long call raises KeyboardInterrupt within a second (the run alone takes
    several seconds: 20 simulations of 10⁵ steps in one call would be a loop, so one MPC run of
    the MPC scene's 30 s is used)."""
    code = (
        "import chainbeam as cb, signal, sys, time\n"
        # Started from a shell's background job, SIGINT arrives ignored and Python installs no
        # KeyboardInterrupt handler: restore it (the test is of chainbeam, not of the launcher).
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        f"s = cb.Scene.from_file({str(ROOT / 'examples/scenes/mpc_riser.toml')!r})\n"
        "print('start', flush=True)\n"
        "t0 = time.perf_counter()\n"
        "try:\n"
        "    cb.mpc(s, baselines=True)\n"
        "    print('finished', time.perf_counter() - t0, flush=True)\n"
        "except KeyboardInterrupt:\n"
        "    print('interrupted', time.perf_counter() - t0, flush=True)\n"
    )
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    assert p.stdout is not None
    assert p.stdout.readline().strip() == "start"
    time.sleep(1.0)
    sent = time.perf_counter()
    p.send_signal(signal.SIGINT)
    line = p.stdout.readline().split()
    waited = time.perf_counter() - sent
    p.wait(timeout=60)
    assert line[0] == "interrupted", line
    assert waited < 1.0, waited


def optimize_in_child(q: "mp.Queue[float]") -> None:
    r = cb.optimize(cb.Scene.from_file(RISER), method="riccati")
    q.put(r.objective)


def test_fork_after_threads() -> None:
    """The Riccati solver computes its stage Jacobians on the current rayon pool; after such a
    call a forked child runs the same call and gets the same result (had the parent used rayon's
    global pool, the child would wait forever on pool threads that exist only in the parent)."""
    if sys.platform == "win32" or "fork" not in mp.get_all_start_methods():
        raise AssertionError("fork is available on the platforms CI runs (Linux)")
    parent = cb.optimize(cb.Scene.from_file(RISER), method="riccati").objective
    ctx = mp.get_context("fork")
    q: "mp.Queue[float]" = ctx.Queue()
    child = ctx.Process(target=optimize_in_child, args=(q,))
    child.start()
    child.join(timeout=120)
    if child.is_alive():
        os.kill(child.pid or 0, signal.SIGKILL)
        raise AssertionError("the forked child hung")
    assert child.exitcode == 0
    assert q.get(timeout=5) == parent
