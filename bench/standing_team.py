#!/usr/bin/env python3
"""Episode latency of a standing team whose robots keep their own costs, against a one-shot
`solve` of the same problem (start-up included). Standard library only.

    python3 bench/standing_team.py --binary target/release/admm-ta --robots 10,20,50 \
        [--episodes 30] [--topology random:0.2] [--transport ipc] [--solves 5] [--rounds FILE]

For each team size N (N robots, N tasks) it writes a private team file (costs = "private"),
starts N `admm-ta agent --serve` sidecars and feeds them, as robot programs would:

* **drift**: `--episodes` episodes whose costs move slightly (uniform costs, each changed by
  up to ±1 % of the range per episode), then
* **redrawn**: `--episodes` episodes of fresh uniform costs,

once with `warm_start = true` (the default: every episode starts from the last one's
iterates) and once with `warm_start = false` (cold). An episode's latency is the wall time
from the first row written to the last answer read. Then it times `admm-ta solve --costs
F --transport T` on the last drift episode's matrix (`--solves` times: start-up, connection,
solve, exit). Every episode must be certified and all robots must report the same
assignment (else the script says so and exits 1).

Prints one table row per team size: episode p50/p99 (warm drift), p50 (warm redrawn), rounds
per episode p50 warm against cold (drift, redrawn), the agreement's rounds, the one-shot
solve's p50 wall time and the warm episode's share of it. `--rounds FILE` also appends,
per team size, one JSON line with every drift episode's rounds of the warm and the cold team
({"seed", "robots", "warm": [...], "cold": [...]}; `bench/margins.py standing` reads it).
"""

import argparse
import json
import os
import random
import statistics
import subprocess
import sys
import tempfile
import time


def percentile(values, q):
    values = sorted(values)
    if not values:
        return float("nan")
    k = min(len(values) - 1, max(0, int(round(q / 100 * (len(values) - 1)))))
    return values[k]


class Team:
    def __init__(self, binary, directory, run, robots, topology, transport, warm, seed, extra):
        self.team = os.path.join(directory, f"{run}.toml")
        with open(self.team, "w", encoding="utf-8") as f:
            f.write(f'run = "{run}"\nrobots = {robots}\ntasks = {robots}\n'
                    f'costs = "private"\ntopology = "{topology}"\nseed = {seed}\n'
                    f'transport = "{transport}"\nwarm_start = {"true" if warm else "false"}\n'
                    f'round_timeout = 30.0\nepisode_timeout = 60.0\nstartup_timeout = 60.0\n'
                    + "".join(line + "\n" for line in extra))
        self.sidecars = [
            subprocess.Popen([binary, "agent", "--team", self.team, "--robot", str(i), "--serve"],
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
                             bufsize=1)
            for i in range(robots)
        ]

    def episode(self, rows):
        started = time.perf_counter()
        for s, row in zip(self.sidecars, rows):
            s.stdin.write(json.dumps({"costs": row}) + "\n")
            s.stdin.flush()
        answers = []
        for s in self.sidecars:
            line = s.stdout.readline()
            if not line:
                raise SystemExit(f"a sidecar ended: exit {s.wait()}")
            answers.append(json.loads(line))
        return time.perf_counter() - started, answers

    def close(self):
        for s in self.sidecars:
            s.stdin.close()
        codes = [s.wait(timeout=120) for s in self.sidecars]
        if any(codes):
            raise SystemExit(f"sidecars exited with {codes}")


def check(answers, what):
    views = {json.dumps(a.get("assignment")) for a in answers}
    if len(views) != 1 or not all(a.get("certified") for a in answers):
        raise SystemExit(f"{what}: not certified or robots disagree: {answers[0]}")


def costs_of(seed, n, episodes):
    """The base costs, the drift episodes and the redrawn ones of `seed`'s team of `n`."""
    rng = random.Random(seed * 1000 + n)
    base = [[rng.random() for _ in range(n)] for _ in range(n)]
    drift, rows = [], base
    for _ in range(episodes):
        rows = [[min(1.0, max(0.0, v + rng.uniform(-0.01, 0.01))) for v in r] for r in rows]
        drift.append(rows)
    redrawn = [[[rng.random() for _ in range(n)] for _ in range(n)] for _ in range(episodes)]
    return base, drift, redrawn


