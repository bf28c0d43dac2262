#!/usr/bin/env python3
"""Writes docs/results.md from the main job's outputs in docs/results/.

Nothing in the page is typed by hand: the numbers come from ratios.csv (equal-error ratios,
scripts/ratios.py), the scene CSVs (figures, scripts/plot_results.py draws a missing one),
bench_step[_o3].json (per-step cost), mpi_*.csv, mri_inner_cost[_o3].csv, chain_dae[_o3].csv,
python_*.csv (the Python module's benchmarks, bench/python/) and run_info.json (how the run was made: commit, date, machine, compiler and flags, SUNDIALS
builds, command; written by the last step of scripts/main_job.sh). The one-sentence problem
statements are the SCENES table below. The -O3 SUNDIALS half is the headline wherever it
exists; a scene whose CSVs are missing gets a line saying it was not run.

Usage: results_page.py [--results docs/results] [--out docs/results.md]
"""
import argparse
import csv
import json
import math
import os
import sys
from collections import defaultdict

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import summary_table  # noqa: E402
from wp_curves import time_to_reach  # noqa: E402

# name, title, the problem in one sentence (error measure included).
SCENES = [
    ("pendulum_ode", "Simple pendulum (explicit path)",
     "θ'' = −(g/L) cos θ released from the horizontal, 10 s; f does not read the velocity, so a "
     "CEODE step is one f call. Error: max |E − E0| over every step."),
    ("spinning_top", "Heavy symmetric top (implicit path)",
     "A top on a fixed tip in Euler angles, 10 s; f depends on the velocities, so every CEODE step "
     "solves for the acceleration. Error: max |E − E0|."),
    ("damped_pendulum", "Damped driven pendulum (implicit path, 1 DOF)",
     "θ'' = −9.81 cos θ − 0.5 θ' + sin 2t from rest, 10 s. Error: |θ(10) − ref| against a "
     "Richardson-extrapolated long-double reference."),
    ("forced_vibration", "Forced vibration (stability-limited)",
     "x'' + x = sin(0.01 t) over 1000 s, started on its exact particular solution: the answer is "
     "slow, but the free frequency bounds every explicit step. Error: max |x − x_exact|."),
    ("fpu_chain", "FPU-β chain of 1 000 masses (expensive smooth f)",
     "x_i'' = (d_i − d_{i−1}) + β (d_i³ − d_{i−1}³), d_i = x_{i+1} − x_i, fixed ends, β = 1, "
     "released from rest on 2 sin(50π i / 1001), 100 s; f is one pass of about 1 µs, so a step's "
     "own arithmetic counts beside f. Error: max_i |x_i(100) − ref_i| against a "
     "Richardson-extrapolated long-double RK4 reference; ratios at 1e-6, 1e-8 and 1e-10."),
    ("events", "Event location (Kepler orbit)",
     "SUNDIALS' Kepler problem (e = 0.6) over 10 orbits with the root function g = q₂ in both "
     "directions: 20 events at t = kπ, located on each solver's dense output (CEODE, ARKODE ERK, "
     "CVODE Adams). Error: max |t_k − kπ|; the CSV's drift column holds the g evaluations."),
    ("pendulum_dae", "Pendulum as an index-3 DAE",
     "The same pendulum in centre-of-mass coordinates with a singular mass matrix (I_zz = 0) and "
     "two position constraints; CEODE without index reduction, ARKODE on the index-1 form, IDA. "
     "Error: max |E − E0|."),
    ("chain_dae_wp", "Chain of 8 pendulums (index-3 DAE, sparse)",
     "16 coordinates, 8 constraints, 2 s of fall and whip; the saddle-point matrix is factored by "
     "KLU. Error: max |E − E0|."),
    ("fe_plate", "Q4 cantilever plate (structural dynamics)",
     "Linear plane-stress plate of 1 248 DOF, lumped mass, started on its two lowest modes so the "
     "exact solution is modal; CEODE at fractions of the guard's stable step, the hand loop is "
     "central differences on the same f. Error: relative position error over one period of mode 1."),
    ("fe_nonlinear", "Plate with a large-deflection truss",
     "The plate at 3 360 DOF carrying one axial spring per element edge (exact geometry), f "
     "nonlinear in x. Error against a converged high-order reference."),
    ("fe_damped_mass", "Plate with mass-proportional damping",
     "C = aM, 5 % of critical in mode 1, 3 360 DOF: the step depends on the velocity through a "
     "diagonal term. Error against the modal closed form."),
    ("fe_damped_stiff", "Plate with stiffness-proportional damping",
     "C = bK (ζ = 2 at the highest frequency), 3 360 DOF: every implicit step needs a linear solve "
     "with M + κbK. Error against the modal closed form."),
]
HIGH_ORDER = ("wp_high_order", "High-degree sets against 8th-order integrators",
              "G6_O5 … G8_O8 at fixed h against GSL rk8pd, Boost.Odeint rkf78 and Bulirsch–Stoer "
              "and ARKODE ERK order 8, on the pendulum and an FPU-β chain of 16 masses. Error at "
              "t = 10 against an extrapolated reference.")
