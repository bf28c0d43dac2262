"""The plotting scripts of the main job: one style per method (scripts/plot_style.py), the
panels and headline curves of a work-precision figure (scripts/plot_results.py), the summary
chart's ratios (scripts/plot_summary.py) and the skipping of absent data. Needs matplotlib
(Debian: python3-matplotlib); skipped without it.

Run: python3 -m unittest discover -s test/report (ctest: report_tools).
"""
import contextlib
import io
import os
import sys
import tempfile
import unittest
from collections import OrderedDict

SCRIPTS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts")
sys.path.insert(0, SCRIPTS)
try:
    import matplotlib  # noqa: F401
    HAVE_MPL = True
except ImportError:
    HAVE_MPL = False

if HAVE_MPL:
    import plot_dae
    import plot_results
    import plot_style as ps
    import plot_summary
    from test_report_tools import HS, exact_time, power_curve, write_scene


@unittest.skipUnless(HAVE_MPL, "matplotlib is not installed")
class StyleMap(unittest.TestCase):
    def test_every_method_has_a_colour_and_marker_pair_of_its_own(self):
        pairs = [v for v in ps.CEODE_SETS.values()] + [v[:2] for v in ps.OTHERS.values()]
        self.assertEqual(len(pairs), len(set(pairs)))
        colours = [c for c, _ in ps.CEODE_SETS.values()]
        self.assertEqual(len(colours), len(set(colours)), "two CEODE sets share a colour")

    def test_a_set_keeps_its_colour_in_every_mode(self):
        for config in ("G5_O4", "G5_O4-AUTO adaptive", "G5_O4 adaptive", "G5_O4-auto"):
            self.assertEqual(ps.base_style("CEODE", config), ps.CEODE_SETS["G5_O4"], config)
        self.assertEqual(ps.key("CEODE", "G5_ONES KLU"), "G5_ONES")
        self.assertEqual(ps.key("CEODE-hand", "CD-damped"), "hand G3_CD")

    def test_reads_the_high_order_scene_names_as_the_common_schema(self):
        self.assertEqual(ps.normalise("G8_O8+comp", "fixed h"), ("CEODE", "G8_O8 compensated"))
        self.assertEqual(ps.normalise("G5_O4 adaptive", "adaptive tol"), ("CEODE", "G5_O4 adaptive"))
        self.assertEqual(ps.normalise("gsl_rk8pd", "adaptive tol"), ("GSL", "rk8pd"))
        self.assertEqual(ps.family("ARKODE-ERK"), "sundials")
        self.assertEqual(ps.family("odeint"), "peer")

    def test_ceode_is_solid_and_every_other_integrator_dashed(self):
        self.assertEqual(ps.style("CEODE", "G3_CD")["linestyle"], "-")
        self.assertEqual(ps.style("odeint", "rk4")["linestyle"], "--")
        self.assertEqual(ps.style("CVODE-BDF", "adaptive")["linestyle"], "--")


def curves_of(spec):
    """OrderedDict (solver, config) -> points of error c h^p, seconds 1e-3 / h."""
    return OrderedDict(((s, c), [dict(p, drift=0.0) for p in power_curve(k, p, HS)])
                       for s, c, k, p in spec)


@unittest.skipUnless(HAVE_MPL, "matplotlib is not installed")
class Panels(unittest.TestCase):
    def test_headline_holds_the_fastest_set_and_the_recommended_ones(self):
        spec = [("CEODE", f"G{d}_X{i}", 1.0, 2) for d, i in ((3, 1), (3, 2), (4, 3))]
        spec += [("CEODE", "G8_O8", 1e3, 8), ("CEODE", "G5_O4", 10.0, 4), ("CEODE", "G3_CD", 0.5, 2)]
        head = plot_results.headline(curves_of(spec), "pendulum_ode")
        self.assertIn(("CEODE", "G8_O8"), head)  # fastest at 1e-11 (and recommended)
        self.assertIn(("CEODE", "G5_O4"), head)
        self.assertLessEqual(len(head), plot_results.MAX_HEADLINE)

    def test_splits_many_ceode_curves_into_panels_of_at_most_ten(self):
        sets = list(ps.CEODE_SETS)
        spec = [("CEODE", s, 1.0 + i, 2) for i, s in enumerate(sets)]
        spec += [("CEODE", s + "-auto", 1.0 + i, 2) for i, s in enumerate(sets)]
        spec += [("ARKODE-ERK", "adaptive", 1.0, 4), ("odeint", "rk4", 1.0, 4)]
        out = plot_results.scene_panels("damped_pendulum", curves_of(spec))
        drawn = [len(items) for title, items in out if title.startswith("CEODE")]
        self.assertTrue(drawn and max(drawn) <= plot_results.MAX_CURVES, drawn)
        self.assertEqual(sum(drawn), 2 * len(sets))  # every CEODE curve in some panel

    def test_a_missing_csv_is_skipped_with_a_message(self):
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            self.assertEqual(plot_dae.plot_file("/nonexistent/pendulum_dae_o3.csv", "/tmp"), 0)
        self.assertIn("missing, skipped", out.getvalue())


@unittest.skipUnless(HAVE_MPL, "matplotlib is not installed")
class SummaryChart(unittest.TestCase):
    def test_ratio_is_the_fastest_ceode_over_the_fastest_of_each_kind(self):
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "pendulum_ode_o3.csv")
            write_scene(path, "pendulum_ode", {
                ("CEODE", "G5_O4"): power_curve(10.0, 4, HS),
                ("ARKODE-ERK", "adaptive"): power_curve(2.0, 3, HS),
                ("odeint", "rk4"): power_curve(1.0, 4, HS),
                ("GSL", "rk8pd"): power_curve(1e3, 8, HS)})
            rows = plot_summary.rows_of(path)
        lab, ratios, _ = rows[0]
        self.assertEqual(lab, "pendulum_ode @ 1e-06")
        lv = 1e-6
        want = {"SUNDIALS": exact_time(10.0, 4, lv) / exact_time(2.0, 3, lv),
                "Boost.Odeint": exact_time(10.0, 4, lv) / exact_time(1.0, 4, lv),
                "GSL": exact_time(10.0, 4, lv) / exact_time(1e3, 8, lv)}
        for k, v in want.items():
            self.assertAlmostEqual(ratios[k][0] / v, 1.0, places=9, msg=k)

    def test_draws_nothing_and_succeeds_without_scene_csvs(self):
        with tempfile.TemporaryDirectory() as d, contextlib.redirect_stdout(io.StringIO()):
            self.assertEqual(plot_summary.collect(d), [])


if __name__ == "__main__":
    unittest.main()
