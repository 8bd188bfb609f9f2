"""Two threads simulating at once against one (the target: ≤ 1.3× the wall time of one, since
the extension releases the GIL while it simulates).

    python python/benchmarks/threads.py [STEPS] [REPEATS]

Each repeat times one `simulate` of examples/scenes/riser_5.toml stretched to STEPS steps
(default 10⁵), then two at once on two threads, back to back; it prints the wall-time ratio
two/one of every repeat and their median, and the process CPU time of each (two threads that
really run in parallel take ≈ 2× the CPU in ≈ 1× the wall time). On a machine whose cores are busy
with other work the wall ratio measures the machine, not the GIL: quote it with the load.
"""

from __future__ import annotations

import os
import statistics
import sys
import threading
import time
from pathlib import Path

import chainbeam as cb

ROOT = Path(__file__).resolve().parents[2]


def timed(fn: object, threads: int) -> tuple[float, float]:
    """(wall, process CPU) seconds of `threads` simultaneous calls."""
    ts = [threading.Thread(target=fn) for _ in range(threads)]  # type: ignore[arg-type]
    w0, c0 = time.perf_counter(), time.process_time()
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    return time.perf_counter() - w0, time.process_time() - c0


def main() -> None:
    steps = int(sys.argv[1]) if len(sys.argv) > 1 else 100_000
    repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 7
    scene = cb.Scene.from_file(ROOT / "examples/scenes/riser_5.toml").replace(
        {"time.steps": steps}
    )
    work = lambda: cb.simulate(scene)  # noqa: E731
    work()  # warm-up
    ratios, cpu_ratios = [], []
    for r in range(repeats):
        w1, c1 = timed(work, 1)
        w2, c2 = timed(work, 2)
        ratios.append(w2 / w1)
        cpu_ratios.append(c2 / c1)
        print(f"repeat {r}: one {w1:.3f} s (cpu {c1:.3f}), two {w2:.3f} s (cpu {c2:.3f}), "
              f"wall ratio {w2 / w1:.3f}")
    print(f"cores {os.cpu_count()}, load average {os.getloadavg()[0]:.1f}; "
          f"median wall ratio two/one {statistics.median(ratios):.3f} "
          f"(min {min(ratios):.3f}, max {max(ratios):.3f}); "
          f"median CPU ratio {statistics.median(cpu_ratios):.3f}")


if __name__ == "__main__":
    main()
