"""Python's overhead on a long simulation: `chainbeam.simulate` against the library call
`chainbeam::simulate` alone, timed inside the same extension (`_chainbeam._time_library_simulate`:
the same compiled code, no copies into numpy) — issue 29: ≤ 5 % at 10⁵ steps.

    python python/benchmarks/overhead.py [STEPS] [REPEATS]

The two are timed alternately, REPEATS pairs (default 9); it prints the medians of the pairwise
ratios Python/library in wall time and in the process's CPU time (the CPU ratio holds on a busy
machine, where the wall times measure the other processes too). The Python side adds a worker thread, the copies
of t, energy, M₀, the positions (N+1)·n·3 and the controls into numpy arrays, and the finiteness
check the command line also makes.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

import chainbeam as cb
from chainbeam import _chainbeam

ROOT = Path(__file__).resolve().parents[2]


def main() -> None:
    steps = int(sys.argv[1]) if len(sys.argv) > 1 else 100_000
    repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 9
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
        q = _chainbeam._time_library_simulate(scene)
        qc = time.process_time() - c0
        py.append(p)
        lib.append(q)
        ratios.append(p / q)
        cpu_ratios.append(pc / qc)
    print(f"{steps} steps: wall Python {statistics.median(py) * 1e3:.1f} ms, library "
          f"{statistics.median(lib) * 1e3:.1f} ms (medians of {repeats}); median wall ratio "
          f"{statistics.median(ratios):.4f} (min {min(ratios):.4f}, max {max(ratios):.4f}); "
          f"median process-CPU ratio {statistics.median(cpu_ratios):.4f} "
          f"(min {min(cpu_ratios):.4f}, max {max(cpu_ratios):.4f})")


if __name__ == "__main__":
    main()
