"""The report tooling of the main job: scripts/wp_curves.py (time to reach an error on a
work-precision curve), scripts/ratios.py (CEODE / best SUNDIALS and / best peer at equal error) and
scripts/summary_table.py (the summary table of docs/results.md), on curves made here whose times at
every error are known in closed form. Standard library only, so any python3 runs it.

Run: python3 -m unittest discover -s test/report (ctest: report_tools).
"""
import csv
import math
import os
import subprocess
import sys
import tempfile
import unittest

SCRIPTS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts")
sys.path.insert(0, SCRIPTS)
import wp_curves  # noqa: E402

HEADER = ["scene", "solver", "config", "h_or_tol", "error", "drift", "steps", "rhs_evals", "seconds"]


def power_curve(c, p, hs):
    """Points of error = c h^p and seconds = 1e-3 / h: log-log straight, so the time to reach
    an error e is exactly 1e-3 (c / e)^(1/p)."""
    return [{"h_or_tol": h, "error": c * h ** p, "seconds": 1e-3 / h, "steps": int(1 / h)}
            for h in hs]


def exact_time(c, p, level):
    return 1e-3 * (c / level) ** (1.0 / p)


def write_scene(path, scene, curves):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(HEADER)
        for (solver, config), pts in curves.items():
            for pt in pts:
                w.writerow([scene, solver, config, pt["h_or_tol"], pt["error"], 0, pt["steps"],
                            pt["steps"], pt["seconds"]])


HS = [0.1, 0.05, 0.02, 0.01, 0.005, 0.002, 0.001]


class TimeToReach(unittest.TestCase):
    def test_interpolates_a_log_log_straight_curve_exactly(self):
        pts = power_curve(2.0, 4, HS)
        for level in (1e-6, 3.3e-8, 1e-9):
            got = wp_curves.time_to_reach(pts, level)
            self.assertEqual(got[1], "interp")
            self.assertAlmostEqual(got[0] / exact_time(2.0, 4, level), 1.0, places=12)

    def test_takes_a_measured_point_when_the_curve_starts_below_the_level(self):
        pts = power_curve(1.0, 2, HS)  # errors 1e-2 .. 1e-6
        got = wp_curves.time_to_reach(pts, 0.5)
        self.assertEqual(got, (pts[0]["seconds"], "point"))

    def test_says_none_when_the_curve_never_gets_down_to_the_level(self):
        self.assertIsNone(wp_curves.time_to_reach(power_curve(1.0, 2, HS), 1e-9))

    def test_skips_failed_and_non_finite_points(self):
        pts = power_curve(2.0, 4, HS)
        broken = pts[:3] + [dict(pts[3], error=float("nan")), dict(pts[3], seconds=-1.0)] + pts[3:]
        level = 1e-7
        self.assertAlmostEqual(wp_curves.time_to_reach(broken, level)[0],
                               wp_curves.time_to_reach(pts, level)[0], delta=0)

    def test_takes_the_cheapest_crossing_of_a_curve_that_turns_back_up(self):
        pts = power_curve(2.0, 4, HS[:5])  # down to 1.25e-9, then a round-off floor that rises
        pts += [{"h_or_tol": 0.002, "error": 1e-8, "seconds": 0.5, "steps": 500}]
        got = wp_curves.time_to_reach(pts, 1e-8)
        self.assertAlmostEqual(got[0] / exact_time(2.0, 4, 1e-8), 1.0, places=12)


