#!/usr/bin/env python3
"""Are two binaries the same solver? Runs `admm-ta solve --json` over a sweep of methods,
variants, transports, topologies, shapes, cost models and seeds with each binary, strips what
depends on the clock (wall time, round latency, CPU usage, start-up, timelines) and compares
the rest byte for byte. Standard library only.

    python3 bench/solve_sweep.py OLD/admm-ta NEW/admm-ta [--quick]

Prints the number of runs and every run whose report differs (exit 1 if any).
"""

import argparse
import itertools
import json
import re
import subprocess
import sys

#: Report fields that measure time or the machine, or name one run, not the solve.
CLOCK = re.compile(
    r"(^|_)(ms|us|ns)$|latency|usage|startup|wall|cpu|context_switch|timeline|critical|^run_id$"
)


def strip(value):
    if isinstance(value, dict):
        return {k: strip(v) for k, v in value.items() if not CLOCK.search(k)}
    if isinstance(value, list):
        return [strip(v) for v in value]
    return value


def cases(quick):
    methods = [
        ["--method", "primal"],
        ["--method", "primal", "--primal-variant", "paper"],
        ["--method", "dual"],
        ["--method", "dual", "--dual-variant", "paper"],
        ["--method", "inexact-dual"],
        ["--method", "cbaa"],
        ["--method", "market"],
        ["--method", "dist-hungarian"],
        ["--method", "hungarian"],
    ]
    shapes = [["--robots", "8", "--tasks", "8"], ["--robots", "10", "--tasks", "6"],
              ["--robots", "6", "--tasks", "9", "--case", "idle"]]
    topologies = ["complete", "ring", "random:0.3"]
    models = ["uniform", "geometric"]
    seeds = [1, 2] if quick else [1, 2, 3]
    for method, shape, topology, model, seed in itertools.product(
            methods, shapes, topologies, models, seeds):
        yield ["solve", *method, *shape, "--topology", topology, "--cost-model", model,
               "--seed", str(seed), "--check", "--json", "--max-iters", "3000"]
    # Transports and options on a few cases.
    for transport, method in itertools.product(["threads", "ipc"], ["primal", "dual"]):
        yield ["solve", "--method", method, "--robots", "8", "--tasks", "6", "--topology",
               "ring", "--seed", "4", "--transport", transport, "--check", "--json"]
    for extra in (["--maximize"], ["--adaptive-rho", "--primal-variant", "paper"],
                  ["--stop", "max-iters", "--max-iters", "40"], ["--rho", "0.5"]):
        yield ["solve", "--robots", "7", "--tasks", "7", "--topology", "chain", "--seed", "5",
               "--check", "--json", *extra]


def run(binary, args):
    out = subprocess.run([binary, *args], capture_output=True, text=True, timeout=600)
    try:
        report = json.dumps(strip(json.loads(out.stdout)), sort_keys=True)
    except json.JSONDecodeError:
        report = out.stdout
    return out.returncode, report, out.stderr.strip()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("old")
    parser.add_argument("new")
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    differ = 0
    total = 0
    for case in cases(args.quick):
        total += 1
        before, after = run(args.old, case), run(args.new, case)
        if before != after:
            differ += 1
            print("differs:", " ".join(case))
            print("  old:", before[0], before[1][:400], before[2][:200])
            print("  new:", after[0], after[1][:400], after[2][:200])
    print(f"{total} runs, {differ} differ")
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
