"""One look per method for every plot of the project (work-precision, summary, long-run, which-set).

Every method keeps its colour and marker in every figure: a CEODE parameter set by its name
(G5_O4 is red triangles wherever it appears, fixed step or error control), every SUNDIALS
integrator, Boost.Odeint and GSL stepper by its own entry. CEODE is drawn solid with filled
markers, every other integrator dashed with open markers, the hand-written loop of CEODE's method
dotted grey. Two curves of one method in one axes (a set in two modes, a solver with two linear
solvers) keep the colour and the marker and differ in the marker's fill and the line's dashes.

Used by plot_results.py, plot_dae.py, plot_wp_high_order.py, plot_summary.py,
plot_long_run.py and plot_which_set.py.
"""
import re

import matplotlib

matplotlib.use("Agg")  # files only, no display needed
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import LogFormatterSciNotation  # noqa: E402

# CEODE's named sets: (colour, marker). Distinct hues for the sets users pick most (G3_CD,
# G4_A34, G5_O4, G8_O8); the paper's weakly unstable sets in muted tones.
CEODE_SETS = {
    "G3_CD": ("#000000", "o"),
    "G3_A43": ("#8c564b", "<"),
    "G3_A2": ("#b5a300", ">"),
    "G4_A14": ("#17becf", "v"),
    "G4_A34": ("#ff7f0e", "s"),
    "G4_A54": ("#7f7f7f", "x"),
    "G5": ("#9467bd", "D"),
    "G5_TOP": ("#e377c2", "P"),
    "G5_ONES": ("#8c6d31", "H"),
    "G5_O4": ("#d62728", "^"),
    "G6_O5": ("#2ca02c", "p"),
    "G6_O6": ("#637939", "d"),
    "G7_O7": ("#7b4173", "X"),
    "G8_O8": ("#1f77b4", "*"),
}
HAND = ("#555555", "x")

# Every other integrator: key -> (colour, marker, label). Keys come from other_key().
OTHERS = {
    "ARKODE RK3": ("#8c2d04", "s", "ARKODE RK3, fixed h"),
    "ARKODE RK3+proj": ("#8c8ce0", "D", "ARKODE RK3 + projection, fixed h"),
    "ARKODE-ERK adaptive": ("#009e73", "o", "ARKODE ERK adaptive, order 4"),
    "ARKODE-ERK order3": ("#56b4e9", "v", "ARKODE ERK adaptive, order 3"),
    "ARKODE-ERK order5": ("#004c6d", "p", "ARKODE ERK adaptive, order 5"),
    "ARKODE-ERK order6": ("#5e3c99", "h", "ARKODE ERK adaptive, order 6"),
    "ARKODE-ERK order8": ("#cc79a7", "*", "ARKODE ERK adaptive, order 8"),
    "ARKODE-DIRK": ("#999999", "<", "ARKODE DIRK"),
    "ARKODE-IMEX": ("#b15928", ">", "ARKODE IMEX"),
    "CVODE-Adams": ("#e6ab02", "^", "CVODE Adams"),
    "CVODE-BDF": ("#6a3d9a", "v", "CVODE BDF"),
    "IDA": ("#e7298a", "h", "IDA (BDF, GGL form)"),
    "odeint rk4": ("#66a61e", "o", "odeint rk4, fixed h"),
    "odeint rkf78": ("#8c510a", "X", "odeint rkf78"),
    "odeint dopri5": ("#1b9e77", "d", "odeint dopri5"),
    "odeint bulirsch_stoer": ("#a6761d", "H", "odeint Bulirsch-Stoer"),
    "odeint velocity_verlet": ("#737373", "1", "odeint velocity Verlet, fixed h"),
    "odeint sb3a_mclachlan": ("#01665e", "2", "odeint McLachlan SB3A, fixed h"),
    "GSL rk8pd": ("#00ced1", "*", "GSL rk8pd"),
    "GSL rkf45": ("#80b1d3", "P", "GSL rkf45"),
    "GSL msadams": ("#bc80bd", "D", "GSL msadams"),
    "DPRKN6": ("#4d4d4d", "8", "DPRKN6 (Runge-Kutta-Nystrom 6(4))"),
}
# The summary chart's bars: one colour per kind of competitor.
FAMILY_COLOURS = {"SUNDIALS": "#009e73", "Boost.Odeint": "#66a61e", "GSL": "#00ced1",
                  "hand loop": "#555555"}
