"""The notebook-facing API, cell by cell (run: python examples/python/notebook_tour.py; needs
numpy and pandas, and xarray for the one cell that uses it). python/tests/test_notebook_tour.py
runs it and checks what it prints.

A riser in a wave scene, simulated and turned into tables: the trajectory as a DataFrame and an
xarray Dataset (units in attrs), the wellhead moment M_w = M₀·l₁/2 beside the thesis's M₀, the
scene's values, a fatigue assessment with two controllers as a cells × controllers table, an MPC
closed loop in long form, and the short reprs a notebook shows.
"""

# %% Setup
from pathlib import Path

import numpy as np
import pandas as pd

import chainbeam as cb

root = Path(__file__).resolve().parents[2]
pd.set_option("display.width", 120)

# %% A 60 m riser in a JONSWAP sea and a current (a small cousin of riser_300m.toml)
scene = cb.Scene.from_toml(
    """
[beam]
pendulums = 6
support = "riser"

[pipe]
length = 60.0
outer_diameter = 0.5334
wall_thickness = 0.0222

[water]
depth = 60.0

[loads]
tension = 1e6
drag = 1e-4

[loads.current]
profile = "uniform"
speed = 0.3

[loads.waves]
spectrum = "jonswap"
hs = 3.0
tp = 9.0
seed = 7

[time]
step = 0.05
steps = 200

[fatigue]
outer_diameter = 0.5334
wall_thickness = 0.0222
scf = 1.2
curve = "F1"
dff = 10.0
"""
)
print("scene:", repr(scene))
print("l1 [m]:", scene.l1)
print("duration [s]:", scene.duration)
print("tension [N]:", scene["loads.tension"])
section = scene.section
assert section is not None
print("second moment of area [m^4]:", f"{section['second_moment']:.6e}")

# %% Simulate and look at it as tables
traj = cb.simulate(scene)
print("trajectory:", repr(traj))
print("repr length:", len(repr(traj)))
df = traj.to_pandas()
print("frame shape:", df.shape)
print("frame columns:", ",".join(df.columns))
print("frame index:", df.index.name)
print("units of wellhead_moment:", df.attrs["units"]["wellhead_moment"])
print(df.head(3).to_string(float_format="{:.4g}".format))
ratio = np.max(np.abs(traj.wellhead_moment)) / np.max(np.abs(traj.moment))
print("max |M_w| / max |M0|:", f"{ratio:.6f}")
nodes = traj.to_pandas(positions=True)
print("positions frame shape:", nodes.shape)
print("positions index:", ",".join(nodes.index.names))
try:
    ds = traj.to_xarray()
    print("xarray dims:", dict(ds.sizes))
    print("xarray positions units:", ds["positions"].attrs["units"])
except ImportError:
    print("xarray dims: (xarray not installed)")

# %% Fatigue with two controllers: a cells x controllers table
scatter = cb.reduced_north_atlantic().head(3)
scatter = scatter.assign(probability=scatter["probability"] / scatter["probability"].sum())
fat = cb.fatigue(scene, scatter=scatter, controllers="none,constant", spin_up=2.0)
print("fatigue:", repr(fat))
table = fat.to_pandas()
print("fatigue table shape:", table.shape)
print("fatigue table columns:", ",".join(table.columns))
print(table.to_string(float_format="{:.4g}".format))
print(fat.summary_frame().to_string(float_format="{:.4g}".format))
plain = cb.fatigue(scene, spin_up=2.0)
cycles = plain.cycles_frame()
print("cycles columns:", ",".join(cycles.columns))
print("cycles counted:", f"{cycles['count'].sum():g}")

# %% MPC in closed loop, in long form
loop = cb.mpc(
    cb.Scene.from_file(root / "examples/scenes/mpc_riser.toml"),
    duration=2.0, baselines=True, horizon=0.5,
)
print("mpc:", repr(loop))
long = loop.to_pandas()
print("mpc long shape:", long.shape)
print("mpc controllers:", ",".join(long["controller"].cat.categories))
print(loop.summary_frame()[["c_sum", "max_abs_control"]].to_string(float_format="{:.4g}".format))