HIGH_ORDER_LEVELS = (1e-9, 1e-11)


def fmt(x, digits=3):
    return f"{x:.{digits}g}"


class Page:
    def __init__(self, results):
        self.dir = results
        self.lines = []

    def path(self, name):
        return os.path.join(self.dir, name)

    def exists(self, name):
        return os.path.exists(self.path(name))

    def headline(self, stem, ext):
        """stem_o3.ext when it exists, else stem.ext, else None."""
        for name in (f"{stem}_o3.{ext}", f"{stem}.{ext}"):
            if self.exists(name):
                return name
        return None

    def figure(self, stem, alt):
        """Markdown image of the headline PNG; draws it from the CSV when it is missing."""
        png = self.headline(stem, "png")
        csv_name = self.headline(stem, "csv")
        if csv_name and (png is None or ("_o3" in csv_name and "_o3" not in png)):
            import plot_results  # matplotlib only when a plot is missing
            plot_results.plot(self.path(csv_name), None, True)
            png = csv_name[:-4] + ".png"
        if png and self.exists(png):
            return [f"![{alt}](results/{png})", ""]
        return []

    def add(self, *lines):
        self.lines.extend(lines)


def run_info(page):
    try:
        with open(page.path("run_info.json")) as f:
            return json.load(f)
    except (OSError, ValueError):
        return {}


def bench_step(page):
    """{(method, n): (ceode / hand_fpass, ceode ns per step)} and the CV range, headline build."""
    name = page.headline("bench_step", "json")
    if not name:
        return None, {}, []
    with open(page.path(name)) as f:
        data = json.load(f)
    med, cvs = {}, []
    for b in data.get("benchmarks", []):
        parts = b.get("run_name", "").split("/")
        if len(parts) != 3 or parts[0] not in ("ceode", "hand_fpass"):
            continue
        key = (parts[0], parts[1], int(parts[2].split(":")[1]))
        if b.get("aggregate_name") == "median":
            scale = {"ns": 1.0, "us": 1e3, "ms": 1e6, "s": 1e9}[b.get("time_unit", "ns")]
            med[key] = b["cpu_time"] * scale / max(float(b.get("steps", 1)), 1.0)  # ns a step
        elif b.get("aggregate_name") == "cv":
            cvs.append(b["cpu_time"])
    out = {}
    for (who, method, n), t in med.items():
        hand = med.get(("hand_fpass", method, n))
        if who == "ceode" and hand:
            out[(method, n)] = (t / hand, t)
    return name, out, cvs


def mpi(page, stem):
    """(file, {(vector, ranks): best seconds per step}, largest spread max/min - 1)."""
    name = page.headline(stem, "csv")
    if not name:
        return None, {}, 0.0
    reps = defaultdict(list)
    with open(page.path(name), newline="") as f:
        for r in csv.DictReader(f):
            reps[(r["vector"], int(r["ranks"]))].append(float(r["seconds_per_step"]))
    best = {k: min(v) for k, v in reps.items()}
    spread = max((max(v) / min(v) - 1 for v in reps.values()), default=0.0)
    return name, best, spread


def high_order(page):
    """[(problem, level, best CEODE, s, best other, s)] at HIGH_ORDER_LEVELS, headline build."""
    name = page.headline("wp_high_order", "csv")
    if not name:
        return None, []
    problems = defaultdict(dict)
    with open(page.path(name), newline="") as f:
        for r in csv.DictReader(f):
            problems[r["scene"]].setdefault(r["solver"], []).append(
                {"error": max(float(r["error"]), 1e-17), "seconds": float(r["seconds"]),
                 "h_or_tol": float(r["h_or_tol"]), "steps": 0})
    rows = []
    for problem, curves in problems.items():
        for lv in HIGH_ORDER_LEVELS:
            best = {True: None, False: None}
            for solver, pts in curves.items():
                pts = sorted(pts, key=lambda p: -p["h_or_tol"])
                t = time_to_reach(pts, lv)
                ceode = solver[:1] == "G"
                if t and (best[ceode] is None or t[0] < best[ceode][1]):
                    best[ceode] = (solver, t[0])
            rows.append((problem, lv, best[True], best[False]))
    return name, rows


