#!/usr/bin/env python3
"""Rounds of the dual methods to the certified stop: issue 30's cases, one table per run.

    python3 bench/dual_rounds.py [--binary target/release/admm-ta] [--seeds 1-10]
        [--variants fast,paper] [--methods dual,inexact-dual] [--cases all|NAME,...] [--jobs 2]
        [--max-iters 5000] [--rho-scale 1]

Every run is `admm-ta solve … --check --json` (lockstep sim, defaults, decentralized stop).
A cell is `median rounds (certified/runs, optimal/runs)`; a run that did not certify counts
as its round limit in the median. Bytes are per robot to the stop, from the JSON.
"""
import argparse
import concurrent.futures
import json
import statistics
import subprocess

CASES = {
    "50x50 complete uniform": ["--robots", "50", "--tasks", "50", "--topology", "complete"],
    "50x50 complete distance": [
        "--robots", "50", "--tasks", "50", "--topology", "complete",
        "--cost-model", "geometric",
    ],
    "50x30 chain uniform": ["--robots", "50", "--tasks", "30", "--topology", "chain"],
    "50x50 random:0.1 distance": [
        "--robots", "50", "--tasks", "50", "--topology", "random:0.1",
        "--cost-model", "geometric",
    ],
    "100x100 chain uniform": ["--robots", "100", "--tasks", "100", "--topology", "chain"],
    "120x120 complete uniform": ["--robots", "120", "--tasks", "120", "--topology", "complete"],
}


def seeds(text):
    if "-" in text:
        a, b = text.split("-")
        return list(range(int(a), int(b) + 1))
    return [int(s) for s in text.split(",")]


def run(binary, method, variant, case, seed, max_iters, rho_scale=1.0):
    cmd = [
        binary, "solve", *CASES[case], "--seed", str(seed), "--method", method,
        "--dual-variant", variant, "--check", "--json", "--max-iters", str(max_iters),
    ]
    if rho_scale != 1.0:
        probe = subprocess.run(cmd[:-2] + ["--max-iters", "1"], capture_output=True, text=True)
        cmd += ["--rho", repr(json.loads(probe.stdout)["rho"] * rho_scale)]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=3600)
    if not out.stdout.strip():
        return {"rounds": max_iters, "certified": False, "optimal": False, "bytes": None,
                "error": out.stderr.strip().splitlines()[-1:]}
    d = json.loads(out.stdout)
    return {
        "rounds": d["iterations"],
        "certified": bool(d["certified"]),
        "optimal": bool(d["check"]["optimal"]),
        "bytes": d["bytes_per_agent"],
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--binary", default="target/release/admm-ta")
    ap.add_argument("--seeds", default="1-10")
    ap.add_argument("--variants", default="fast,paper")
    ap.add_argument("--methods", default="dual,inexact-dual")
    ap.add_argument("--cases", default="all")
    ap.add_argument("--per-seed", action="store_true", help="also list every seed's rounds")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--max-iters", type=int, default=5000)
    ap.add_argument("--rho-scale", type=float, default=1.0,
                    help="multiply each run's default ρ (a tuning aid)")
    args = ap.parse_args()
    cases = list(CASES) if args.cases == "all" else args.cases.split(",")
    keys = [
        (m, v, c, s)
        for c in cases
        for m in args.methods.split(",")
        for v in args.variants.split(",")
        for s in seeds(args.seeds)
    ]
    with concurrent.futures.ThreadPoolExecutor(args.jobs) as pool:
        results = dict(zip(keys, pool.map(lambda k: run(args.binary, *k, args.max_iters, args.rho_scale), keys)))
    columns = [(m, v) for m in args.methods.split(",") for v in args.variants.split(",")]
    print("| case | " + " | ".join(f"{m} ({v})" for m, v in columns) + " |")
    print("|---" * (len(columns) + 1) + "|")
    for c in cases:
        cells = []
        for m, v in columns:
            rs = [results[(m, v, c, s)] for s in seeds(args.seeds)]
            median = statistics.median(r["rounds"] for r in rs)
            cert = sum(r["certified"] for r in rs)
            opt = sum(r["optimal"] for r in rs)
            byts = [r["bytes"] for r in rs if r["bytes"] is not None]
            kib = f", {statistics.median(byts) / 1024:.0f} KiB" if byts else ""
            each = f" [{' '.join(str(r['rounds']) for r in rs)}]" if args.per_seed else ""
            cells.append(f"{median:g} ({cert}/{len(rs)} cert., {opt} opt.{kib}){each}")
        print(f"| {c} | " + " | ".join(cells) + " |")
    wrong = [k for k, r in results.items() if r["certified"] and not r["optimal"]]
    print(f"\ncertified but not optimal: {wrong or 'none'}")


if __name__ == "__main__":
    main()
