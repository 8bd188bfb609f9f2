"""Ctrl-C stops the Rust work, not only the wait: after a KeyboardInterrupt the process uses
< 1 s of CPU (resource.getrusage) while the abandoned computation would have run for seconds
more.

Each case runs in a subprocess that starts a long call, sends itself SIGINT after the call has
run for 0.5 s, catches the KeyboardInterrupt, then sleeps: the CPU time of the process during
the sleep is the abandoned work's (the interpreter is idle). The reference: the same call's
CPU time measured for a shorter run in the same subprocess, scaled to the full length, which
shows how much work the interrupt saved (the test requires ≥ 3 s of it)."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

from conftest import SCENES, wave_riser_toml

FATIGUE = "\n[fatigue]\nouter_diameter = 0.5334\nwall_thickness = 0.0222\n"

SCRIPT = textwrap.dedent(
    """
    import json, os, resource, signal, sys, threading, time
    import chainbeam as cb

    # A child of a shell's background job starts with SIGINT ignored, and the interpreter then
    # installs no KeyboardInterrupt handler: restore it, so the test does not depend on how the
    # suite was launched.
    signal.signal(signal.SIGINT, signal.default_int_handler)

    def cpu():
        r = resource.getrusage(resource.RUSAGE_SELF)
        return r.ru_utime + r.ru_stime

    scene = cb.Scene.from_toml(sys.argv[1])
    call = sys.argv[2]
    short, full = float(sys.argv[3]), float(sys.argv[4])

    def run(duration):
        if call == "fatigue":
            cb.fatigue(scene, controllers="none,pd", spin_up=1.0, record=duration - 1.0)
        elif call == "fatigue-executor":
            import concurrent.futures as cf
            cells = [{"hs": 2.0 + 0.1 * i, "tp": 9.0, "probability": 1 / 8} for i in range(8)]
            with cf.ThreadPoolExecutor(1) as ex:
                try:
                    cb.fatigue(scene, scatter=cells, controllers="none", spin_up=1.0,
                               record=duration - 1.0, executor=ex)
                finally:
                    ex.shutdown(wait=True, cancel_futures=True)
        else:
            cb.simulate(scene, duration=duration)

    t0 = cpu(); run(short); per_second = (cpu() - t0) / short
    threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
    start = cpu()
    try:
        run(full)
        print(json.dumps({"finished": True})); sys.exit(0)
    except KeyboardInterrupt:
        pass
    at_interrupt = cpu()
    time.sleep(3.0)
    print(json.dumps({"finished": False, "after": cpu() - at_interrupt,
                      "before": at_interrupt - start, "expected": per_second * full}))
    """
)


def interrupted(call: str, toml: str, short: float, full: float) -> dict[str, float]:
    p = subprocess.run(
        [sys.executable, "-c", SCRIPT, toml, call, str(short), str(full)],
        capture_output=True, text=True, timeout=600,
    )
    assert p.returncode == 0, p.stderr
    out: dict[str, float] = json.loads(p.stdout.strip().splitlines()[-1])
    assert not out["finished"], "the call ended before the interrupt: make it longer"
    return out


def check(out: dict[str, float]) -> None:
    left = out["expected"] - out["before"]
    assert left >= 3.0, f"the interrupt saved too little work to show anything: {out}"
    assert out["after"] < 1.0, f"the abandoned work went on: {out}"


def test_interrupted_fatigue_stops_its_work() -> None:
    """fatigue with controllers (no control, a tuned PD law) on the 60 m wave riser."""
    check(interrupted("fatigue", wave_riser_toml(tail=FATIGUE), 10.0, 4000.0))


def test_interrupted_simulate_stops_its_work() -> None:
    riser = (SCENES / "riser_5.toml").read_text()
    check(interrupted("simulate", riser, 20.0, 30000.0))


def test_interrupted_fatigue_on_a_thread_pool_cancels_its_tasks() -> None:
    """The executor's thread receives no signal: the wait's interrupt cancels the tasks not
    started and the running computation (``_cancel_running``). Eight cells of 20 000 s: about
    6 s of CPU on an idle 2-core machine of Nov 2026 (2 000 s ended before an interrupt at 1 s
    there)."""
    check(interrupted("fatigue-executor", wave_riser_toml(tail=FATIGUE), 10.0, 20000.0))
