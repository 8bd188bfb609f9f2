"""Hostile inputs from Python never take the interpreter down and every refusal names its cause.

Each case runs in a fresh interpreter (``subprocess``): a crash (SIGABRT on a huge allocation, a
segfault) fails that case instead of killing the test runner. The child prints the exception's
class, ``key`` and ``file`` as JSON; the test checks them and that the child exited normally.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import wave_riser_toml

# The 60 m wave riser of conftest.py; its [pipe] gives the fatigue section (no [fatigue] table).
SCENE = wave_riser_toml()

CHILD = """
import json, sys
import chainbeam as cb
scene = cb.Scene.from_toml({scene!r})
try:
{body}
    out = {{"ok": True}}
except Exception as e:  # every refusal is a ChainbeamError naming its key
    out = {{"ok": False, "cls": type(e).__name__, "key": getattr(e, "key", None),
           "file": getattr(e, "file", None), "msg": str(e),
           "chainbeam": isinstance(e, cb.ChainbeamError)}}
print(json.dumps(out))
"""


def run(body: str, timeout: float = 300.0) -> dict:
    """Runs `body` (indented under a try) in a fresh interpreter; its outcome as a dict."""
    code = CHILD.format(scene=SCENE, body="\n".join("    " + ln for ln in body.splitlines()))
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=timeout)
    assert p.returncode == 0, f"the interpreter died ({p.returncode}): {p.stderr[-2000:]}"
    out: dict = json.loads(p.stdout.strip().splitlines()[-1])
    return out


@pytest.mark.parametrize("body, key", [
    # The automatic component count of a very short peak period (used to abort on 6 GB – 500 TB).
    ("cb.Scene.from_toml(scene.to_toml().replace('tp = 9.0', 'tp = 0.001'))", "loads.waves.tp"),
    ("scene.replace({'loads.waves.tp': 1e-3})", "loads.waves.tp"),
    ("scene.replace({'loads.waves.tp': 5e-324})", "loads.waves.tp"),
])
def test_short_peak_period_is_a_scene_error(body: str, key: str) -> None:
    out = run(body)
    assert not out["ok"] and out["cls"] == "SceneError" and out["key"] == key, out
    assert "components" in out["msg"], out


def test_one_bad_scatter_row_is_an_error_not_a_crash() -> None:
    out = run("cb.fatigue(scene, scatter=[{'hs': 2.0, 'tp': 9.0, 'probability': 0.5},"
              " {'hs': 2.0, 'tp': 1e-3, 'probability': 0.5}], record=10.0)")
    assert not out["ok"] and out["chainbeam"], out
    assert "tp" in out["msg"] and "components" in out["msg"], out


def test_zero_probabilities_are_refused() -> None:
    out = run("cb.fatigue(scene, scatter=[{'hs': 2.0, 'tp': 9.0, 'probability': 0.0}], record=10.0)")
    assert not out["ok"] and out["key"] == "scatter" and "add up to 0" in out["msg"], out


@pytest.mark.parametrize("make, reason", [
    (None, "/dev/zero"),
    ("missing", "cannot read it"),
    ("latin1", "invalid UTF-8"),
    ("sparse", "over the limit"),
    ("directory", "directory"),
    ("duplicate", "named twice"),
])
def test_scatter_files_go_through_the_bounded_reader(tmp_path: Path, make: str | None,
                                                     reason: str) -> None:
    if make is None:
        path = Path("/dev/zero")
    else:
        path = tmp_path / f"{make}.csv"
        if make == "latin1":
            path.write_bytes(b"hs,tp,probability\n1.5,9.0,0.5 # \xe9t\xe9\n")
        elif make == "sparse":
            with open(path, "wb") as f:  # 2 GB of holes: refused by its size, not read
                f.truncate(2 << 30)
        elif make == "directory":
            path.mkdir()
        elif make == "duplicate":
            path.write_text("hs,tp,probability,tp\n1.5,9.0,1.0,12.0\n")
    out = run(f"cb.fatigue(scene, scatter={str(path)!r})", timeout=60.0)
    assert not out["ok"] and out["cls"] == "InvalidArgumentError", out
    assert out["key"] == "scatter" and out["file"] == str(path), out
    assert reason in out["msg"], out


@pytest.mark.parametrize("body, key", [
    ("cb.fatigue(scene, controllers='mpc', iterations=-1)", "iterations"),
    ("cb.fatigue(scene, controllers='mpc', plan_pendulums=-3)", "plan_pendulums"),
    ("cb.fatigue(scene, spin_up='soon')", "spin_up"),
    ("cb.fatigue(scene, controllers='mpc', horizon='long')", "horizon"),
    ("cb.fatigue(scene, controllers='mpc', iterations=2**80)", "iterations"),
    # Past the Python wrapper, the binding names the argument too.
    ("cb._chainbeam._fatigue(scene, None, ['mpc'], {'iterations': -1, 'spin_up': 0.0})",
     "iterations"),
    ("cb._chainbeam._fatigue(scene, None, None, {'spin_up': 'soon'})", "spin_up"),
])
def test_bad_arguments_name_the_argument(body: str, key: str) -> None:
    out = run(body)
    assert not out["ok"] and out["cls"] == "InvalidArgumentError" and out["key"] == key, out
    assert "failed to extract" not in out["msg"] and "Settings" not in out["msg"], out


def test_a_pipe_scene_without_a_fatigue_table_is_assessed() -> None:
    out = run("r = cb.fatigue(scene)\nassert r['damage'] >= 0.0 and r['duration_s'] == 10.0")
    assert out["ok"], out


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="POSIX FIFOs")
def test_a_fifo_without_writer_is_documented_to_wait(tmp_path: Path) -> None:
    """A FIFO keeps its POSIX semantics (docs/cli.md): opening it waits for a writer. With one,
    the file is read through the same bounded reader."""
    fifo = tmp_path / "d.csv"
    os.mkfifo(fifo)
    code = CHILD.format(scene=SCENE, body=f"    print(cb._chainbeam._read_scatter({str(fifo)!r}))")
    child = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    with open(fifo, "w") as w:
        w.write("hs,tp,probability\n1.5,9.0,1.0\n")
    out, _ = child.communicate(timeout=60)
    assert child.returncode == 0 and "(1.5, 9.0, 1.0, None)" in out, out