def run_sequence(team, sequences):
    """Latencies and rounds per named sequence of episodes."""
    out = {}
    for name, episodes in sequences:
        times, rounds, sent = [], [], []
        for k, rows in enumerate(episodes):
            elapsed, answers = team.episode(rows)
            check(answers, f"{name} episode {k}")
            times.append(elapsed)
            rounds.append(answers[0]["rounds"])
            sent.append(answers[0]["sent_bytes"])
        out[name] = (times, rounds, answers[0]["agreement_rounds"], sent)
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--binary", default="target/release/admm-ta")
    parser.add_argument("--robots", default="10,20,50")
    parser.add_argument("--episodes", type=int, default=30)
    parser.add_argument("--topology", default="random:0.2")
    parser.add_argument("--transport", default="ipc")
    parser.add_argument("--solves", type=int, default=5)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--rounds", metavar="FILE",
                        help="append the drift episodes' rounds, warm and cold (JSON lines)")
    parser.add_argument("--method", default="primal",
                        help="the team's method (and the one-shot solve's): primal, dual, inexact-dual")
    parser.add_argument("--team-key", action="append", default=[],
                        help="an extra line of the team file (primal_variant = \"paper\")")
    args = parser.parse_args()
    directory = tempfile.mkdtemp(prefix="admm-ta-standing-")
    print(f"| robots | warm episode p50 / p99 (drift) | warm p50 (redrawn) | rounds warm / cold "
          f"(drift) | rounds warm / cold (redrawn) | agreement rounds | one-shot solve p50 "
          f"| warm / one-shot | sent per robot per episode (warm drift p50) |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for n in [int(x) for x in args.robots.split(",")]:
        base, drift, redrawn = costs_of(args.seed, n, args.episodes)
        sequences = [("drift", drift), ("redrawn", redrawn)]
        results = {}
        for warm in (True, False):
            run = f"st{os.getpid() % 100000}-{n}-{'w' if warm else 'c'}"
            team = Team(args.binary, directory, run, n, args.topology, args.transport, warm,
                        args.seed, [f'method = "{args.method}"'] + args.team_key)
            try:
                # An untimed first episode on the base costs: the sidecars join meanwhile.
                check(team.episode(base)[1], "first episode")
                results[warm] = run_sequence(team, sequences)
            finally:
                team.close()
        # The one-shot solve of the last drift episode's matrix, start-up included.
        csv = os.path.join(directory, f"costs-{n}.csv")
        with open(csv, "w", encoding="utf-8") as f:
            for r in drift[-1]:
                f.write(",".join(repr(v) for v in r) + "\n")
        solves = [float("nan")]
        for _ in range(args.solves):
            started = time.perf_counter()
            done = subprocess.run([args.binary, "solve", "--costs", csv, "--transport",
                                   args.transport, "--topology", args.topology, "--seed",
                                   str(args.seed), "--method", args.method],
                                  capture_output=True, text=True)
            solves.append(time.perf_counter() - started)
            solves = [v for v in solves if v == v]
            if done.returncode != 0:
                raise SystemExit(f"solve failed: {done.stderr}")
        warm_drift, warm_rounds, agreement, warm_sent = results[True]["drift"]
        if args.rounds:
            with open(args.rounds, "a", encoding="utf-8") as f:
                f.write(json.dumps({"seed": args.seed, "robots": n,
                                    "warm": results[True]["drift"][1],
                                    "cold": results[False]["drift"][1]}) + "\n")
        warm_redrawn = results[True]["redrawn"]
        cold_drift = results[False]["drift"]
        cold_redrawn = results[False]["redrawn"]
        ms = lambda s: f"{s * 1e3:.1f} ms"
        solve_p50 = statistics.median(solves)
        print(f"| {n} | {ms(statistics.median(warm_drift))} / {ms(percentile(warm_drift, 99))} "
              f"| {ms(statistics.median(warm_redrawn[0]))} "
              f"| {statistics.median(warm_rounds):.0f} / {statistics.median(cold_drift[1]):.0f} "
              f"| {statistics.median(warm_redrawn[1]):.0f} / "
              f"{statistics.median(cold_redrawn[1]):.0f} | {agreement} "
              f"| {ms(solve_p50)} | {statistics.median(warm_drift) / solve_p50:.3f} "
              f"| {statistics.median(warm_sent) / 1e3:.1f} kB |",
              flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