def mri(page):
    """{(omega, amp): [best CEODE fast f / RK4's over the H]} of the headline build."""
    name = page.headline("mri_inner_cost", "csv")
    if not name:
        return None, {}
    best = defaultdict(dict)
    with open(page.path(name), newline="") as f:
        for r in csv.DictReader(f):
            if r["inner"] != "ceode" or r["omega_given"] != "no" or float(r["ratio_to_rk4"]) <= 0:
                continue
            key, h = (r["omega"], r["amp"]), float(r["H"])
            best[key][h] = min(best[key].get(h, math.inf), float(r["ratio_to_rk4"]))
    return name, {k: [v[h] for h in sorted(v, reverse=True)] for k, v in best.items()}


def how_measured(page, info, cvs, spreads):
    g = info.get
    page.add("## How measured", "")
    box = [
        ("commit", g("commit")),
        ("date", f"{g('start', '?')} to {g('end', '?')} UTC, {g('seconds', '?')} s, exit {g('exit', '?')}"
         if g("start") else None),
        ("machine", g("machine")),
        ("system", g("os")),
        ("compiler and CEODE flags", g("compiler") and f"{g('compiler')}; {g('ceode_flags', '')}"),
        ("SUNDIALS, headline", g("sundials_o3")),
        ("SUNDIALS, second half", g("sundials_package")),
        ("command", g("command") and f"`{g('command')}`"),
        ("repetitions", g("repetitions")),
    ]
    spread = []
    if cvs:
        spread.append(f"per-step benchmark: coefficient of variation {100 * min(cvs):.0f}–"
                      f"{100 * max(cvs):.0f} % over the repetitions of one configuration")
    for label, s in spreads:
        spread.append(f"{label}: repetitions of one configuration up to {100 * s:.0f} % apart")
    box.append(("spread", "; ".join(spread) or None))
    page.add("| | |", "|---|---|")
    for k, v in box:
        page.add(f"| {k} | {v if v else 'not recorded'} |")
    page.add("", "Every solver of a scene runs in the same process on the same machine, so ratios "
             "within a scene are side by side; times on another machine differ. Below 1, CEODE is "
             "faster. Equal-error times are interpolated on each curve in log-log "
             "(`scripts/ratios.py`).", "")


def scene_section(page, rows, name, title, sentence):
    page.add(f"### {name}", "", f"**{title}.** {sentence}", "")
    if not (page.exists(f"{name}.csv") or page.exists(f"{name}_o3.csv")):
        page.add("Not run in this job (no `docs/results/%s[_o3].csv`)." % name, "")
        return
    page.add(*page.figure(name, f"{name} work-precision"))
    page.add(*loss_lines(rows, name))
    mine = [r for r in rows if r["scene"] == name]
    if mine:
        page.add(*summary_table.table(mine, {name}))
        page.add("")
    page.add(*drift_lines(page, name))
    page.add(*scaling_lines(page, name))


def loss_lines(rows, name):
    """A plain sentence for every headline level where CEODE is slower than a competitor."""
    out = []
    for scene, level, r in summary_table.headline(rows):
        if scene != name:
            continue
        for col, who in (("ratio_ceode_over_sundials", "sundials_best"),
                         ("ratio_ceode_over_peer", "peer_best")):
            if r[col] and float(r[col]) > 1:
                out.append(f"* **CEODE loses here at {level}:** its fastest configuration "
                           f"({summary_table.strip(r['ceode_best'])}) takes {r[col]}× the time "
                           f"of {r[who]}.")
        if r["ceode_best"] == "not reached" and r["sundials_best"] != "not reached":
            out.append(f"* **CEODE loses here at {level}:** no CEODE configuration reaches it; "
                       f"{r['sundials_best']} does.")
    return out + [""] if out else []


