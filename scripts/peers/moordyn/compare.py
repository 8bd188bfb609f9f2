"""The chain against MoorDyn v2 on one riser: static offsets and wellhead moment in a current,
σ of the wellhead moment in an irregular sea. Writes both codes' inputs, runs both, prints the
comparison table (README.md in this directory says how to rerun it and what it measured).

    target/peer-venv/bin/python scripts/peers/moordyn/compare.py --case all

Needs numpy and moordyn (2.7.2) in the Python that runs it, and a release build of the
command line (`cargo build --release --bin chainbeam`).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from dataclasses import asdict, dataclass

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import chain  # noqa: E402
import peer  # noqa: E402
from pipe import Riser, Sea  # noqa: E402

REPO = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))
SAMPLE = 0.1  # s, the times both codes are compared at
STATIC_DURATION = 200.0  # s: the drag in the current settles the riser in ≈ 100 s


@dataclass
class StaticRow:
    case: str
    chain_moment: float
    peer_moment: float
    moment_diff: float
    chain_max_offset: float
    peer_max_offset: float
    max_offset_node: int
    max_offset_diff: float
    profile_diff: float  # max over nodes |Δz| / max |z|
    chain_settling: float  # relative change of M_w over the last 50 s
    peer_settling: float
    peer_tension_dev: float  # max |T_top − T|/T over the last 50 s


@dataclass
class WaveRow:
    case: str
    window: tuple[float, float]
    chain_mean: float
    peer_mean: float
    mean_diff: float
    chain_std: float
    peer_std: float
    std_diff: float
    chain_std_top_half: float  # σ of the offset at node n/2 (mid-depth)
    peer_std_top_half: float
    offset_std_diff: float
    peer_tension_dev: float  # σ(T_top − T)/T in the window
    eta_reconstruction: float  # max |η_chain − η from the components| / max |η|


def settling(t: np.ndarray, m: np.ndarray) -> float:
    last = m[-1]
    before = m[np.searchsorted(t, t[-1] - 50.0)]
    return float(abs(last - before) / abs(last))


def static_case(
    name: str, current: chain.Current, riser: Riser, settings: peer.PeerSettings, args
) -> StaticRow:
    steps = int(round(STATIC_DURATION / args.chain_step))
    every = int(round(SAMPLE / args.chain_step))
    scene = chain.scene_toml(
        riser, current, None, args.chain_step, steps,
        f"Peer comparison, static: the riser in a {current.profile} current",
    )
    c = chain.run(args.chainbeam, riser, scene, os.path.join(args.out, f"{name}.toml"), False, every)
    heights = riser.node_heights()
    water = current.at(heights, riser.length)
    zeros = np.zeros(riser.segments + 1)
    p = peer.run(
        riser, settings, STATIC_DURATION, lambda k, t: (water, zeros),
        int(round(SAMPLE / settings.coupling_step)), os.path.join(args.out, name),
    )
    zc, zp = c.offsets[-1], p.offsets[-1]
    node = int(np.argmax(np.abs(zc)))
    last50 = p.t >= p.t[-1] - 50.0
    return StaticRow(
        case=name,
        chain_moment=float(c.moment[-1]),
        peer_moment=float(p.moment[-1]),
        moment_diff=float(c.moment[-1] / p.moment[-1] - 1.0),
        chain_max_offset=float(zc[node]),
        peer_max_offset=float(zp[node]),
        max_offset_node=node,
        max_offset_diff=float(zc[node] / zp[node] - 1.0),
        profile_diff=float(np.max(np.abs(zc - zp)) / np.max(np.abs(zp))),
        chain_settling=settling(c.t, c.moment),
        peer_settling=settling(p.t, p.moment),
        peer_tension_dev=float(
            np.max(np.abs(p.top_tension[last50] / riser.top_tension - 1.0))
        ),
    )


def wave_case(
    name: str, current: chain.Current, waves: chain.Waves, riser: Riser,
    settings: peer.PeerSettings, args,
) -> WaveRow:
    duration = waves.period
    steps = int(round(duration / args.chain_step))
    scene = chain.scene_toml(
        riser, current, waves, args.chain_step, steps,
        f"Peer comparison, irregular sea: H_s = {waves.hs} m, T_p = {waves.tp} s, and a current",
    )
    c = chain.run(args.chainbeam, riser, scene, os.path.join(args.out, f"{name}.toml"), True, 1)
    # The sea both codes see: the chain's η(t) over one repeat period, taken apart by a DFT.
    sea = Sea.from_elevation(c.eta[:steps], args.chain_step, waves.components)
    rebuilt = sea.elevation(c.t[: steps + 1])
    eta_err = float(np.max(np.abs(rebuilt - c.eta)) / np.max(np.abs(c.eta)))
    heights = riser.node_heights()
    water = current.at(heights, riser.length)
    dt = settings.coupling_step
    u, a = sea.kinematics_series(heights, riser.length, dt, shift=0.5 * dt)
    p = peer.run(
        riser, settings, duration,
        lambda k, t: (water + u[k % len(u)], a[k % len(a)]),
        int(round(SAMPLE / dt)), os.path.join(args.out, name),
    )
    np.savez(
        os.path.join(args.out, f"{name}-samples.npz"),
        t=p.t, chain_moment=c.moment[:: int(round(SAMPLE / args.chain_step))],
        peer_moment=p.moment, peer_tension=p.top_tension, peer_top_z=p.top_z,
    )
    every = int(round(SAMPLE / args.chain_step))
    tc, mc, zc = c.t[::every], c.moment[::every], c.offsets[::every]
    if len(tc) != len(p.t) or np.max(np.abs(tc - p.t)) > 1e-9:
        raise RuntimeError("the two codes' sample times differ")
    start = duration - args.window
    w = tc >= start - 1e-9
    mid = riser.segments // 2
    return WaveRow(
        case=name,
        window=(float(tc[w][0]), float(tc[w][-1])),
        chain_mean=float(np.mean(mc[w])),
        peer_mean=float(np.mean(p.moment[w])),
        mean_diff=float(np.mean(mc[w]) / np.mean(p.moment[w]) - 1.0),
        chain_std=float(np.std(mc[w])),
        peer_std=float(np.std(p.moment[w])),
        std_diff=float(np.std(mc[w]) / np.std(p.moment[w]) - 1.0),
        chain_std_top_half=float(np.std(zc[w, mid])),
        peer_std_top_half=float(np.std(p.offsets[w, mid])),
        offset_std_diff=float(np.std(zc[w, mid]) / np.std(p.offsets[w, mid]) - 1.0),
        peer_tension_dev=float(np.std(p.top_tension[w] / riser.top_tension - 1.0)),
        eta_reconstruction=eta_err,
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--case", choices=["static", "waves", "all"], default="all")
    parser.add_argument(
        "--chainbeam", default=os.path.join(REPO, "target", "release", "chainbeam")
    )
    parser.add_argument("--out", default=os.path.join(REPO, "target", "peer-moordyn"))
    parser.add_argument("--segments", type=int, default=80)
    parser.add_argument("--window", type=float, default=600.0, help="s, the record compared")
    parser.add_argument("--hs", type=float, default=4.9)
    parser.add_argument("--tp", type=float, default=9.9)
    parser.add_argument("--components", type=int, default=425)
    parser.add_argument(
        "--chain-step", type=float, default=0.0125,
        help="s, the chain's h (riser_300m.toml's at n = 80); must divide T_p/6 and 0.1 s",
    )
    parser.add_argument(
        "--tensioner-gain", type=float, default=peer.PeerSettings.tensioner_gain,
        help="the fraction of MoorDyn's top-tension error corrected per 0.01 s step",
    )
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)

    import moordyn  # noqa: F401  (fail early, before the chain's runs)

    riser = Riser(segments=args.segments)
    settings = peer.PeerSettings(tensioner_gain=args.tensioner_gain)
    results: dict[str, object] = {
        "riser": {
            "segments": riser.segments,
            "top_tension": riser.top_tension,
            "submerged_weight": riser.submerged_weight,
            "bending_stiffness": riser.bending_stiffness,
        },
        "peer_settings": asdict(settings),
        "chain_step": args.chain_step,
    }
    if args.case in ("static", "all"):
        rows = [
            static_case("static_uniform", chain.Current("uniform", 0.5), riser, settings, args),
            static_case(
                "static_sheared", chain.Current("linear", 1.0, 0.25), riser, settings, args
            ),
        ]
        results["static"] = [asdict(r) for r in rows]
        print("\nstatic (t = 200 s)       M_w chain [N m]  M_w MoorDyn  diff     "
              "max z chain [m]  MoorDyn  (node)  diff     profile")
        for r in rows:
            print(
                f"{r.case:24s} {r.chain_moment:14.6e}  {r.peer_moment:11.6e}  "
                f"{100 * r.moment_diff:+6.2f} %  {r.chain_max_offset:14.4f}  "
                f"{r.peer_max_offset:7.4f}  ({r.max_offset_node:3d})  "
                f"{100 * r.max_offset_diff:+6.2f} %  {100 * r.profile_diff:5.2f} %"
            )
    if args.case in ("waves", "all"):
        waves = chain.Waves(hs=args.hs, tp=args.tp, components=args.components)
        row = wave_case("waves", chain.Current("uniform", 0.5), waves, riser, settings, args)
        results["waves"] = asdict(row)
        print(f"\nirregular sea H_s = {waves.hs} m, T_p = {waves.tp} s, γ = {waves.gamma}, "
              f"0.5 m/s current; t in [{row.window[0]:.2f}, {row.window[1]:.2f}] s")
        print(f"  mean M_w   chain {row.chain_mean:.6e}  MoorDyn {row.peer_mean:.6e}  "
              f"{100 * row.mean_diff:+.2f} %")
        print(f"  σ(M_w)     chain {row.chain_std:.6e}  MoorDyn {row.peer_std:.6e}  "
              f"{100 * row.std_diff:+.2f} %")
        print(f"  σ(z_n/2)   chain {row.chain_std_top_half:.6e}  MoorDyn "
              f"{row.peer_std_top_half:.6e}  {100 * row.offset_std_diff:+.2f} %")
        print(f"  MoorDyn's top tension: σ(T/T₀ − 1) = {row.peer_tension_dev:.2e}; "
              f"η from the components: {row.eta_reconstruction:.1e} of max |η|")
    path = os.path.join(args.out, f"results-{args.case}.json")
    with open(path, "w", encoding="utf-8") as f:
        json.dump(results, f, indent=2)
    print(f"\nresults: {path}")


if __name__ == "__main__":
    main()
