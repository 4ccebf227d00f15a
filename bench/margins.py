#!/usr/bin/env python3
"""How the dual's rounds follow the optimum's margin: how much more the runner-up costs.

    # the drift episodes of standing teams (bench/standing_team.py's `--rounds` lines)
    python3 bench/standing_team.py --robots 50 --episodes 20 --method dual \
        --topology random:0.1 --seed S --rounds rounds.jsonl
    python3 bench/margins.py standing rounds.jsonl [more.jsonl ...]

    # one-shot solves of uniform costs in [0, 1) (sim), --seeds per team size
    python3 bench/margins.py one-shot --binary target/release/admm-ta --robots 50,100,200 \
        [--seeds 10] [--method dual] [--topology random:0.1]

A problem's *margin* is the second-best assignment's cost less the optimum's (the optimum
with one of its pairs forbidden, the cheapest over its pairs), in the costs' units. Prints
each problem's margin and rounds, then per group the rank correlation of rounds and margin
(Spearman), a fit `rounds ≈ a + b·log10(margin)` and the median rounds per band of margins.
Needs numpy and scipy (the virtual environment `./test` makes has both).
"""

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.stats import spearmanr

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from standing_team import costs_of  # noqa: E402

BANDS = [(0.0, 1e-4), (1e-4, 3e-4), (3e-4, 1e-3), (1e-3, 3e-3), (3e-3, 1e-2), (1e-2, math.inf)]


def margin(costs):
    """The second-best assignment's cost less the optimum's (square or wide costs)."""
    c = np.array(costs, dtype=float)
    rows, cols = linear_sum_assignment(c)
    best = c[rows, cols].sum()
    second = math.inf
    for i, j in zip(rows, cols):
        d = c.copy()
        d[i, j] = math.inf
        try:
            r, k = linear_sum_assignment(d)
        except ValueError:  # no assignment without that pair
            continue
        second = min(second, d[r, k].sum())
    # An exact tie gives 0 (never less but for rounding).
    return max(second - best, 0.0)


def summary(name, margins, rounds):
    """Spearman, the fit and the bands of one group (a margin of 0, a tie, fits as 1e-12)."""
    if len(rounds) < 2:
        print(f"{name}: {len(rounds)} problem(s), too few to fit")
        return
    logs = np.log10(np.maximum(margins, 1e-12))
    slope, at_one = np.polyfit(logs, rounds, 1)
    print(f"{name}: {len(rounds)} problems, median margin {statistics.median(margins):.2e}, "
          f"median rounds {statistics.median(rounds):.0f}, Spearman "
          f"{spearmanr(rounds, margins)[0]:+.2f}, rounds ≈ {at_one:.0f} "
          f"{slope:+.0f}·log10(margin)")
    for lo, hi in BANDS:
        band = [r for r, m in zip(rounds, margins) if lo <= m < hi]
        if band:
            print(f"  margin in [{lo:g}, {hi:g}): {len(band)}, median rounds "
                  f"{statistics.median(band):.0f}")


def runs_of(path):
    """standing_team.py's `--rounds` lines: {"seed", "robots", "warm": [...], "cold": [...]}."""
    with open(path, encoding="utf-8") as f:
        runs = [json.loads(line) for line in f if line.strip()]
    for run in runs:
        if not {"seed", "robots", "warm", "cold"} <= set(run) or \
                len(run["warm"]) != len(run["cold"]):
            raise SystemExit(f"{path}: not a line of standing_team.py --rounds: {run}")
    return runs


def standing(args):
    margins, rounds = [], {"warm": [], "cold": []}
    for run in (run for path in args.files for run in runs_of(path)):
        seed, n = run["seed"], run["robots"]
        drift = costs_of(seed, n, len(run["warm"]))[1]
        for k, costs in enumerate(drift):
            margins.append(margin(costs))
            print(f"seed {seed}, {n} robots, episode {k}: margin {margins[-1]:.2e}, rounds "
                  f"warm {run['warm'][k]} cold {run['cold'][k]}")
            for team in rounds:
                rounds[team].append(run[team][k])
    for team, r in rounds.items():
        summary(team, margins, r)


def one_shot(args):
    with tempfile.TemporaryDirectory(prefix="admm-ta-margins-") as directory:
        one_shot_in(args, directory)


def one_shot_in(args, directory):
    sizes = [int(x) for x in args.robots.split(",")]
    every = ([], [], [])
    for n in sizes:
        margins, rounds = [], []
        for seed in range(1, args.seeds + 1):
            costs = np.random.default_rng(seed * 7919 + n).random((n, n))
            path = os.path.join(directory, f"costs-{n}-{seed}.csv")
            np.savetxt(path, costs, delimiter=",")
            done = subprocess.run(
                [args.binary, "solve", "--costs", path, "--method", args.method, "--transport",
                 "sim", "--topology", args.topology, "--seed", str(seed), "--json"],
                capture_output=True, text=True, timeout=args.timeout)
            if not done.stdout:
                raise SystemExit(f"solve failed (exit {done.returncode}): {done.stderr}")
            report = json.loads(done.stdout)
            m = margin(costs)
            print(f"{n} robots, seed {seed}: margin {m:.2e}, rounds {report['iterations']}"
                  f"{'' if report['certified'] else ' (not certified: left out)'}", flush=True)
            if report["certified"]:
                margins.append(m)
                rounds.append(report["iterations"])
        summary(f"{n} robots", margins, rounds)
        every[0].extend(margins)
        every[1].extend(rounds)
        every[2].extend([n] * len(rounds))
    if len(sizes) > 1:
        summary("every size", every[0], every[1])
        with_size(*every)


def with_size(margins, rounds, sizes):
    """The fit of rounds to the margin and the team size together, against each alone."""
    r = np.array(rounds, dtype=float)
    columns = {"margin": np.log10(np.maximum(margins, 1e-12)), "n": np.log10(sizes)}

    def fit(names):
        x = np.column_stack([np.ones(len(r))] + [columns[k] for k in names])
        coef = np.linalg.lstsq(x, r, rcond=None)[0]
        return coef, 1 - ((r - x @ coef) ** 2).sum() / ((r - r.mean()) ** 2).sum()

    (a, b, c), both = fit(["margin", "n"])
    print(f"  rounds ≈ {a:.0f} {b:+.0f}·log10(margin) {c:+.0f}·log10(n): R² {both:.2f} "
          f"(margin alone {fit(['margin'])[1]:.2f}, n alone {fit(['n'])[1]:.2f})")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    modes = parser.add_subparsers(dest="mode", required=True)
    drift = modes.add_parser("standing", help="standing_team.py's drift episodes")
    drift.add_argument("files", nargs="+", help="files standing_team.py --rounds wrote")
    once = modes.add_parser("one-shot", help="one-shot solves in the sim")
    once.add_argument("--binary", default="target/release/admm-ta")
    once.add_argument("--robots", default="50,100,200")
    once.add_argument("--seeds", type=int, default=10)
    once.add_argument("--method", default="dual")
    once.add_argument("--topology", default="random:0.1")
    once.add_argument("--timeout", type=float, default=3600.0, help="seconds per solve")
    args = parser.parse_args()
    {"standing": standing, "one-shot": one_shot}[args.mode](args)


if __name__ == "__main__":
    main()
