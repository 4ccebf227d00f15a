#!/usr/bin/env python3
"""How the dual's rounds follow the optimum's margin: how much more the runner-up costs.

    # the drift episodes of standing teams (bench/standing_team.py's `--rounds` lines)
    python3 bench/standing_team.py --robots 50 --episodes 20 --method dual \
        --topology random:0.1 --seed S --rounds rounds.jsonl
    python3 bench/margins.py standing rounds.jsonl [more.jsonl ...]

    # one-shot solves of uniform costs in [0, 1) (sim), --seeds per team size
    python3 bench/margins.py one-shot --binary target/release/admm-ta --robots 50,100,200 \
        [--seeds 10] [--method dual] [--topology random:0.1] [--out solves.jsonl]
    python3 bench/margins.py fit solves.jsonl [more.jsonl ...]   # the summary again

A problem's *margin* is the second-best assignment's cost less the optimum's (the optimum
with one of its pairs forbidden, the cheapest over its pairs), in the costs' units, and
*moved* the number of robots whose task the second-best changes (the length of the
exchange that turns the optimum into it). Prints each problem's margin and rounds, then
per group the rank correlation of rounds and margin (Spearman), fits `rounds ≈ a +
b·log10(margin)` and the same with the margin per moved robot, and the median rounds per
band of margins; over several team sizes, the fits with `log10(n)` as a second term.
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
    """The second-best assignment's cost less the optimum's (square or wide costs), and how
    many robots the second-best moves off their optimal tasks (`moved`)."""
    c = np.array(costs, dtype=float)
    rows, cols = linear_sum_assignment(c)
    best = c[rows, cols].sum()
    second, moved = math.inf, 0
    for i, j in zip(rows, cols):
        d = c.copy()
        d[i, j] = math.inf
        try:
            r, k = linear_sum_assignment(d)
        except ValueError:  # no assignment without that pair
            continue
        if d[r, k].sum() < second:
            second = d[r, k].sum()
            moved = int((tasks_of(r, k, len(c)) != tasks_of(rows, cols, len(c))).sum())
    # An exact tie gives 0 (never less but for rounding).
    return max(second - best, 0.0), moved


def tasks_of(rows, cols, robots):
    """Each robot's task in an assignment (-1: none)."""
    tasks = np.full(robots, -1)
    tasks[rows] = cols
    return tasks


def summary(name, margins, rounds, moved):
    """Spearman, the fits and the bands of one group (a margin of 0, a tie, fits as 1e-12):
    against the margin, and against the margin per moved robot."""
    if len(rounds) < 2:
        print(f"{name}: {len(rounds)} problem(s), too few to fit")
        return
    per_robot = [m / max(k, 1) for m, k in zip(margins, moved)]
    print(f"{name}: {len(rounds)} problems, median margin {statistics.median(margins):.2e}, "
          f"median moved {statistics.median(moved):.0f}, median rounds "
          f"{statistics.median(rounds):.0f}")
    for label, values in (("margin", margins), ("margin/moved", per_robot)):
        logs = np.log10(np.maximum(values, 1e-12))
        slope, at_one = np.polyfit(logs, rounds, 1)
        print(f"  {label}: Spearman {spearmanr(rounds, values)[0]:+.2f}, rounds ≈ "
              f"{at_one:.0f} {slope:+.0f}·log10({label}), R² {r_squared(logs, rounds):.2f}")
    for lo, hi in BANDS:
        band = [r for r, m in zip(rounds, margins) if lo <= m < hi]
        if band:
            print(f"  margin in [{lo:g}, {hi:g}): {len(band)}, median rounds "
                  f"{statistics.median(band):.0f}")


def r_squared(x, y):
    """R² of the least-squares line through (x, y)."""
    y = np.array(y, dtype=float)
    line = np.polyval(np.polyfit(x, y, 1), x)
    return 1 - ((y - line) ** 2).sum() / ((y - y.mean()) ** 2).sum()


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
    margins, moved, rounds = [], [], {"warm": [], "cold": []}
    for run in (run for path in args.files for run in runs_of(path)):
        seed, n = run["seed"], run["robots"]
        drift = costs_of(seed, n, len(run["warm"]))[1]
        for k, costs in enumerate(drift):
            m, robots_moved = margin(costs)
            margins.append(m)
            moved.append(robots_moved)
            print(f"seed {seed}, {n} robots, episode {k}: margin {m:.2e} ({robots_moved} moved), "
                  f"rounds warm {run['warm'][k]} cold {run['cold'][k]}")
            for team in rounds:
                rounds[team].append(run[team][k])
    for team, r in rounds.items():
        summary(team, margins, r, moved)


