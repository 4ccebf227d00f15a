#!/usr/bin/env python3
"""Warm and cold episodes of `dual_warm` over several seeds: mean, median, p90 and max rounds.

    python3 bench/dual_warm_stats.py "ROBOTS TASKS TOPOLOGY uniform|distance EPISODES" SEED...

Runs target/release/examples/dual_warm (build it with `cargo build --release -p
admm-ta-runtime --example dual_warm`) once per seed with the environment as given (RHO0,
RHO_SCALE, HEDGE, DRIFT); an episode not certified in 5000 rounds counts 5000.
"""
import os
import pathlib
import subprocess
import sys

BINARY = pathlib.Path(__file__).resolve().parent.parent / "target/release/examples/dual_warm"


def rounds_of(spec, seed):
    out = subprocess.run([str(BINARY), *spec, seed, "5000"], capture_output=True, text=True,
                         env=os.environ, check=True).stdout
    warm, cold, into = [], [], None
    for line in out.splitlines():
        if line.startswith("warm: first"):
            into = warm
        elif line.startswith("cold: first"):
            into = cold
        elif "episode" in line and "rounds" in line and into is not None:
            value = line.split("rounds ")[1].split(",")[0]
            into.append(5000 if value == "none" else int(value))
    return warm, cold


def stats(xs):
    xs = sorted(xs)
    return "mean %.1f median %d p90 %d max %d" % (
        sum(xs) / len(xs), xs[len(xs) // 2], xs[int(0.9 * len(xs))], xs[-1])


def main():
    spec, seeds = sys.argv[1].split(), sys.argv[2:]
    warm, cold = [], []
    for seed in seeds:
        w, c = rounds_of(spec, seed)
        warm += w
        cold += c
    print(f"{sys.argv[1]} | warm {stats(warm)} | cold {stats(cold)}")


if __name__ == "__main__":
    main()
