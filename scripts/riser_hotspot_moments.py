#!/usr/bin/env python3
"""The hot spots' moments of a stack-up scene from `chainbeam simulate`'s node positions.

    chainbeam simulate SCENE.toml --every K -o run.csv
    python3 scripts/riser_hotspot_moments.py SCENE.toml run.csv T0

For each `[[fatigue.hotspot]]` of SCENE: the joint torques k_j θ_j (θ_j the signed angle between
pendulums j−1 and j, from the planar node positions (y, z); k_j the stack-up's joint spring: the
two half-pendulums in series 1/(l_{j−1}/(2EI_{j−1}) + l_j/(2EI_j)), 2EI₁/l₁ at a clamped foot,
a flex joint's stiffness where one sits, the tip's spring 2EIₙ/lₙ or the upper flex joint's),
interpolated linearly in elevation between the two joints around the hot spot (the joint's own
when it lies on one), and their mean and standard deviation over t ≥ T0. This is the moment
`chainbeam fatigue` assesses (src/hotspots.rs), recomputed independently from the positions;
docs/riser-system.md "Convergence in n and h" used it. Needs numpy; planar scenes only.
"""
import math
import sys
import tomllib

import numpy as np


def main():
    scene_path, csv_path, t0 = sys.argv[1], sys.argv[2], float(sys.argv[3])
    scene = tomllib.load(open(scene_path, "rb"))
    header = open(csv_path).readline().strip().split(",")
    data = np.loadtxt(csv_path, delimiter=",", skiprows=1)
    ycol = [i for i, k in enumerate(header) if k[0] == "y" and k[1:].isdigit()]
    zcol = [i for i, k in enumerate(header) if k[0] == "z" and k[1:].isdigit()]
    keep = data[:, 0] >= t0
    for spot, (lo, hi), m in hotspot_moments(scene, data[keep][:, ycol], data[keep][:, zcol]):
        print(
            f"{spot['name']}: elevation {spot['elevation']} m, joints at {lo:.3f}/{hi:.3f} m, "
            f"mean {m.mean():.5e} N m, std {m.std():.5e} N m"
        )


def hotspot_moments(scene, node_y, node_z):
    """Each `[[fatigue.hotspot]]` of the parsed `scene` with the elevations of the two joints
    read and its moment series [N m], from the node positions node_y, node_z (rows: times; columns: nodes
    1..n, the base node 0 at the origin left out, as `chainbeam simulate` writes them)."""
    st = scene["stackup"]
    segments = st.get("segment", [])
    bodies = st.get("body", [])
    ei_of = {}
    stiffest = 0.0
    for s in segments:
        d, t = s["outer_diameter"], s["wall_thickness"]
        ei = s.get("youngs_modulus", 207e9) * math.pi / 64 * (d**4 - (d - 2 * t) ** 4)
        ei_of[s["name"]] = ei
        stiffest = max(stiffest, ei)
    # The parts from the bottom up: each segment, then the bodies standing on it (file order).
    parts = []
    for s in segments:
        parts.append((s["name"], s["length"] * s.get("joints", 1)))
        for b in bodies:
            if b["above"] == s["name"]:
                parts.append((b["name"], b["height"]))
                ei_of[b["name"]] = b.get("bending_stiffness", 10 * stiffest)
    tops, y = {}, 0.0
    bounds = []
    for name, length in parts:
        bounds.append((y, y + length, name))
        y += length
        tops[name] = y

    rows = node_y.shape[0]
    ys = np.hstack([np.zeros((rows, 1)), node_y])
    zs = np.hstack([np.zeros((rows, 1)), node_z])
    # The pendulums' lengths (any row: they are constant).
    lengths = np.hypot(np.diff(ys[0]), np.diff(zs[0]))
    n = len(lengths)
    s = np.concatenate([[0.0], np.cumsum(lengths)])
    mids = 0.5 * (s[:-1] + s[1:])
    ei = np.array([next(ei_of[nm] for a, b, nm in bounds if a <= m < b) for m in mids])
    k = np.zeros(n + 1)
    for j in range(1, n):
        k[j] = 1.0 / (lengths[j - 1] / (2 * ei[j - 1]) + lengths[j] / (2 * ei[j]))
    if st.get("foot", "clamped") == "clamped":
        k[0] = 2 * ei[0] / lengths[0]
    k[n] = 2 * ei[n - 1] / lengths[n - 1]
    for f in st.get("flex_joint", []):
        at = tops[f["above"]] if "above" in f else f["elevation"]
        k[int(np.argmin(abs(s - at)))] = f["stiffness"]
    qy, qz = np.diff(ys, axis=1) / lengths, np.diff(zs, axis=1) / lengths
    ones, zeros = np.ones((rows, 1)), np.zeros((rows, 1))
    ay, az = np.hstack([ones, qy]), np.hstack([zeros, qz])
    by, bz = np.hstack([qy, ones]), np.hstack([qz, zeros])
    torque = np.arctan2(ay * bz - az * by, ay * by + az * bz) * k
    tol = 1e-9 * max(s[-1], 1.0)
    out = []
    for spot in scene["fatigue"].get("hotspot", []):
        e = spot["elevation"]
        on = np.nonzero(abs(s - e) <= tol)[0]
        if len(on):
            lo = hi = int(on[0])
            w = 0.0
        else:
            lo = int(np.searchsorted(s, e)) - 1
            hi = lo + 1
            w = (e - s[lo]) / (s[hi] - s[lo])
        m = (1 - w) * torque[:, lo] + w * torque[:, hi]
        out.append((spot, (s[lo], s[hi]), m))
    return out


if __name__ == "__main__":
    main()