SPARE = ["#8dd3c7", "#bebada", "#fb8072", "#b3de69", "#fccde5", "#ccebc5", "#ffed6f"]
SUNDIALS_PREFIXES = ("ARKODE", "CVODE", "IDA")
PEER_SOLVERS = ("odeint", "GSL", "DPRKN6")
_SET = re.compile(r"G[3-8](?:_[A-Z0-9]+)?")

# Configurations that add nothing to the method's name in a legend.
TRIVIAL = {"", "adaptive", "fixed h", "adaptive tol", "rk3-kutta", "bdf-ggl", "order3", "order4",
           "order5", "order8", "rk3", "rk3+proj"}

# Axis text shared by the work-precision plots.
TIME_LABEL = "CPU time per run [s] (median of the repetitions)"


def normalise(solver, config):
    """(solver, config) in the work-precision schema's spelling. wp_high_order names its curves
    by the set (solver "G5_O4", "G5_O4 adaptive") or the peer ("gsl_rk8pd")."""
    low = solver.lower()
    if _SET.fullmatch(solver.split()[0].split("+")[0]):
        return "CEODE", solver.replace("+comp", " compensated")
    peers = {"gsl_rk8pd": ("GSL", "rk8pd"), "odeint_rkf78": ("odeint", "rkf78"),
             "odeint_bs": ("odeint", "bulirsch_stoer"), "arkode_erk8": ("ARKODE-ERK", "order8")}
    return peers.get(low, (solver, config))


def family(solver):
    """'ceode', 'hand', 'sundials' or 'peer' (Boost.Odeint, GSL, DPRKN6) of a normalised solver."""
    if solver == "CEODE":
        return "ceode"
    if solver.startswith("CEODE"):
        return "hand"
    if solver.upper().startswith(SUNDIALS_PREFIXES):
        return "sundials"
    return "peer"


def ceode_set(config):
    """The named set a CEODE configuration runs ('G5_O4-AUTO adaptive' -> 'G5_O4'), or None."""
    m = _SET.match(config)
    if m and m.group(0) in CEODE_SETS:
        return m.group(0)
    m = _SET.search(config)
    return m.group(0) if m and m.group(0) in CEODE_SETS else None


def is_adaptive(config):
    """A CEODE error-control curve (h_or_tol is the tolerance)."""
    return "adaptive" in config


def other_key(solver, config):
    """OTHERS key of a SUNDIALS or peer curve."""
    c = config.lower()
    if solver.startswith("ARKODE"):
        if "rk3+proj" in c:
            return "ARKODE RK3+proj"
        if c.startswith("rk3"):
            return "ARKODE RK3"
        for order in ("3", "5", "6", "8"):
            if f"order{order}" in c or f"order {order}" in c:
                return f"ARKODE-ERK order{order}"
        if "verner" in c:
            return "ARKODE-ERK order6"
        if "fehlberg" in c:
            return "ARKODE-ERK order8"
        if solver in ("ARKODE-DIRK", "ARKODE-IMEX"):
            return solver
        return "ARKODE-ERK adaptive"
    if solver.startswith("CVODE"):
        return "CVODE-BDF" if "BDF" in solver else "CVODE-Adams"
    if solver.startswith("IDA"):
        return "IDA"
    if solver == "DPRKN6":
        return "DPRKN6"
    return f"{solver} {config}"


