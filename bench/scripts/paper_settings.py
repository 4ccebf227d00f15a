#!/usr/bin/env python3
"""The paper's other settings (50x50 complete, 50x30 complete / random:0.1 / chain) with its
criterion: rounds until the robots' own columns are within 0.1% of the optimum
(`solve --stop oracle`), for every ADMM method, on uniform costs in [0,1) and shifted to
[1,2). Costs are drawn here (Python's random, seeded) and written as CSV files.

    cargo build --release && python3 bench/scripts/paper_settings.py [--adaptive-rho] [--seeds 5]

Prints one line per setting, method and cost range: mean rounds, runs that reached the
criterion within 3000 rounds, and every run's count. bench/README.md quotes one run.
"""
import json
import os
import random
import subprocess
import sys
import tempfile

BINARY = os.environ.get("ADMM_TA", "target/release/admm-ta")


def costs(directory, n, m, seed, shift):
    path = os.path.join(directory, f"c{n}x{m}_{seed}_{shift}.csv")
    rng = random.Random(1000 * seed + n + m)
    with open(path, "w") as f:
        for _ in range(n):
            f.write(",".join(f"{shift + rng.random():.17g}" for _ in range(m)) + "\n")
    return path


def main():
    extra = ["--adaptive-rho"] if "--adaptive-rho" in sys.argv else []
    seeds = int(sys.argv[sys.argv.index("--seeds") + 1]) if "--seeds" in sys.argv else 5
    settings = [(50, 50, "complete"), (50, 30, "complete"), (50, 30, "random:0.1"), (50, 30, "chain")]
    with tempfile.TemporaryDirectory() as directory:
        for n, m, topology in settings:
            for method in ["primal", "dual", "inexact-dual"]:
                for shift in [0, 1]:
                    rounds = []
                    for seed in range(seeds):
                        args = [BINARY, "solve", "--costs", costs(directory, n, m, seed, shift),
                                "--topology", topology, "--seed", str(seed), "--method", method,
                                "--stop", "oracle", "--json", "--max-iters", "3000"] + extra
                        report = json.loads(subprocess.run(args, capture_output=True, text=True,
                                                           check=True).stdout)
                        rounds.append(report["iterations"] if report["converged"] else None)
                    reached = [r for r in rounds if r is not None]
                    mean = sum(reached) / max(1, len(reached))
                    print(f"{n}x{m} {topology} {method} [{shift},{shift + 1}): mean {mean:.1f} "
                          f"reached {len(reached)}/{seeds} {rounds}", flush=True)


if __name__ == "__main__":
    main()
