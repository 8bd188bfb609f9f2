"""Python's overhead on a long simulation: `chainbeam.simulate` against the library call
`chainbeam::simulate` alone, timed inside the same extension (`_chainbeam._time_library_simulate`:
the same compiled code on the same kind of worker thread, nothing handed to numpy) — the
target: ≤ 5 % at 10⁵ steps.

    python python/benchmarks/overhead.py [STEPS] [REPEATS] [--malloc default|warm|cold]

The two are timed alternately, REPEATS pairs (default 9); it prints the medians (min, max) of
the pairwise ratios Python/library in wall time and in the process's CPU time (the CPU ratio
holds on a busy machine, where the wall times measure the other processes too). Neither side's
timing includes freeing its result (the library's trajectory, Python's arrays): both are
dropped after the clock stops. The Python side adds the call through Python, the worker thread
and the columns handed to numpy (`SceneTrajectory::into_columns`: t and the positions built in
the trajectory's memory, the finiteness check the command line also makes, p, λ, μ freed).

At 10⁵ steps a trajectory is ~50 MB, and whether a call finds that memory already mapped
(reused from the previous call) or fresh from the kernel (a page fault per 4 KiB page, a
sizeable part of the simulation's time) is decided by glibc malloc's heuristics — its dynamic
trim threshold and which free happens to come last — not by the work either side does. So the
allocator's regime is a choice here (Linux with glibc; the script re-runs itself with
GLIBC_TUNABLES set):

  default  glibc as configured: either side may or may not have its memory returned to the
           kernel between calls, by the luck of its free order;
  warm     mmap_threshold = 32 MiB, no trimming: both sides reuse their memory (the cost of
           the work itself);
  cold     mmap_threshold = 128 KiB: every large buffer is fresh memory on both sides (the
           positions' third over q in the planar model is then the bindings' extra cost).
"""

from __future__ import annotations

import os
import statistics
import sys
import time
from pathlib import Path

import chainbeam as cb
from chainbeam import _chainbeam

ROOT = Path(__file__).resolve().parents[2]


MALLOC = {
    "default": None,
    "warm": "glibc.malloc.mmap_threshold=33554432:glibc.malloc.trim_threshold=4294967295",
    "cold": "glibc.malloc.mmap_threshold=131072",
}


def main() -> None:
    args = sys.argv[1:]
    regime = "default"
    if "--malloc" in args:
        i = args.index("--malloc")
        regime = args[i + 1]
        del args[i : i + 2]
        if regime not in MALLOC:
            sys.exit(f"--malloc: expected one of {', '.join(MALLOC)}, got {regime!r}")
    tunables = MALLOC[regime]
    if tunables is not None and os.environ.get("GLIBC_TUNABLES") != tunables:
        env = dict(os.environ, GLIBC_TUNABLES=tunables)
        os.execve(sys.executable, [sys.executable, __file__, *sys.argv[1:]], env)
    steps = int(args[0]) if len(args) > 0 else 100_000
    repeats = int(args[1]) if len(args) > 1 else 9
    scene = cb.Scene.from_file(ROOT / "examples/scenes/riser_5.toml").replace(
        {"time.steps": steps}
    )
    cb.simulate(scene)  # warm-up
    py, lib, ratios, cpu_ratios = [], [], [], []
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        traj = cb.simulate(scene)
        p, pc = time.perf_counter() - t0, time.process_time() - c0
        del traj
        c0 = time.process_time()
        q, kept = _chainbeam._time_library_simulate(scene)
        qc = time.process_time() - c0
        del kept
        py.append(p)
        lib.append(q)
        ratios.append(p / q)
        cpu_ratios.append(pc / qc)
    print(f"{steps} steps, malloc {regime}: wall Python {statistics.median(py) * 1e3:.1f} ms, library "
          f"{statistics.median(lib) * 1e3:.1f} ms (medians of {repeats}); median wall ratio "
          f"{statistics.median(ratios):.4f} (min {min(ratios):.4f}, max {max(ratios):.4f}); "
          f"median process-CPU ratio {statistics.median(cpu_ratios):.4f} "
          f"(min {min(cpu_ratios):.4f}, max {max(cpu_ratios):.4f})")


if __name__ == "__main__":
    main()
