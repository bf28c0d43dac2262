"""Reads the work-precision CSVs (common schema) into curves; shared by
plot_results.py and ratios.py.

Schema: scene,solver,config,h_or_tol,error,drift,steps,rhs_evals,seconds.
A curve is one (solver, config) pair, its points in the order the scene ran
them (decreasing h or tolerance), which is also the order they are drawn in.
"""
import csv
import math
from collections import OrderedDict

SUNDIALS_PREFIXES = ("ARKODE", "CVODE", "IDA")


def is_ceode(solver):
    """The library itself (the hand-written loop is a reference, not CEODE)."""
    return solver == "CEODE"


def is_sundials(solver):
    return solver.upper().startswith(SUNDIALS_PREFIXES)


# The integrators users pick outside SUNDIALS (bench/peers.h): Boost.Odeint and GSL.
PEER_SOLVERS = ("odeint", "GSL")


def is_peer(solver):
    return solver in PEER_SOLVERS


def read_curves(path):
    """Returns (scene, OrderedDict[(solver, config)] -> list of dict points)."""
    curves = OrderedDict()
    scene = None
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            scene = row["scene"]
            try:
                pt = {
                    "h_or_tol": float(row["h_or_tol"]),
                    "error": float(row["error"]),
                    "seconds": float(row["seconds"]),
                    "steps": int(float(row["steps"])),
                }
            except ValueError:
                continue
            curves.setdefault((row["solver"], row["config"]), []).append(pt)
    return scene, curves


def usable(pt):
    e, s = pt["error"], pt["seconds"]
    return math.isfinite(e) and e > 0 and math.isfinite(s) and s > 0


def time_to_reach(points, level):
    """Cheapest time at which the curve reaches error <= level.

    Candidates are the measured points with error <= level and, on every
    segment between consecutive points that crosses the level, the time
    interpolated linearly in log(error)-log(seconds). Returns (seconds, how) or
    None when the curve never gets down to the level. how is "interp" or
    "point" (a measured point already below the level: an upper bound on the
    time, since the curve was not sampled at coarser settings there).
    """
    best = None
    pts = [p for p in points if usable(p)]
    for p in pts:
        if p["error"] <= level and (best is None or p["seconds"] < best[0]):
            best = (p["seconds"], "point")
    le = math.log(level)
    for a, b in zip(pts, pts[1:]):
        ea, eb = math.log(a["error"]), math.log(b["error"])
        if (ea - le) * (eb - le) >= 0 or ea == eb:
            continue
        w = (le - ea) / (eb - ea)
        s = math.exp(math.log(a["seconds"]) + w * (math.log(b["seconds"]) - math.log(a["seconds"])))
        if best is None or s < best[0]:
            best = (s, "interp")
    return best
