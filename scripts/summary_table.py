#!/usr/bin/env python3
"""The summary table of docs/results.md, as Markdown, from ratios.csv.

One row per scene and error level: the best CEODE and best SUNDIALS curves of the
-O3 half with their times and ratio, the best peer (Boost.Odeint, GSL) with the
CEODE / peer ratio, the CEODE / SUNDIALS ratio against the unoptimised (-O0)
SUNDIALS package, and CEODE's time over the hand-written loop's ("CEODE-hand"
curves) where a scene has one. Scenes run only against the -O0 package (no -O3
row) show that half, marked "(-O0)".

Usage: summary_table.py ratios.csv [--out summary.md]
scripts/results_page.py imports read_rows() and table() for docs/results.md.
"""
import argparse
import csv
import sys

O3 = "6.4.1 -O3"
HEAD = ("| scene | error | best CEODE | s | best SUNDIALS | s | **CEODE / SUNDIALS** | best peer | s "
        "| **CEODE / peer** | CEODE / SUNDIALS, -O0 package | CEODE / hand loop |\n|" + "---|" * 12)


def cell(v):
    return v if v else "–"


def secs(v):
    return f"{float(v):.3g}" if v else "–"


def hand(r):
    """CEODE's time over the hand-written loop's of the same method (scenes that have one)."""
    if not (r["hand_loop_seconds"] and r["ceode_seconds"]):
        return "–"
    return f"{float(r['ceode_seconds']) / float(r['hand_loop_seconds']):.3g}"


def hand_over_peer(r):
    """The hand-written loop's time over the best peer's (scenes that have both): above 1, the
    method itself loses to that peer, whatever the library's overhead."""
    if not (r["hand_loop_seconds"] and r["peer_seconds"]):
        return "–"
    return f"{float(r['hand_loop_seconds']) / float(r['peer_seconds']):.3g}"


def strip(name):
    return name[len("CEODE "):] if name.startswith("CEODE ") else name


def read_rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def headline(rows):
    """[(scene, level, row)]: the -O3 row of every scene and level, else the -O0 one."""
    by_key = {(r["scene"], r["error_level"], r["sundials_build"]): r for r in rows}
    o0 = {(r["scene"], r["error_level"]): r for r in rows if r["sundials_build"] != O3}
    keys = [(r["scene"], r["error_level"]) for r in rows if r["sundials_build"] == O3]
    keys += [k for k in o0 if k not in keys]
    return [(s, lv, by_key.get((s, lv, O3)) or o0[(s, lv)]) for s, lv in keys]


def table(rows, scenes=None):
    """The Markdown table (list of lines), every scene or only those in scenes."""
    o0 = {(r["scene"], r["error_level"]): r for r in rows if r["sundials_build"] != O3}
    lines = HEAD.split("\n")
    for scene, level, r in headline(rows):
        if scenes is not None and scene not in scenes:
            continue
        half = "" if r["sundials_build"] == O3 else " (-O0)"
        d = o0.get((scene, level), {})
        lines.append(
            f"| {scene}{half} | {level} | {strip(r['ceode_best'])} | {secs(r['ceode_seconds'])} "
            f"| {r['sundials_best']} | {secs(r['sundials_seconds'])} "
            f"| **{cell(r['ratio_ceode_over_sundials'])}** | {cell(r['peer_best'])} "
            f"| {secs(r['peer_seconds'])} | **{cell(r['ratio_ceode_over_peer'])}** "
            f"| {cell(d.get('ratio_ceode_over_sundials', ''))} | {hand(r)} |")
    return lines


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("ratios")
    ap.add_argument("--out")
    args = ap.parse_args()
    text = "\n".join(table(read_rows(args.ratios))) + "\n"
    if args.out:
        with open(args.out, "w") as f:
            f.write(text)
    sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