class RatiosAndSummary(unittest.TestCase):
    """Two builds of one scene (Debian's and -O3) and an FE scene with its own levels."""

    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        d = self.dir.name
        # CEODE twice as fast as ARKODE at every error (same order), the peer four times faster
        # than CEODE, the hand loop at 0.8 of CEODE; a SUNDIALS curve that never reaches 1e-11.
        def scene(cvode_c):
            return {
                ("CEODE", "G4_A34"): power_curve(1.0, 4, HS),
                ("CEODE", "G3_CD"): power_curve(100.0, 2, HS),
                ("ARKODE-ERK", "order4"): power_curve(16.0, 4, HS),
                ("CVODE-BDF", "adaptive"): power_curve(cvode_c, 1, HS),
                ("odeint", "rk4"): power_curve(1.0 / 256, 4, HS),
                ("CEODE-hand", "G4_A34"): [dict(p, seconds=0.8 * p["seconds"])
                                           for p in power_curve(1.0, 4, HS)],
            }
        self.debian = os.path.join(d, "toy.csv")
        self.o3 = os.path.join(d, "toy_o3.csv")
        write_scene(self.debian, "toy", scene(1e-5))  # first order: best at 1e-6 only
        write_scene(self.o3, "toy", scene(1.0))  # never below 1e-3
        self.fe = os.path.join(d, "fe_toy.csv")
        write_scene(self.fe, "fe_toy", {("CEODE", "G3_CD"): power_curve(1.0, 2, HS),
                                        ("ARKODE-ERK", "order3"): power_curve(9.0, 2, HS)})
        self.out = os.path.join(d, "ratios.csv")
        subprocess.run([sys.executable, os.path.join(SCRIPTS, "ratios.py"), "--out", self.out,
                        "--levels", "1e-6,1e-9,1e-11", "--scene-levels", "fe_=1e-4",
                        self.debian, self.o3, self.fe],
                       check=True, stdout=subprocess.DEVNULL)
        with open(self.out, newline="") as f:
            self.rows = list(csv.DictReader(f))

    def tearDown(self):
        self.dir.cleanup()

    def row(self, scene, build, level):
        return next(r for r in self.rows if r["scene"] == scene and
                    r["sundials_build"] == build and r["error_level"] == level)

    def test_puts_the_o3_rows_of_a_scene_first(self):
        builds = [r["sundials_build"] for r in self.rows if r["scene"] == "toy"]
        self.assertEqual(builds, ["6.4.1 -O3"] * 3 + ["6.4.1 -O0"] * 3)

    def test_divides_the_best_ceode_by_the_best_sundials_and_the_best_peer_at_equal_error(self):
        r = self.row("toy", "6.4.1 -O3", "1e-09")
        self.assertEqual(r["ceode_best"], "CEODE G4_A34")
        self.assertEqual(r["sundials_best"], "ARKODE-ERK order4")
        self.assertAlmostEqual(float(r["ratio_ceode_over_sundials"]), 0.5, places=2)
        self.assertEqual(r["peer_best"], "odeint rk4")
        self.assertAlmostEqual(float(r["ratio_ceode_over_peer"]), 4.0, places=2)
        self.assertAlmostEqual(float(r["ceode_seconds"]), exact_time(1.0, 4, 1e-9), delta=1e-3 *
                               exact_time(1.0, 4, 1e-9))
        self.assertAlmostEqual(float(r["hand_loop_seconds"]) / float(r["ceode_seconds"]), 0.8,
                               places=2)

    def test_picks_the_sundials_curve_that_is_fastest_at_each_level(self):
        # Debian's first-order CVODE curve beats ARKODE at 1e-6 and never reaches 1e-9.
        self.assertEqual(self.row("toy", "6.4.1 -O0", "1e-06")["sundials_best"],
                         "CVODE-BDF adaptive")
        self.assertEqual(self.row("toy", "6.4.1 -O0", "1e-09")["sundials_best"],
                         "ARKODE-ERK order4")

    def test_reports_a_level_one_side_never_reaches_without_a_ratio(self):
        r = self.row("toy", "6.4.1 -O3", "1e-11")  # ARKODE's best error is 1.6e-11
        self.assertEqual(r["ceode_best"], "CEODE G4_A34")
        self.assertEqual(r["sundials_best"], "not reached")
        self.assertEqual(r["ratio_ceode_over_sundials"], "")
        r = self.row("fe_toy", "6.4.1 -O0", "1e-04")
        self.assertAlmostEqual(float(r["ratio_ceode_over_sundials"]), 1.0 / 3, places=2)
        self.assertEqual(r["peer_best"], "")  # the scene has no peers

    def test_uses_the_scene_levels_for_matching_scenes_only(self):
        self.assertEqual([r["error_level"] for r in self.rows if r["scene"] == "fe_toy"], ["1e-04"])

    def test_summary_table_has_one_row_per_scene_and_level_with_the_o3_ratio_in_bold(self):
        out = subprocess.run([sys.executable, os.path.join(SCRIPTS, "summary_table.py"), self.out],
                             check=True, capture_output=True, text=True).stdout
        lines = [l for l in out.splitlines() if l.startswith("| toy") or l.startswith("| fe_toy")]
        self.assertEqual(len(lines), 4)
        cells = [c.strip() for c in lines[1].split("|")[1:-1]]
        self.assertEqual(cells[:3], ["toy", "1e-09", "G4_A34"])
        self.assertEqual(cells[6], "**" + self.row("toy", "6.4.1 -O3", "1e-09")[
            "ratio_ceode_over_sundials"] + "**")
        self.assertEqual(cells[10], self.row("toy", "6.4.1 -O0", "1e-09")[
            "ratio_ceode_over_sundials"])
        self.assertAlmostEqual(float(cells[11]), 1 / 0.8, places=2)
        self.assertIn("(-O0)", lines[3])  # the FE scene has only the Debian half



