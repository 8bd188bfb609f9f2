"""The peer: the same riser in MoorDyn v2 (a lumped-mass line with bending stiffness).

Layout (MoorDyn's axes: X along the chain's z, the current's and the waves' direction; Z up):
- the wellhead is a Fixed Rod, vertical, whose top end B is at Z = −301 m; the line's end A is
  attached to it, so the line is cantilevered there (MoorDyn's `CANTILEVERED` end: its first
  segment bends against the rod's axis with the curvature 4/l·sin(φ/2), i.e. the moment
  EI·κ₀ ≈ 2EI/l·φ, the chain's base spring k₁ = 2EI/l);
- the top end B is a Coupled Point held at X = Y = 0 (pinned: no moment), Z = −1 m, moved
  vertically by a tensioner loop in this script so that the line's vertical force at the top
  stays the chain's constant tension T (the chain is inextensible with the tension a constant
  force; MoorDyn's line is extensible, EA of the steel wall, and its top must be free to follow
  the set-down for the tension to stay T);
- the line: n segments, Diam = D_o (buoyancy, drag and added mass on the outer diameter),
  Mass/m = steel + contents, EI, Cd, Ca transverse; no axial drag or added mass (the chain has
  none); g and ρ_w the chain's; the seabed below the rod (no contact);
- the water: WaveKin = 1, the kinematics given node by node by this script (the chain's: the
  current plus the Airy velocity and acceleration at each node's height on the straight riser,
  from the same η(t)), set at the midpoint of each coupling step.

The 1 m between the top node and MoorDyn's mean surface keeps every segment fully submerged
(MoorDyn would wet only part of a segment cut by the surface; the chain's buoyancy and weight
act on the whole pipe). MoorDyn's surface plays no other role: its kinematics are given.
"""

from __future__ import annotations

import math
import os
import tempfile
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from pipe import Riser

FOOT_Z = -301.0  # MoorDyn Z of the wellhead (node 0)
TOP_Z = -1.0  # MoorDyn Z of the top node at rest
DEPTH = 321.0  # MoorDyn's water depth: the seabed lies below the wellhead rod


@dataclass(frozen=True)
class PeerSettings:
    """MoorDyn's integration and the tensioner loop."""

    coupling_step: float = 0.01  # s, one moordyn.Step (and one kinematics update)
    internal_step: float = 2.5e-4  # s, MoorDyn's dtM (RK2; the axial waves need ≲ 1e-3 s)
    axial_damping_ratio: float = 0.8  # MoorDyn's BA as −ζ: damps the line's axial modes only
    tensioner_gain: float = 0.1  # fraction of the tension error corrected per coupling step


def unstretched_length(riser: Riser) -> float:
    """The line's unstretched length so that, straight under the effective tension
    T_e(y) = T − w (L − y), it spans the riser's length: ∫₀ᴸ dy / (1 + T_e(y)/EA)."""
    y = np.linspace(0.0, riser.length, 20001)
    te = riser.top_tension - riser.submerged_weight * (riser.length - y)
    f = 1.0 / (1.0 + te / riser.axial_stiffness)
    return float(np.trapezoid(f, y))


def input_file(riser: Riser, settings: PeerSettings) -> str:
    """MoorDyn v2's input file for the riser."""
    length0 = unstretched_length(riser)
    d = riser.outer_diameter
    return f"""--------------------- MoorDyn Input File ------------------------------------
chainbeam peer comparison: a {riser.length:g} m riser pipe, clamped at the wellhead, pinned at the top
----------------------- LINE TYPES ------------------------------------------
TypeName  Diam      Mass/m        EA            BA/-zeta   EI            Cd     Ca     CdAx  CaAx
(name)    (m)       (kg/m)        (N)           (N-s/-)    (N-m^2)       (-)    (-)    (-)   (-)
riser     {d:.6f}  {riser.structural_mass:.9e}  {riser.axial_stiffness:.9e}  {-settings.axial_damping_ratio:g}  {riser.bending_stiffness:.9e}  {riser.drag_coefficient:g}  {riser.added_mass_coefficient:g}  0.0  0.0
---------------------- ROD TYPES ------------------------------------
TypeName  Diam      Mass/m   Cd    Ca    CdEnd  CaEnd
(name)    (m)       (kg/m)   (-)   (-)   (-)    (-)
wellhead  {d:.6f}  1000.0   0.0   0.0   0.0    0.0
---------------------- RODS ----------------------------------------
ID  RodType   Attachment  Xa   Ya   Za      Xb   Yb   Zb      NumSegs  RodOutputs
(#) (name)    (word/ID)   (m)  (m)  (m)     (m)  (m)  (m)     (-)      (-)
1   wellhead  Fixed       0.0  0.0  {FOOT_Z - 10.0:.3f}  0.0  0.0  {FOOT_Z:.3f}  1        -
---------------------- POINTS ---------------------------------------
ID  Attachment  X    Y    Z       Mass  Volume  CdA  Ca
(#) (word/ID)   (m)  (m)  (m)     (kg)  (m^3)   (m^2) (-)
1   Coupled     0.0  0.0  {TOP_Z:.3f}  0.0   0.0     0.0  0.0
---------------------- LINES ----------------------------------------
ID  LineType  AttachA  AttachB  UnstrLen       NumSegs  LineOutputs
(#) (name)    (ID)     (ID)     (m)            (-)      (-)
1   riser     R1B      1        {length0:.9f}  {riser.segments}  -
---------------------- OPTIONS -----------------------------------------
{settings.internal_step:g}   dtM       MoorDyn's time step (s)
9.80665   g         gravity (the chain's)
{riser.water_density:g}      rho       water density
{DEPTH:g}       WtrDpth   water depth: the seabed below the wellhead rod, no contact
1         WaveKin   external kinematics, node by node, from the driving script
0         Currents  the current is part of the external kinematics
1.0       dtIC      IC generation: convergence check interval (s)
60.0      TmaxIC    IC generation: max time (s)
1         disableOutput  no progress line on standard output
1e-6      threshIC  IC generation: convergence threshold
------------------------- need this line --------------------------------------
"""


