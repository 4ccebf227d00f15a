#!/usr/bin/env python3
"""Round latency of two admm-ta binaries on the same cases, in one run.

    python3 bench/compare_binaries.py OLD_BINARY NEW_BINARY [--repeat 6] [-- BENCH ROUNDS ARGS]

Runs `BINARY bench rounds --json ARGS` with each binary in turn, `--repeat` times (which
binary goes first alternates, so that the machine's drift and order effects cancel), and
prints per case the medians of round p50 and p99 for each binary and the median of the
paired ratios new / old (one ratio per repetition). This is how "zero cost when off" is
measured: a binary from before a change against one after it, the new feature switched off.

The default cases: touch and primal steps, 10 and 50 agents, threads and ipc, 2000 recorded
rounds after 200 of warm-up. Standard library only.
"""

import argparse
import json
import statistics
import subprocess
import sys
import tempfile

DEFAULT_SWEEPS = [
    ["--step", "touch", "--agents", "10,50", "--transports", "threads,ipc"],
    ["--step", "primal", "--agents", "10,50", "--transports", "threads,ipc"],
]


def measure(binary, sweep, rounds, warmup):
    """One `bench rounds` run: {case key: (p50, p99)} in µs."""
    with tempfile.TemporaryDirectory() as out:
        args = [binary, "bench", "rounds", "--json", "--out", out]
        args += ["--rounds", str(rounds), "--warmup", str(warmup)] + sweep
        run = subprocess.run(args, capture_output=True, text=True, check=False)
        if run.returncode != 0:
            sys.exit(f"{binary} failed ({run.returncode}): {run.stderr.strip()}")
        report = json.loads(run.stdout)
    cases = {}
    for r in report["results"]:
        key = (r["step"], r["agents"], r["topology"], r["transport"])
        cases[key] = (r["round_us"]["p50"], r["round_us"]["p99"])
    return cases


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("old")
    parser.add_argument("new")
    parser.add_argument("--repeat", type=int, default=6)
    parser.add_argument("--rounds", type=int, default=2000)
    parser.add_argument("--warmup", type=int, default=200)
    parser.add_argument("sweep", nargs="*", help="bench rounds arguments (after --)")
    args = parser.parse_args()
    sweeps = [args.sweep] if args.sweep else DEFAULT_SWEEPS
    samples = {}  # key -> {"old": [(p50, p99)], "new": [...]}
    for rep in range(args.repeat):
        order = [("old", args.old), ("new", args.new)]
        if rep % 2:
            order.reverse()
        for sweep in sweeps:
            for name, binary in order:
                for key, value in measure(binary, sweep, args.rounds, args.warmup).items():
                    samples.setdefault(key, {"old": [], "new": []})[name].append(value)
        print(f"repetition {rep + 1}/{args.repeat} done", file=sys.stderr)
    print(
        "| step | agents | graph | transport | old p50 | new p50 | new/old p50 "
        "| old p99 | new p99 | new/old p99 |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for key, s in sorted(samples.items()):
        old, new = s["old"], s["new"]
        med = statistics.median
        ratio = lambda k: med(n[k] / o[k] for o, n in zip(old, new))  # noqa: E731
        print(
            f"| {key[0]} | {key[1]} | {key[2]} | {key[3]} "
            f"| {med(o[0] for o in old):.1f} | {med(n[0] for n in new):.1f} | {ratio(0):.3f} "
            f"| {med(o[1] for o in old):.1f} | {med(n[1] for n in new):.1f} | {ratio(1):.3f} |"
        )


if __name__ == "__main__":
    main()