def drift_lines(page, name):
    """The constraint-drift figure of a DAE scene (scripts/plot_dae.py), headline build."""
    for stem in (f"{name}_o3", name):
        png = f"{stem}_drift.png"
        if page.exists(png) and page.exists(f"{stem}.csv"):
            return [f"Constraint drift: the largest position-constraint residual of each run "
                    f"against its CPU time (`{stem}.csv`, column drift). The scene records each "
                    "run's largest residual, not the residual along the run, so there is no "
                    "drift-against-simulated-time curve.", "",
                    f"![{name} constraint drift](results/{png})", ""]
    return []


def scaling_lines(page, name):
    """ns per DOF and step against the model size, from <scene>[_o3]_scaling.csv (FE plate)."""
    names = (f"{name}{sfx}_scaling.csv" for sfx in ("_o3", ""))
    path = next((n for n in names if page.exists(n)), None)
    if not path:
        return []
    with open(page.path(path), newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        return []
    cols = [c for c in rows[0] if c != "dof"]
    label = {c: ("hand loop" if c.startswith("hand") else c.upper()) for c in cols}
    lines = [f"Cost per DOF and step against the model size (`{path}`, ns):", "",
             "| DOF | " + " | ".join(label[c] for c in cols) + " |", "|---|" + "---|" * len(cols)]
    lines += [f"| {int(r['dof']):,} | ".replace(",", " ") +
              " | ".join(fmt(float(r[c]) / int(r["dof"]) * 1e9) for c in cols) + " |" for r in rows]
    return lines + [""]


def power(n):
    """1, 10⁴, 3·10⁵, ... for the sizes of the per-step benchmark."""
    e = int(math.floor(math.log10(n))) if n > 0 else 0
    m = n / 10 ** e
    sup = str(e).translate(str.maketrans("0123456789", "⁰¹²³⁴⁵⁶⁷⁸⁹"))
    if e == 0:
        return f"{n:g}"
    return f"10{sup}" if m == 1 else f"{m:g}·10{sup}"


def duration(ns):
    for unit, scale in (("ms", 1e6), ("µs", 1e3)):
        if ns >= scale:
            return f"{fmt(ns / scale)} {unit}"
    return f"{fmt(ns)} ns"


def collect_losses(rows, bs, ho, mri_best):
    """{group: [(scene, text)]}: every headline ratio above 1 and every level CEODE misses."""
    groups = defaultdict(list)
    for scene, level, r in summary_table.headline(rows):
        half = "" if r["sundials_build"] == summary_table.O3 else ", -O0 half only"
        ceode = summary_table.strip(r["ceode_best"])
        if r["ceode_best"] == "not reached" and r["sundials_best"] != "not reached":
            groups["SUNDIALS"].append((scene, f"{level} not reached by CEODE "
                                       f"({r['sundials_best']} reaches it{half})"))
        for col, who, group in (("ratio_ceode_over_sundials", "sundials_best", "SUNDIALS"),
                                ("ratio_ceode_over_peer", "peer_best", "peer")):
            if r[col] and float(r[col]) > 1:
                floor = summary_table.hand_over_peer(r) if group == "peer" else "–"
                floor = "" if floor == "–" else f"; the hand-written loop {floor}×"
                groups[group].append((scene, f"{r[col]}× {r[who]} at {level} ({ceode}{half}"
                                      f"{floor})"))
        h = summary_table.hand(r)
        if h != "–" and float(h) > 1:
            groups["hand"].append((scene, f"{h}× at {level} ({ceode}{half})"))
    for problem, lv, c, o in ho:
        if c and o and c[1] > o[1]:
            groups["high"].append((problem, f"{fmt(c[1] / o[1])}× {o[0]} at {lv:.0e} ({c[0]})"))
        elif o and not c:
            groups["high"].append((problem, f"{lv:.0e} not reached by CEODE ({o[0]} reaches it)"))
    for (method, n), (ratio, t) in sorted(bs.items()):
        if ratio > 1:
            groups["step"].append((method, f"{fmt(ratio)}× at n = {power(n)} ({duration(t)} a step)"))
    for (omega, amp), ratios in mri_best.items():
        if max(ratios) > 1:
            groups["mri"].append((f"ω = {omega}, A = {amp}", f"up to {fmt(max(ratios))}× RK4's "
                                  "fast evaluations"))
    return groups


LOSS_TITLES = [
    ("SUNDIALS", "Against the best SUNDIALS configuration (-O3) at equal error"),
    ("peer", "Against the best integrator outside SUNDIALS (Boost.Odeint, GSL) at equal error"),
    ("hand", "Against a hand-written loop of the same method, at equal error"),
    ("high", "High-degree sets against the best 8th-order integrator at equal error"),
    ("step", "Per step, against a hand-written loop (explicit path, n springs)"),
    ("mri", "As MRIStep's inner stepper, fast evaluations against RK4"),
]


def compact_summary(rows):
    """One line per scene: its ratios at every level (-O3 half where it exists)."""
    lines = ["| scene | error | CEODE / best SUNDIALS | CEODE / best peer | CEODE / hand loop |",
             "|---|---|---|---|---|"]
    per = defaultdict(list)
    for scene, level, r in summary_table.headline(rows):
        per[scene].append((level, r))
    order = {name: i for i, (name, _, _) in enumerate(SCENES)}
    for scene, items in sorted(per.items(), key=lambda kv: order.get(kv[0], len(order))):
        half = "" if items[0][1]["sundials_build"] == summary_table.O3 else " (-O0)"
        cols = [" / ".join(summary_table.cell(r[c]) for _, r in items)
                for c in ("ratio_ceode_over_sundials", "ratio_ceode_over_peer")]
        cols.append(" / ".join(summary_table.hand(r) for _, r in items))
        cols = [c if c.strip("/ –") else "–" for c in cols]
        lines.append(f"| [{scene}](#{scene}){half} | {' / '.join(lv for lv, _ in items)} | "
                     f"**{cols[0]}** | {cols[1]} | {cols[2]} |")
    return lines


def damping_note(page):
    """The sets that are stable undamped but lose their whole interval at xi = 0.05."""
    path = os.path.join(os.path.dirname(os.path.abspath(page.dir)), "data", "set_summary.csv")
    if not os.path.exists(path):
        return ""
    with open(path, newline="") as f:
        lost = [r["set"] for r in csv.DictReader(f)
                if float(r["omega_max_xi0"]) > 0 and float(r["omega_max_xi005"]) == 0]
    return (f" {' and '.join(lost)} lose their whole interval at ξ = 0.05 (`set_summary.csv`)."
            if lost else "")


def image(page, png, alt):
    """Markdown lines of a chart in docs/results/, or [] when it was not drawn."""
    return [f"![{alt}](results/{png})"] if page.exists(png) else []


def section(page, heading, intro, body, missing="Not run in this job."):
    """Heading, intro paragraph, then body (a list of lines) or the missing line."""
    page.add(heading, "", intro, "")
    page.add(*(body + [""] if body else [missing, ""]))


def losses_lines(rows, bs, ho, mri_best):
    losses = collect_losses(rows, bs, ho, mri_best)
    lines = []
    for key, title in LOSS_TITLES:
        if losses.get(key):
            lines.append(f"* {title}:")
            per = defaultdict(list)
            for who, text in losses[key]:
                per[who].append(text)
            lines += [f"  * {who}: {'; '.join(texts)}." for who, texts in per.items()]
    return lines


def high_order_lines(page, ho):
    if not ho:
        return []
    lines = page.figure("wp_high_order", "high-order work-precision")
    lines += ["| problem | error | best CEODE | s | best other | s | CEODE / other |",
              "|---|---|---|---|---|---|---|"]
    for problem, lv, c, o in ho:
        ratio = fmt(c[1] / o[1]) if c and o else "–"
        lines.append(f"| {problem} | {lv:.0e} | {c[0] if c else 'not reached'} | "
                     f"{fmt(c[1]) if c else '–'} | {o[0] if o else 'not reached'} | "
                     f"{fmt(o[1]) if o else '–'} | **{ratio}** |")
    return lines


def chain_lines(page):
    chain = page.headline("chain_dae", "csv")
    if not chain:
        return []
    import plot_dae  # noqa: E402  (matplotlib only when the scene ran)
    pts, slope = plot_dae.chain_slope(plot_dae.read_rows([page.path(chain)]))
    png = chain[:-4] + ".png"  # scripts/plot_dae.py names the plot after its CSV
    lines = [f"![chain N-scaling, {chain}](results/{png})", ""] if page.exists(png) else []
    return lines + [f"N = {pts[0][0]} … {pts[-1][0]}: {fmt(pts[0][1] * 1e6)} µs to "
                    f"{fmt(pts[-1][1] * 1e6)} µs per step, log-log slope **{slope:.3f}** "
                    f"(`{chain}`)."]


def bench_step_lines(bs_name, bs):
    if not bs:
        return []
    ns = sorted({n for _, n in bs})
    methods = sorted({m for m, _ in bs})
    lines = ["| set | " + " | ".join(f"n = {power(n)}" for n in ns) + " |",
             "|---|" + "---|" * len(ns)]
    lines += [f"| {m} | " + " | ".join(fmt(bs[(m, n)][0]) if (m, n) in bs else "" for n in ns)
              + " |" for m in methods]
    return lines + ["", f"From `{bs_name}`."]


def mpi_lines(mpi_runs):
    if not any(n for _, n, _, _ in mpi_runs):
        return []
    lines = ["| model | CEODE speedup | hand-loop speedup | CEODE / hand per step, 2 ranks | file |",
             "|---|---|---|---|---|"]
    for label, n, best, _ in mpi_runs:
        if not n:
            lines.append(f"| {label} | not run | | | |")
            continue
        c1, c2 = best.get(("parallel", 1)), best.get(("parallel", 2))
        h1, h2 = best.get(("hand", 1)), best.get(("hand", 2))
        lines.append(f"| {label} | **{fmt(c1 / c2) if c1 and c2 else '–'}** | "
                     f"{fmt(h1 / h2) if h1 and h2 else '–'} | "
                     f"{fmt(c2 / h2) if c2 and h2 else '–'} | `{n}` |")
    return lines + ["", "Every run's states are compared with the serial run entry by entry; the "
                    "job fails when they differ."]


def mri_lines(mri_name, mri_best):
    if not mri_best:
        return []
    lines = ["| ω | amplitude of the fast mode | best CEODE / RK4 over H |", "|---|---|---|"]
    lines += [f"| {omega} | {amp} | {', '.join(fmt(x, 2) for x in ratios)} |"
              for (omega, amp), ratios in mri_best.items()]
    return lines + ["", f"From `{mri_name}`."]


def read_csv(page, name):
    """The rows of docs/results/<name>, [] when it is absent."""
    if not page.exists(name):
        return []
    with open(page.path(name), newline="") as f:
        return list(csv.DictReader(f))


def python_lines(page):
    """The Python module's benchmarks (bench/python/): python_structural.csv, python_callback.csv,
    python_ratios.csv and the work-precision figures python_<problem>.png."""
    lines = []
    st = read_csv(page, "python_structural.csv")
    if st:
        dof = f"{int(st[0]['dof']):,}".replace(",", " ")
        lines += [f"Structural path: `ceode.LinearStructure` against the C scene on the identical "
                  f"Q4 plate ({dof} DOF, K and M exported by the C assembly), time per step; the "
                  f"ratio is the median over {st[0]['pairs']} pairs of chunks run alternately "
                  "(quartiles beside it), then the fastest chunk's over the fastest chunk's "
                  "(`python_structural.csv`):", "",
                  "| set | h | Python ms/step (spread) | C ms/step (spread) | Python / C "
                  "(quartiles) | fastest / fastest |", "|---|---|---|---|---|---|"]
        lines += [f"| {r['set']} | {fmt(float(r['h']))} | {fmt(1e3 * float(r['python_s_per_step']))} "
                  f"({100 * float(r['python_spread']):.0f} %) | {fmt(1e3 * float(r['c_s_per_step']))} "
                  f"({100 * float(r['c_spread']):.0f} %) | **{r['ratio_python_over_c']}** "
                  f"({r['ratio_q1']} – {r['ratio_q3']}) | {r['ratio_of_best']} |" for r in st]
        lines.append("")
    cb = read_csv(page, "python_callback.csv")
    if cb:
        lines += [f"Python right-hand side (the pendulum: f's arithmetic {cb[0]['f_ns']} ns, the "
                  f"bare Python call {cb[0]['call_ns']} ns): the ns beyond f's arithmetic per "
                  "CEODE step and per solve_ivp evaluation (`python_callback.csv`):", "",
                  "| solver | configuration | steps | f evaluations | ns per step | ns per evaluation |",
                  "|---|---|---|---|---|---|"]
        lines += [f"| {r['solver']} | {r['config']} | {r['steps']} | {r['rhs_evals']} | "
                  f"{r['overhead_ns_per_step']} | **{r['overhead_ns_per_eval']}** |" for r in cb]
        lines.append("")
    eq = read_csv(page, "python_ratios.csv")
    if eq:
        lines += ["At equal error, CEODE's fastest curve (Python f) against solve_ivp on the same f, "
                  "interpolated in log-log (`python_ratios.csv`):", "",
                  "| problem | error | CEODE best | s | CEODE / RK45 | CEODE / DOP853 |",
                  "|---|---|---|---|---|---|"]
        lines += [f"| {r['scene']} | {r['error_level']} | {r['ceode_best']} | "
                  f"{r['ceode_seconds'] or '–'} | **{r['ratio_ceode_over_rk45'] or '–'}** | "
                  f"**{r['ratio_ceode_over_dop853'] or '–'}** |" for r in eq]
        lines.append("")
        for scene in dict.fromkeys(r["scene"] for r in eq):
            lines += image(page, f"{scene}.png", f"{scene} work-precision")
        lines.append("")
    if page.exists("python_plate_tip.png"):
        lines += ["The example `examples/python/plate_tip.py` (its checked run of this job, "
                  "`python_example.txt`):", ""] + image(page, "python_plate_tip.png",
                                                       "plate tip displacement")
    return lines


def write(results, out_path):
    page = Page(results)
    ratios_path = page.path("ratios.csv")
    rows = summary_table.read_rows(ratios_path) if os.path.exists(ratios_path) else []
    bs_name, bs, cvs = bench_step(page)
    mpi_runs = [(label, *mpi(page, stem)) for stem, label in
                (("mpi_scaling", "membrane"), ("mpi_fe_plate", "Q4 plate"))]
    ho = high_order(page)[1]
    mri_name, mri_best = mri(page)

    page.add("# Results: CEODE side by side with SUNDIALS and other integrators", "",
             "<!-- Generated by scripts/results_page.py from docs/results/ (scripts/main_job.sh). "
             "Do not edit: the next run overwrites it. -->", "",
             "Each scene runs CEODE, ARKODE, CVODE and IDA (and, where they apply, Boost.Odeint, GSL "
             "and a hand-written loop of CEODE's method) on one problem and reports error against CPU "
             "time. The headline figures use SUNDIALS built `-O3`; the column \"CEODE / SUNDIALS, -O0 "
             "package\" is the same scene run against the unoptimised SUNDIALS package. Why the code "
             "is shaped as it is: [performance.md](performance.md).", "")
    how_measured(page, run_info(page), cvs, [(f"MPI {label}", s) for label, n, _, s in mpi_runs if n])
    section(page, "## Summary at equal error",
            "Ratios of CPU time to reach the error, one per error level, in the order of the error "
            "column; –: not measured or a level one side does not reach. FE levels are relative "
            "position errors. Each scene below has the full row: which configurations were best and "
            "their times.", compact_summary(rows) if rows else [], "No `ratios.csv` in this run.")
    section(page, "### Summary chart",
            "The fastest CEODE configuration against the fastest curve of each kind of competitor "
            "at every error level, from the scene CSVs (`scripts/plot_summary.py`, the same "
            "interpolation as the table); bars to the right of 1 (hatched) are where CEODE is "
            "slower.", image(page, "summary_ratios.png", "speed ratios at equal error"),
            "Not drawn: its data are absent.")
    section(page, "## Where CEODE loses", "Every ratio above 1 in this run, from the data. Where a scene has a hand-written "
            "loop, a loss to a peer also gives the fastest hand loop's time over that peer's: "
            "above 1, the method itself loses there, not only the library's overhead.",
            losses_lines(rows, bs, ho, mri_best), "Nowhere in this run.")
    section(page, "## Which set",
            "Every named set's order in x against its stability limit Ω_max = ω_max·h (undamped; "
            "the arrow goes to the limit at damping ratio ξ = 0.05), ringed by its long-run "
            "behaviour on the pendulum and the oscillator at h = 1e-3 and 2e-3, the worst of the "
            "four runs. Orders and limits are computed by the library (`CEodeMethodOrder`, "
            "`CEodeStabilityLimit`, written to `docs/data/set_summary.csv`), the long-run classes "
            "come from `docs/data/long_run_*.csv` ([stability.md](stability.md)). Up and to the "
            "right is better." + damping_note(page),
            image(page, "which_set.png", "order against stability limit for every set"),
            "Not drawn: its data are absent.")
    section(page, "## Long runs: energy error against time",
            "10⁷ steps of h = 1e-3 (10⁴ s) on the pendulum and the linear oscillator, the largest "
            "|E − E0| over the first 1 %, the 1 % before T/2 and the last 1 % of the run (the "
            "windows the study keeps, `docs/data/long_run_*.csv`); × marks a blow-up. Flat is "
            "bounded (G3_CD only), slope 1 is a linear drift, steeper is growth. "
            "([stability.md](stability.md#long-runs-what-each-set-conserves))",
            image(page, "long_run_energy.png", "long-run energy error against time"),
            "Not drawn: its data are absent.")
    page.add("## Scenes", "",
             "Each figure is the scene's -O3 run in panels that share their axes: the headline "
             "CEODE curves (the fastest at each error level, the recommended sets G5_O4, G8_O8 "
             "and G4_A34 and the fastest error-control curve, those the scene ran) against every "
             "SUNDIALS curve, the same CEODE curves against Boost.Odeint and GSL, then every "
             "CEODE configuration. A method has one colour and marker in every figure; CEODE is "
             "solid, the others dashed; dotted lines mark the error levels of the ratios.", "")
    for name, title, sentence in SCENES:
        scene_section(page, rows, name, title, sentence)
    name, title, sentence = HIGH_ORDER
    section(page, f"### {title} (`{name}`)", sentence, high_order_lines(page, ho))
    section(page, "### Chain of N pendulums: cost per step against N (`chain_dae`)",
            "CEODE alone (G3_CD, sparse saddle point with KLU), 1 000 steps per size; linear growth "
            "is slope 1.", chain_lines(page))
    section(page, "## Per-step cost against a hand-written loop (`bench_step`)",
            "n independent springs on the explicit path, h = 1e-3, CEODE integrating to a distant "
            "`tout` against a hand loop of the same method that calls f as its own pass; median CPU "
            "time per step, ratio CEODE / hand loop.", bench_step_lines(bs_name, bs))
    section(page, "## MPI: 1 → 2 ranks at N = 10⁶ (`NVECTOR_PARALLEL`)",
            "Each model partitioned over ranks with a halo exchange in f; best of the repetitions. "
            "The hand loop runs the same method on the same partition: its speedup is what the "
            "machine gives.", mpi_lines(mpi_runs), "Not run in this job (no `mpiexec`, or no MPI build).")
    section(page, "## CEODE as MRIStep's inner stepper (`mri_inner_cost`)",
            "Fast evaluations CEODE needs to match the MRI error of an almost exact inner solve, "
            "over RK4's, for each slow step H (largest first); counts, not timings.",
            mri_lines(mri_name, mri_best))
    section(page, "## Python (`ceode` module, `bench/python/`)",
            "The Python module on the C scenes' models: the structural path's time per step against "
            "the C scene, the overhead of a Python right-hand side against solve_ivp's, and "
            "work-precision against scipy's solve_ivp RK45 and DOP853 on the same f "
            "([bench/python/README.md](../bench/python/README.md)).",
            python_lines(page), "Not run in this job (the module was not built).")
    page.add("## Files", "",
             "`docs/results/<scene>.csv` (schema `scene,solver,config,h_or_tol,error,drift,steps,"
             "rhs_evals,seconds`) and `<scene>.txt` for the unoptimised SUNDIALS, `<scene>_o3.*` for "
             "the `-O3` build; `ratios.csv`; `bench_step[_o3].json`; `mpi_*`, `mri_inner_cost*`; "
             "`run_info.json`; `python_*.csv`, `.txt`, `.png` (bench/python/); the charts "
             "`summary_ratios.png` (scripts/plot_summary.py), "
             "`which_set.png` (scripts/plot_which_set.py), `long_run_energy.png` "
             "(scripts/plot_long_run.py) and `<scene>[_o3]_drift.png` (scripts/plot_dae.py). "
             "Regenerate this page with "
             "`/usr/bin/python3 scripts/results_page.py`.")
    text = "\n".join(page.lines).rstrip() + "\n"
    with open(out_path, "w") as f:
        f.write(text)
    return text


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    root = os.path.dirname(HERE)
    ap.add_argument("--results", default=os.path.join(root, "docs", "results"))
    ap.add_argument("--out", default=os.path.join(root, "docs", "results.md"))
    args = ap.parse_args()
    text = write(args.results, args.out)
    print(f"wrote {args.out} ({text.count(chr(10))} lines)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
