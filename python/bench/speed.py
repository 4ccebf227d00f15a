"""Speed of the Python package, in one run (docs/python.md, "Python: speed"):

1. ``admm_ta.linear_sum_assignment`` against ``scipy.optimize.linear_sum_assignment`` at
   n = 10, 100, 1000, 3000, uniform [0, 1) and integer [0, 100) costs: median time per
   call, the two calls alternating on the same matrices.
2. ``admm_ta.solve`` from Python against the ``admm-ta solve`` command line for the same
   problem: the report's own solve time (``wall_time_ms``) beside the whole call (Python)
   and the whole process (command line), so the overhead of each front end shows.

    python python/bench/speed.py [--cli target/release/admm-ta] [--quick]
"""

import argparse
import json
import statistics
import subprocess
import sys
import time

import numpy as np
from scipy.optimize import linear_sum_assignment as scipy_lsap

import admm_ta


def median_ms(f, reps):
    times = []
    for _ in range(reps):
        start = time.perf_counter()
        f()
        times.append(time.perf_counter() - start)
    return 1e3 * statistics.median(times)


def lsap_table(sizes):
    rng = np.random.default_rng(1)
    print("| n | costs | scipy (ms) | admm_ta (ms) | admm_ta / scipy |")
    print("| --- | --- | --- | --- | --- |")
    for n in sizes:
        for kind in ["uniform", "integer"]:
            cost = rng.random((n, n)) if kind == "uniform" else rng.integers(0, 100, (n, n))
            reps = {10: 2000, 100: 200, 1000: 9, 3000: 3}.get(n, 3)
            scipy_times, ours = [], []
            for _ in range(reps):  # alternate, so drift hits both alike
                scipy_times.append(median_ms(lambda: scipy_lsap(cost), 1))
                ours.append(median_ms(lambda: admm_ta.linear_sum_assignment(cost), 1))
            s, a = statistics.median(scipy_times), statistics.median(ours)
            print(f"| {n} | {kind} | {s:.4g} | {a:.4g} | {a / s:.2f} |")


def solve_table(cli, reps):
    print()
    print("| problem | front end | whole call (ms, median) | solve inside (ms) | overhead (ms) |")
    print("| --- | --- | --- | --- | --- |")
    for robots, transport in [(20, "sim"), (20, "ipc"), (50, "ipc")]:
        cost = np.random.default_rng(robots).random((robots, robots))
        csv = "\n".join(",".join(repr(float(x)) for x in row) for row in cost) + "\n"
        inside, calls = [], []
        for _ in range(reps):
            start = time.perf_counter()
            r = admm_ta.solve(cost, transport=transport)
            calls.append(1e3 * (time.perf_counter() - start))
            inside.append(r.wall_time_ms)
        c, w = statistics.median(calls), statistics.median(inside)
        label = f"{robots}×{robots} primal, {transport}"
        print(f"| {label} | Python `admm_ta.solve` | {c:.1f} | {w:.1f} | {c - w:.1f} |")
        if cli:
            inside, calls = [], []
            for _ in range(reps):
                start = time.perf_counter()
                out = subprocess.run([cli, "solve", "--costs", "-", "--transport", transport,
                                      "--json"], input=csv, capture_output=True, text=True,
                                     check=True)
                calls.append(1e3 * (time.perf_counter() - start))
                inside.append(json.loads(out.stdout)["wall_time_ms"])
            c, w = statistics.median(calls), statistics.median(inside)
            print(f"| {label} | `admm-ta solve` process | {c:.1f} | {w:.1f} | {c - w:.1f} |")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--cli", help="the admm-ta binary, for the front-end comparison")
    parser.add_argument("--quick", action="store_true", help="n up to 1000, fewer solves")
    args = parser.parse_args()
    lsap_table([10, 100, 1000] if args.quick else [10, 100, 1000, 3000])
    solve_table(args.cli, 3 if args.quick else 9)
    return 0


if __name__ == "__main__":
    sys.exit(main())