def one_shot(args):
    with tempfile.TemporaryDirectory(prefix="admm-ta-margins-") as directory:
        report(one_shot_in(args, directory))


def one_shot_in(args, directory):
    """Each seed's problem of each size solved once: a dict per certified solve, each also
    appended to `--out` as soon as it is known."""
    solves = []
    for n in (int(x) for x in args.robots.split(",")):
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
            result = json.loads(done.stdout)
            m, moved = margin(costs)
            print(f"{n} robots, seed {seed}: margin {m:.2e} ({moved} moved), rounds "
                  f"{result['iterations']}"
                  f"{'' if result['certified'] else ' (not certified: left out)'}", flush=True)
            if result["certified"]:
                solves.append({"robots": n, "seed": seed, "margin": m, "moved": moved,
                               "rounds": result["iterations"], "topology": args.topology})
                if args.out:
                    with open(args.out, "a", encoding="utf-8") as f:
                        f.write(json.dumps(solves[-1]) + "\n")
    return solves


KEYS = {"robots", "seed", "margin", "moved", "rounds", "topology"}


def fit(args):
    solves = []
    for path in args.files:
        try:
            with open(path, encoding="utf-8") as f:
                lines = [line for line in f if line.strip()]
            solves.extend(json.loads(line) for line in lines)
        except (OSError, ValueError) as e:
            raise SystemExit(f"{path}: {e}")
        if not all(isinstance(s, dict) and KEYS <= set(s) for s in solves):
            raise SystemExit(f"{path}: not the lines of margins.py one-shot --out")
    for n in {s["robots"] for s in solves}:
        graphs = {s["topology"] for s in solves if s["robots"] == n}
        if len(graphs) > 1:
            raise SystemExit(f"{n} robots solved on several topologies ({', '.join(graphs)}): "
                             "one fit would mix them")
    report(solves)


def report(solves):
    """The summary of every team size, then of all sizes with the size as a second term."""
    sizes = sorted({s["robots"] for s in solves})
    for n in sizes:
        group = [s for s in solves if s["robots"] == n]
        summary(f"{n} robots ({group[0]['topology']})",
                *columns(group, "margin", "rounds", "moved"))
    if len(sizes) > 1:
        summary("every size", *columns(solves, "margin", "rounds", "moved"))
        with_size(solves)


def columns(solves, *keys):
    return tuple([s[k] for s in solves] for k in keys)


def with_size(solves):
    """The fits of rounds to the margin (or the margin per moved robot) and the team size."""
    margins, rounds, moved, sizes = columns(solves, "margin", "rounds", "moved", "robots")
    r = np.array(rounds, dtype=float)
    terms = {
        "margin": np.log10(np.maximum(margins, 1e-12)),
        "margin/moved": np.log10(np.maximum(np.divide(margins, np.maximum(moved, 1)), 1e-12)),
        "n": np.log10(sizes),
    }

    def fit_of(names):
        x = np.column_stack([np.ones(len(r))] + [terms[k] for k in names])
        coef = np.linalg.lstsq(x, r, rcond=None)[0]
        return coef, 1 - ((r - x @ coef) ** 2).sum() / ((r - r.mean()) ** 2).sum()

    for first in ("margin", "margin/moved"):
        (a, b, c), both = fit_of([first, "n"])
        print(f"  rounds ≈ {a:.0f} {b:+.0f}·log10({first}) {c:+.0f}·log10(n): R² {both:.2f} "
              f"({first} alone {fit_of([first])[1]:.2f}, n alone {fit_of(['n'])[1]:.2f})")


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
    once.add_argument("--out", help="append a JSON line per certified solve to this file")
    again = modes.add_parser("fit", help="the summary of files one-shot --out wrote")
    again.add_argument("files", nargs="+")
    args = parser.parse_args()
    {"standing": standing, "one-shot": one_shot, "fit": fit}[args.mode](args)


if __name__ == "__main__":
    main()