@dataclass
class PeerRun:
    """Samples of a MoorDyn run: at the times t, the wellhead moment (signed, bending toward +X
    positive), the top's vertical force on the line and its height, and the nodes' X offsets."""

    t: np.ndarray
    moment: np.ndarray
    top_tension: np.ndarray
    top_z: np.ndarray
    offsets: np.ndarray  # (samples, n + 1): X of nodes 0..n
    moment_from_curvature: np.ndarray  # EI·κ₀ from MoorDyn's own curvature output (unsigned)
    wall_seconds: float


Kinematics = Callable[[int, float], tuple[np.ndarray, np.ndarray]]
"""(step index k, midpoint time t) -> (u, a), each (n + 1,) along X at the chain's nodes 0..n."""


def run(
    riser: Riser,
    settings: PeerSettings,
    duration: float,
    kinematics: Kinematics,
    sample_every: int,
    workdir: str | None = None,
) -> PeerRun:
    """Run MoorDyn for `duration` s from the straight riser at rest (after MoorDyn's own
    static initialisation in still water), the water given by `kinematics`."""
    import cmoordyn
    import moordyn

    n = riser.segments
    tmp = workdir or tempfile.mkdtemp(prefix="chainbeam-moordyn-")
    os.makedirs(tmp, exist_ok=True)
    path = os.path.join(tmp, "riser.txt")
    with open(path, "w", encoding="utf-8") as f:
        f.write(input_file(riser, settings))

    system = moordyn.Create(path)
    x = [0.0, 0.0, TOP_Z]
    v = [0.0, 0.0, 0.0]
    moordyn.Init(system, x, v)
    moordyn.ExternalWaveKinInit(system)
    coords = np.asarray(moordyn.ExternalWaveKinGetCoordinates(system)).reshape(-1, 3)
    nwp = len(coords)
    # Each point MoorDyn asks about takes the chain's node nearest its height; points below the
    # wellhead (the rod's) take still water.
    heights = coords[:, 2] - FOOT_Z
    node_of_point = np.clip(np.rint(heights / riser.segment_length).astype(int), 0, n)
    wet = heights > -0.5 * riser.segment_length
    line = moordyn.GetLine(system, 1)
    ei = riser.bending_stiffness
    k_axial = riser.axial_stiffness / riser.length

    steps = int(round(duration / settings.coupling_step))
    samples = steps // sample_every + 1
    out_t = np.empty(samples)
    out_m = np.empty(samples)
    out_mk = np.empty(samples)
    out_ten = np.empty(samples)
    out_z = np.empty(samples)
    out_x = np.empty((samples, n + 1))

    def sample(j: int, t: float, tension: float) -> None:
        r0 = np.asarray(moordyn.GetLineNodePos(line, 0))
        r1 = np.asarray(moordyn.GetLineNodePos(line, 1))
        dx, dz = r1[0] - r0[0], r1[2] - r0[2]
        phi = math.atan2(dx, dz)  # the first segment's angle from the rod's axis (vertical)
        lstr = math.hypot(dx, dz, r1[1] - r0[1])
        out_t[j] = t
        out_m[j] = ei * 4.0 / lstr * math.sin(phi / 2.0)  # MoorDyn's EI κ₀ (Line.cpp), signed
        out_mk[j] = ei * moordyn.GetLineNodeCurv(line, 0)
        out_ten[j] = tension
        out_z[j] = x[2]
        out_x[j] = [moordyn.GetLineNodePos(line, i)[0] for i in range(n + 1)]

    tension = riser.top_tension
    sample(0, 0.0, tension)
    t = 0.0
    dt = settings.coupling_step
    start = time.perf_counter()
    dz = 0.0
    u = np.zeros((nwp, 3))
    a = np.zeros((nwp, 3))
    for k in range(steps):
        uk, ak = kinematics(k, t + 0.5 * dt)
        u[:, 0] = np.where(wet, uk[node_of_point], 0.0)
        a[:, 0] = np.where(wet, ak[node_of_point], 0.0)
        # moordyn.ExternalWaveKinSet takes (n, 3) lists and flattens them: give them flat.
        cmoordyn.ext_wave_set(system, u.ravel().tolist(), a.ravel().tolist(), t)
        # MoorDyn takes the coupled point's position at t and its velocity over the step.
        v = [0.0, 0.0, dz / dt]
        force = moordyn.Step(system, x, v, t, dt)
        t = (k + 1) * dt
        x = [0.0, 0.0, x[2] + dz]
        # The tensioner: the line's pull on the top point is −F_Z; the next step moves the top
        # by a fraction of the height that would make it T (the line's axial stiffness EA/L).
        tension = -force[2]
        dz = -settings.tensioner_gain * (tension - riser.top_tension) / k_axial
        if (k + 1) % sample_every == 0:
            sample((k + 1) // sample_every, t, tension)
    wall = time.perf_counter() - start
    moordyn.Close(system)
    return PeerRun(out_t, out_m, out_ten, out_z, out_x, out_mk, wall)
