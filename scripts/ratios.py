#!/usr/bin/env python3
"""CEODE time / best SUNDIALS time (and / best peer time) at equal error, per scene.

For every scene CSV and error level (default 1e-6, 1e-9, 1e-11), the time each
curve needs to reach the level is interpolated on the curve in log-log (see
wp_curves.time_to_reach); the best CEODE configuration is compared with the
best SUNDIALS one (ARKODE, CVODE or IDA) and with the best of all peers users
pick outside SUNDIALS (Boost.Odeint and GSL curves, bench/peers.h; columns
peer_best, peer_seconds, ratio_ceode_over_peer, empty for scenes without
peers). A ratio below 1 means CEODE is faster. Levels that one side never
reaches are reported as such, with no ratio. The hand-written loop
("CEODE-hand") is reported beside, as the floor for per-step overhead, and
takes no part in the CEODE figure.

A CSV whose name ends in _o3.csv is the same scene run against SUNDIALS 6.4.1
built -O3 (CEODE linked against it too); the others ran against the system's
SUNDIALS package (libsundials-dev 6.4.1, compiled -O0). Column sundials_build
says which ("6.4.1 -O3" or "6.4.1 -O0"); the -O3 rows come first in each scene
and are the headline figures.

Usage: ratios.py --out ratios.csv [--levels 1e-6,1e-9,1e-11] [--scene-levels fe_=1e-4,1e-6]
                 FILE.csv ...
"""
import argparse
import csv
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from wp_curves import is_ceode, is_peer, is_sundials, read_curves, time_to_reach  # noqa: E402


def best(curves, pick, level):
    """(seconds, 'solver config', how) of the fastest picked curve, or None."""
    out = None
    for (solver, config), pts in curves.items():
        if not pick(solver):
            continue
        r = time_to_reach(pts, level)
        if r is not None and (out is None or r[0] < out[0]):
            out = (r[0], f"{solver} {config}", r[1])
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv", nargs="+")
    ap.add_argument("--out", required=True)
    ap.add_argument("--levels", default="1e-6,1e-9,1e-11")
    ap.add_argument("--scene-levels", action="append", default=[], metavar="PREFIX=LEVELS",
                    help="levels for the scenes whose name starts with PREFIX, e.g. "
                         "fe_=1e-4,1e-6 (the FE scenes' errors are relative)")
    args = ap.parse_args()
    default_levels = [float(x) for x in args.levels.split(",")]
    special = [(p, [float(x) for x in lv.split(",")])
               for p, lv in (s.split("=", 1) for s in args.scene_levels)]
    rows = []
    for path in args.csv:
        scene, curves = read_curves(path)
        if scene is None:
            continue
        o3 = os.path.splitext(os.path.basename(path))[0].endswith("_o3")
        build = "6.4.1 -O3" if o3 else "6.4.1 -O0"
        levels = next((lv for p, lv in special if scene.startswith(p)), default_levels)
        for lv in levels:
            c = best(curves, is_ceode, lv)
            s = best(curves, is_sundials, lv)
            h = best(curves, lambda name: name == "CEODE-hand", lv)
            has_peers = any(is_peer(solver) for solver, _ in curves)
            p = best(curves, is_peer, lv)
            ratio = c[0] / s[0] if c and s else None
            rows.append({
                "scene": scene,
                "sundials_build": build,
                "error_level": f"{lv:.0e}",
                "ceode_best": c[1] if c else "not reached",
                "ceode_seconds": f"{c[0]:.3e}" if c else "",
                "sundials_best": s[1] if s else "not reached",
                "sundials_seconds": f"{s[0]:.3e}" if s else "",
                "ratio_ceode_over_sundials": f"{ratio:.3g}" if ratio else "",
                "hand_loop_seconds": f"{h[0]:.3e}" if h else "",
                "hand_over_sundials": f"{h[0] / s[0]:.3g}" if h and s else "",
                "peer_best": (p[1] if p else "not reached") if has_peers else "",
                "peer_seconds": f"{p[0]:.3e}" if p else "",
                "ratio_ceode_over_peer": f"{c[0] / p[0]:.3g}" if c and p else "",
                "note": ";".join(
                    f"{who} from a measured point below the level (upper bound)"
                    for who, r in (("CEODE", c), ("SUNDIALS", s), ("peer", p))
                    if r and r[2] == "point"),
            })
    order = {r["scene"]: i for i, r in reversed(list(enumerate(rows)))}
    rows.sort(key=lambda r: (order[r["scene"]], r["sundials_build"] != "6.4.1 -O3"))
    with open(args.out, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()) if rows else ["scene"])
        w.writeheader()
        w.writerows(rows)
    print(f"{'scene':<17} {'SUNDIALS':<17} {'error':>6} {'CEODE best':<20} {'s':>10} {'SUNDIALS best':<24} "
          f"{'s':>10} {'ratio':>7} {'best peer':<22} {'s':>10} {'ratio':>7}")
    for r in rows:
        print(f"{r['scene']:<17} {r['sundials_build']:<17} {r['error_level']:>6} {r['ceode_best']:<20} "
              f"{r['ceode_seconds']:>10} {r['sundials_best']:<24} {r['sundials_seconds']:>10} "
              f"{r['ratio_ceode_over_sundials'] or '-':>7} {r['peer_best'] or '-':<22} "
              f"{r['peer_seconds']:>10} {r['ratio_ceode_over_peer'] or '-':>7}")
    print("ratio = CEODE time / best SUNDIALS (then: best peer, odeint or GSL) time at equal error "
          "(< 1: CEODE faster)")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