class BestCeodeOverEverySet(unittest.TestCase):
    """A fixed-step set fastest at loose errors, an error-control curve of another set at tight
    ones: the best CEODE curve is picked over all of them at each level, and the summary names
    that curve's set and mode."""

    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        d = self.dir.name
        # G5 fixed: 1e-3 (1 / e)^(1/5) s; G8_O8 adaptive: 1e-3 (1e4 / e)^(1/8) s. G5 is faster at
        # 1e-6 (0.0158 s against 0.0178 s), G8_O8 adaptive at 1e-11 (0.075 s against 0.158 s).
        path = os.path.join(d, "sets.csv")
        write_scene(path, "sets", {
            ("CEODE", "G5"): power_curve(1.0, 5, HS),
            ("CEODE", "G8_O8 adaptive"): power_curve(1e4, 8, HS),
            ("CEODE", "G3_CD"): power_curve(100.0, 2, HS),
            ("ARKODE-ERK", "order8"): power_curve(1e6, 8, HS),
            ("GSL", "rk8pd"): power_curve(1e3, 8, HS),
        })
        self.out = os.path.join(d, "ratios.csv")
        subprocess.run([sys.executable, os.path.join(SCRIPTS, "ratios.py"), "--out", self.out,
                        "--levels", "1e-6,1e-11", path], check=True, stdout=subprocess.DEVNULL)
        with open(self.out, newline="") as f:
            self.rows = {r["error_level"]: r for r in csv.DictReader(f)}

    def tearDown(self):
        self.dir.cleanup()

    def test_picks_the_fastest_ceode_curve_over_fixed_and_adaptive_sets_at_each_level(self):
        loose, tight = self.rows["1e-06"], self.rows["1e-11"]
        self.assertEqual(loose["ceode_best"], "CEODE G5")
        self.assertAlmostEqual(float(loose["ceode_seconds"]), exact_time(1.0, 5, 1e-6),
                               delta=1e-3 * exact_time(1.0, 5, 1e-6))
        self.assertEqual(tight["ceode_best"], "CEODE G8_O8 adaptive")
        self.assertAlmostEqual(float(tight["ceode_seconds"]), exact_time(1e4, 8, 1e-11),
                               delta=1e-3 * exact_time(1e4, 8, 1e-11))
        # Same order 8: the peer's time over CEODE's is (1e3 / 1e4)^(1/8) at every level.
        self.assertAlmostEqual(float(tight["ratio_ceode_over_peer"]), 10 ** (1 / 8), places=2)

    def test_summary_names_the_set_and_mode_of_the_best_curve(self):
        out = subprocess.run([sys.executable, os.path.join(SCRIPTS, "summary_table.py"), self.out],
                             check=True, capture_output=True, text=True).stdout
        cells = {l.split("|")[2].strip(): [c.strip() for c in l.split("|")[1:-1]]
                 for l in out.splitlines() if l.startswith("| sets")}
        self.assertEqual(cells["1e-06"][2], "G5")
        self.assertEqual(cells["1e-11"][2], "G8_O8 adaptive")


if __name__ == "__main__":
    unittest.main()
