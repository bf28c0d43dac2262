#!/usr/bin/env python3
"""Work-precision figure of bench/wp_high_order's CSV (docs/results/wp_high_order[_o3].csv):
one row of panels per problem, drawn by plot_results.py in the project's common style.

usage: /usr/bin/python3 scripts/plot_wp_high_order.py [CSV] [PNG]
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plot_results  # noqa: E402

src = sys.argv[1] if len(sys.argv) > 1 else "docs/results/wp_high_order.csv"
out = sys.argv[2] if len(sys.argv) > 2 else os.path.splitext(src)[0] + ".png"
if not os.path.exists(src):
    print(f"{src}: missing, skipped")
    sys.exit(0)
plot_results.plot(src, None, False, out)