def key(solver, config):
    """The method a curve belongs to: one colour and marker per key."""
    fam = family(solver)
    if fam == "ceode":
        return ceode_set(config) or config
    if fam == "hand":
        return "hand " + (ceode_set(config) or ("G3_CD" if "CD" in config else config))
    return other_key(solver, config)


def base_style(solver, config):
    """(colour, marker) of the curve's method."""
    fam, k = family(solver), key(solver, config)
    if fam == "ceode":
        return CEODE_SETS.get(k, (SPARE[sum(map(ord, k)) % len(SPARE)], "o"))
    if fam == "hand":  # the colour of the set it hand-codes
        return CEODE_SETS.get(k[len("hand "):], HAND)[0], "x"
    if k in OTHERS:
        return OTHERS[k][:2]
    return SPARE[sum(map(ord, k)) % len(SPARE)], "o"


def label(solver, config):
    """Legend text: CEODE curves by their configuration, the others by name and configuration."""
    fam = family(solver)
    if fam == "ceode":
        return "CEODE " + config
    if fam == "hand":
        return f"hand loop {config}"
    k = other_key(solver, config)
    name = OTHERS[k][2] if k in OTHERS else f"{solver} {config}"
    extra = "" if k not in OTHERS or config.lower() in TRIVIAL or k.startswith(PEER_SOLVERS) \
        else config
    return f"{name} ({extra})" if extra else name


def style(solver, config, variant=0):
    """matplotlib keyword arguments of one curve. variant > 0: another curve of the same method in
    the same axes (open / half-filled marker, other dashes)."""
    colour, marker = base_style(solver, config)
    fam = family(solver)
    kw = dict(color=colour, marker=marker, ms=5 if marker != "*" else 7, lw=1.4)
    if fam == "ceode":
        kw.update(linestyle=["-", (0, (6, 1.5)), (0, (3, 1, 1, 1)), (0, (1, 1))][variant % 4],
                  fillstyle=["full", "none", "bottom", "left"][variant % 4])
    elif fam == "hand":
        kw.update(linestyle=":", lw=1.2, fillstyle="full" if variant == 0 else "none")
    else:
        kw.update(linestyle=["--", (0, (2, 2)), (0, (5, 2, 1, 2)), (0, (8, 3))][variant % 4],
                  fillstyle="none", lw=1.2, markeredgewidth=1.2)
    return kw


def draw_curves(ax, curves, xkey="seconds", ykey="error"):
    """Draws [(solver, config, points)] on log-log axes, each method in its style; returns the
    number of curves drawn. Two curves of one method get variants 0, 1, ..."""
    seen = {}
    n = 0
    for solver, config, pts in curves:
        if not pts:
            continue
        k = (family(solver), key(solver, config))
        variant = seen.get(k, 0)
        seen[k] = variant + 1
        ax.loglog([p[xkey] for p in pts], [p[ykey] for p in pts], label=label(solver, config),
                  **style(solver, config, variant))
        n += 1
    return n


def grid(ax):
    """Grid lines; on a log axis spanning less than about two decades the minor ticks get numbers
    too (2, 3, 5 x 10^k), so that every panel has more than one labelled tick."""
    for axis in (ax.xaxis, ax.yaxis):
        if axis.get_scale() == "log":
            axis.set_minor_formatter(LogFormatterSciNotation(labelOnlyBase=False,
                                                             minor_thresholds=(2, 0.5)))
    ax.tick_params(which="minor", labelsize=7)
    ax.grid(True, which="major", alpha=0.4)
    ax.grid(True, which="minor", alpha=0.12)


def legend_below(ax, ncol=2, fontsize=7):
    """The legend under the axes, never over the data."""
    handles, labels = ax.get_legend_handles_labels()
    if handles:
        ax.legend(handles, labels, fontsize=fontsize, ncol=ncol, loc="upper center",
                  bbox_to_anchor=(0.5, -0.13), frameon=False)


def save(fig, path, dpi=110):
    fig.savefig(path, dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    print(f"wrote {path}")
