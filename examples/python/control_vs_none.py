"""M₀ with and without control, notebook style (run: python examples/python/control_vs_none.py
[OUT.png]; needs matplotlib).

The thesis's riser (examples/scenes/riser_5.toml: F = 2 N at node 5) over 3 s, a force at the tip
u_0..u_N (|u| ≤ 50 N) optimised for c_sum = Σ M₀(t_k)² (thesis eq. 3.3.4) with a small effort penalty, then
both trajectories simulated and their base bending moments plotted.
"""

# %% Setup
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only, no display needed
import matplotlib.pyplot as plt
import numpy as np

import chainbeam as cb

root = Path(__file__).resolve().parents[2]
out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("m0_control.png")

# %% The scene: 3 s, a per-step control at the tip starting from 0, the summed objective
base = cb.Scene.from_file(root / "examples/scenes/riser_5.toml")
steps = 300
scene = base.replace(
    {
        "time.steps": steps,
        "control.kind": "per-step",
        "control.values": [0.0] * (steps + 1),
        "objective.kind": "sum",
    }
)

# %% Optimise the forces (structured Gauss-Newton with Riccati passes) and simulate with and without them
best = cb.optimize(scene, method="riccati", bound=50.0, effort=1e-3)
print(f"c_sum without control: {cb.gradient(scene)[0]:.4g} N²m²")
print(f"c_sum with control:    {best.objective:.4g} N²m² (converged: {best.converged}, "
      f"{best.termination})")
free = cb.simulate(scene)
controlled = cb.simulate(scene, best.forces)

# %% Plot
fig, (ax_m, ax_u) = plt.subplots(2, 1, sharex=True, figsize=(7, 5))
ax_m.plot(free.t, free.moment, label="no control")
ax_m.plot(controlled.t, controlled.moment, label="optimised control")
ax_m.set_ylabel("M₀ [Nm]")
ax_m.legend()
ax_u.plot(controlled.t, controlled.control, color="C1")
ax_u.set_ylabel("u [N]")
ax_u.set_xlabel("t [s]")
fig.suptitle("riser_5: base bending moment with and without control")
fig.tight_layout()
fig.savefig(out, dpi=120)
print(f"wrote {out} (peak |M₀| {np.abs(free.moment).max():.3g} → "
      f"{np.abs(controlled.moment).max():.3g} Nm)")
