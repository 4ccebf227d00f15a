#!/usr/bin/env python3
"""A team across four hosts with their own addresses, on one machine (needs root and `ip`).

    sudo python3 bench/netns_team.py --binary target/release/admm-ta --agents 100 \
        --transport zenoh --runs 10 [--hosts 4] [--topology random:0.1] [--round-timeout 10]

Makes `--hosts` network namespaces on a bridge (veth pairs, addresses 10.232.0.K/24, no
route anywhere else), and for each run writes a team file (random costs from the run's seed,
the primal method or `--method`, the agents split evenly over the hosts), starts in every namespace
`admm-ta host --team T --name hK` and its agents (`admm-ta agent --team T --robot I`), waits,
and runs `admm-ta collect --check --json`. Prints one line per run (certified and optimal,
wall time from the first process started to the last one ended, round p50/p99 from the
agents' merged latencies, start-up from the first process started to the last agent
connected, every host's exit) and a summary; removes the namespaces and
the bridge at the end, whatever happens. Standard library only.

With `--episodes E` it runs a *standing team* instead (private costs, `agent --serve`
sidecars in the namespaces, one `host` per namespace): E episodes, the first half with costs
drifting by up to ±1 % of the range from the last episode's, the second half redrawn. An
episode passes when every robot's answer is certified, all name the same assignment and its
cost equals the optimum of `admm-ta solve --method hungarian` on the stacked rows. Prints
one line per episode (latency from the first row written to the last answer read, rounds,
the agreements' rounds, bytes one robot sent: over Zenoh as coded) and a summary.
"""

import argparse
import json
import os
import random
import subprocess
import sys
import tempfile
import threading
import time

TAG = f"nt{os.getpid() % 100000}"


def ip(*args, check=True):
    return subprocess.run(["ip", *args], check=check, capture_output=True, text=True)


def make_hosts(k):
    bridge = f"{TAG}b"
    ip("link", "add", bridge, "type", "bridge")
    ip("link", "set", bridge, "up")
    hosts = []
    for h in range(k):
        ns, inner, outer = f"{TAG}h{h}", f"{TAG}i{h}", f"{TAG}o{h}"
        ip("netns", "add", ns)
        ip("link", "add", inner, "type", "veth", "peer", "name", outer)
        ip("link", "set", outer, "master", bridge)
        ip("link", "set", outer, "up")
        ip("link", "set", inner, "netns", ns)
        address = f"10.232.0.{h + 1}"
        ip("-n", ns, "addr", "add", f"{address}/24", "dev", inner)
        ip("-n", ns, "link", "set", inner, "up")
        ip("-n", ns, "link", "set", "lo", "up")
        hosts.append((ns, address))
    return bridge, hosts


def remove_hosts(bridge, hosts):
    for ns, _ in hosts:
        ip("netns", "del", ns, check=False)
    ip("link", "del", bridge, check=False)


def team_file(path, args, hosts, run, seed, costs="random"):
    n = args.agents
    per = [n // len(hosts) + (1 if h < n % len(hosts) else 0) for h in range(len(hosts))]
    lines = [
        f'run = "{run}"', f"robots = {n}", f'costs = "{costs}"', f"tasks = {n}",
        f"seed = {seed}", f'topology = "{args.topology}"', 'results = "results"',
        f"startup_timeout = {args.startup_timeout}", f"round_timeout = {args.round_timeout}",
        f'transport = "{args.transport}"', f'method = "{args.method}"',
    ]
    if costs == "private":
        lines.append(f"episode_timeout = {args.episode_timeout}")
    first = 0
    for h, (_, address) in enumerate(hosts):
        agents = ", ".join(str(a) for a in range(first, first + per[h]))
        lines += ["", "[[hosts]]", f'name = "h{h}"', f"agents = [{agents}]",
                  f'endpoint = "tcp/{address}:7447"']
        first += per[h]
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    return per


def one_run(args, hosts, k):
    with tempfile.TemporaryDirectory() as d:
        team = os.path.join(d, "team.toml")
        run = f"{TAG}r{k}"
        per = team_file(team, args, hosts, run, args.seed + k)
        started = time.monotonic()
        started_ns = time.time_ns()
        procs = []
        first = 0
        for h, (ns, _) in enumerate(hosts):
            exe = ["ip", "netns", "exec", ns, args.binary]
            env = dict(os.environ, RUST_LOG=args.host_log) if args.host_log else None
            nice = ["nice", "-n", str(args.host_nice)] if args.host_nice else []
            procs.append(("host", h, subprocess.Popen(
                ["ip", "netns", "exec", ns] + nice + [args.binary, "host", "--team", team, "--name", f"h{h}"],
                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)))
            for a in range(first, first + per[h]):
                agent_env = dict(os.environ, RUST_LOG=args.agent_log) if args.agent_log else None
                procs.append(("agent", a, subprocess.Popen(
                    exe + ["agent", "--team", team, "--robot", str(a)],
                    stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                    env=agent_env)))
            first += per[h]
        deadline = started + args.limit
        outputs = {}
        for kind, who, p in procs:
            try:
                out, err = p.communicate(timeout=max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                for _, _, q in procs:
                    q.kill()
                out, err = p.communicate()
                err = (err or "") + " [killed at the limit]"
            outputs[(kind, who)] = (p.returncode, (out or "") + (err or ""))
        wall = time.monotonic() - started
        # Start-up: from the first process started to the last agent connected (every
        # agent's result file says when it connected, on this machine's clock).
        connected = []
        results_dir = os.path.join(d, "results")
        for name in os.listdir(results_dir) if os.path.isdir(results_dir) else []:
            try:
                with open(os.path.join(results_dir, name)) as f:
                    connected.append(json.load(f)["connected_unix_ns"])
            except (OSError, ValueError, KeyError):
                pass
        startup = (max(connected) - started_ns) / 1e9 if connected else float("nan")
        if args.keep_results:
            import shutil
            shutil.copytree(os.path.join(d, "results"), os.path.join(args.keep_results, run),
                            dirs_exist_ok=True)
        collected = subprocess.run([args.binary, "collect", "--team", team, "--check", "--json"],
                                   capture_output=True, text=True)
        try:
            result = json.loads(collected.stdout)
        except json.JSONDecodeError:
            result = {}
        host_codes = [outputs[("host", h)][0] for h in range(len(hosts))]
        failed_agents = [w for (kind, w), (rc, _) in outputs.items() if kind == "agent" and rc != 0]
        errors = sorted({f"{kind} {w}: {text.strip().splitlines()[-1]}"
                         for (kind, w), (rc, text) in outputs.items()
                         if rc != 0 and text.strip()})
        first_error = next((e for e in errors if "stopped at round" not in e),
                           errors[0] if errors else "")
        if args.verbose:
            for e in errors:
                print("   ", e[:300], file=sys.stderr)
        if args.log_dir and not (result.get("certified") and result.get("optimal")):
            where = os.path.join(args.log_dir, run)
            os.makedirs(where, exist_ok=True)
            for (kind, w), (rc, text) in outputs.items():
                with open(os.path.join(where, f"{kind}{w}.log"), "w") as f:
                    f.write(f"exit {rc}\n{text}")
        latency = result.get("round_latency_us", {}).get("round", {})
        return {
            "run": k, "wall_s": round(wall, 2), "startup_s": round(startup, 2),
            "certified": result.get("certified"), "optimal": result.get("optimal"),
            "iterations": result.get("iterations"),
            "round_p50_ms": round(latency.get("p50", float("nan")) / 1e3, 2),
            "round_p99_ms": round(latency.get("p99", float("nan")) / 1e3, 2),
            "host_codes": host_codes, "failed_agents": len(failed_agents),
            "error": first_error[:200],
        }


def hungarian_cost(binary, rows, directory):
    """The optimum of the stacked rows, from the centralized oracle."""
    csv = os.path.join(directory, "episode.csv")
    with open(csv, "w") as f:
        for r in rows:
            f.write(",".join(repr(v) for v in r) + "\n")
    done = subprocess.run([binary, "solve", "--costs", csv, "--method", "hungarian", "--json"],
                          capture_output=True, text=True, check=True)
    return json.loads(done.stdout)["cost"]


def standing_rows(n, episodes, seed):
    """Half drifting episodes (±1 % of the range each), then half redrawn."""
    rng = random.Random(seed)
    rows = [[rng.random() for _ in range(n)] for _ in range(n)]
    out = []
    for k in range(episodes):
        if k == 0 or k >= episodes // 2:
            rows = [[rng.random() for _ in range(n)] for _ in range(n)]
        else:
            rows = [[min(1.0, max(0.0, v + rng.uniform(-0.01, 0.01))) for v in r] for r in rows]
        out.append(("redrawn" if k == 0 or k >= episodes // 2 else "drift", rows))
    return out


def start_standing(args, hosts, team, per, d, procs, sidecars):
    """Every host and its sidecars, in their namespaces; logs go to files in `d` (a pipe
    nobody reads would stop a talkative process)."""
    first = 0
    for h, (ns, _) in enumerate(hosts):
        with open(os.path.join(d, f"host{h}.log"), "w") as log:
            procs.append(subprocess.Popen(
                ["ip", "netns", "exec", ns, args.binary, "host", "--team", team, "--name", f"h{h}"],
                stdout=subprocess.DEVNULL, stderr=log, text=True))
        for a in range(first, first + per[h]):
            with open(os.path.join(d, f"robot{a}.log"), "w") as log:
                sidecars.append(subprocess.Popen(
                    ["ip", "netns", "exec", ns, args.binary, "agent", "--team", team,
                     "--robot", str(a), "--serve"],
                    stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=log,
                    text=True, bufsize=1))
        first += per[h]


def episode_ok(answers, rows, best, k):
    """Every robot certified, on episode `k`, with the same total and assignment: a
    permutation whose cost on the stacked rows is the optimum `best`."""
    close = lambda a, b: a is not None and abs(a - b) <= 1e-9 * max(1.0, abs(b))
    first = answers[0].get("assignment")
    if not first or any(t is None for t in first) or len(set(first)) != len(first):
        return False
    return (all(a.get("certified") and a.get("episode") == k and a.get("assignment") == first
                and close(a.get("total_cost"), best) for a in answers)
            and close(sum(rows[i][t] for i, t in enumerate(first)), best))


def one_episode(args, sidecars, rows, k, d):
    """Writes every robot's row and reads every answer (the watchdog ends a wedged team)."""
    limit = args.episode_timeout + args.round_timeout + (args.startup_timeout if k == 0 else 0)
    watchdog = threading.Timer(limit + 30, lambda: [s.kill() for s in sidecars])
    watchdog.start()
    try:
        def ended(i):
            with open(os.path.join(d, f"robot{i}.log")) as f:
                said = f.read().strip().splitlines()[-1:]
            return SystemExit(f"episode {k}: robot {i} ended: exit {sidecars[i].wait()} {said}")

        started = time.monotonic()
        for i, (s, row) in enumerate(zip(sidecars, rows)):
            try:
                s.stdin.write(json.dumps({"costs": row}) + "\n")
                s.stdin.flush()
            except BrokenPipeError:
                raise ended(i) from None
        answers = []
        for i, s in enumerate(sidecars):
            line = s.stdout.readline()
            if not line:
                raise ended(i)
            answers.append(json.loads(line))
        return time.monotonic() - started, answers
    finally:
        watchdog.cancel()


def stop_all(sidecars, procs, within=120):
    """Closes every sidecar's input and waits for all, hosts last, against one deadline;
    kills what is left then. The exit codes."""
    for s in sidecars:
        try:
            s.stdin.close()
        except OSError:
            pass
    deadline = time.monotonic() + within
    for p in sidecars + procs:
        try:
            p.wait(timeout=max(0.1, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()
    return [s.returncode for s in sidecars], [p.returncode for p in procs]


def standing_team(args, hosts):
    """A standing team of private-cost sidecars across the namespaces; one line per episode."""
    n = args.agents
    with tempfile.TemporaryDirectory() as d:
        team = os.path.join(d, "team.toml")
        per = team_file(team, args, hosts, f"{TAG}s", args.seed, costs="private")
        procs, sidecars, lines = [], [], []
        try:
            start_standing(args, hosts, team, per, d, procs, sidecars)
            for k, (kind, rows) in enumerate(standing_rows(n, args.episodes, args.seed)):
                latency, answers = one_episode(args, sidecars, rows, k, d)
                best = hungarian_cost(args.binary, rows, d)
                line = {"episode": k, "costs": kind, "ok": episode_ok(answers, rows, best, k),
                        "latency_s": round(latency, 2), "rounds": answers[0].get("rounds"),
                        "agreement_rounds": answers[0].get("agreement_rounds"),
                        "sent_kB": round(answers[0].get("sent_bytes", 0) / 1e3, 1),
                        "cost": answers[0].get("total_cost"), "optimum": best}
                lines.append(line)
                print(json.dumps(line), flush=True)
        finally:
            codes, host_codes = stop_all(sidecars, procs)
        passed = sum(x["ok"] for x in lines)
        latencies = sorted(x["latency_s"] for x in lines)
        rounds = sorted(x["rounds"] for x in lines)
        print(f"standing {args.method} team of {n} on {len(hosts)} hosts: {passed}/{len(lines)} "
              f"episodes certified optimal, latency median {latencies[len(latencies) // 2]} s "
              f"(max {latencies[-1]} s), rounds median {rounds[len(rounds) // 2]}, "
              f"sidecar exits {sorted(set(codes))}, host exits {host_codes}", flush=True)
        return passed == len(lines) == args.episodes and not any(codes) and not any(host_codes)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--binary", default="target/release/admm-ta")
    parser.add_argument("--agents", type=int, default=100)
    parser.add_argument("--hosts", type=int, default=4)
    parser.add_argument("--transport", choices=["zenoh", "mixed"], default="zenoh")
    parser.add_argument("--topology", default="random:0.1")
    parser.add_argument("--method", default="primal", help="the team's method (dual, …)")
    parser.add_argument("--round-timeout", type=float, default=10.0)
    parser.add_argument("--startup-timeout", type=float, default=60.0)
    parser.add_argument("--runs", type=int, default=1)
    parser.add_argument("--episodes", type=int,
                        help="run a standing team of private costs for this many episodes")
    parser.add_argument("--episode-timeout", type=float, default=300.0)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--limit", type=float, default=300.0, help="seconds per run")
    parser.add_argument("--verbose", action="store_true", help="every failing process's line")
    parser.add_argument("--host-log", help="RUST_LOG filter of the host processes")
    parser.add_argument("--agent-log", help="RUST_LOG filter of the agent processes")
    parser.add_argument("--host-nice", type=int, help="niceness of the host processes")
    parser.add_argument("--keep-results", help="where every run's results directory is copied")
    parser.add_argument("--log-dir", help="where a failed run's process outputs are kept")
    args = parser.parse_args()
    args.binary = os.path.abspath(args.binary)
    if os.geteuid() != 0:
        sys.exit("needs root (ip netns)")
    bridge, hosts = None, []
    try:
        bridge, hosts = make_hosts(args.hosts)
        if args.episodes:
            return 0 if standing_team(args, hosts) else 1
        rows = []
        for k in range(args.runs):
            row = one_run(args, hosts, k)
            rows.append(row)
            print(json.dumps(row), flush=True)
        good = [r for r in rows if r["certified"] and r["optimal"]]
        walls = sorted(r["wall_s"] for r in good)
        startups = sorted(r["startup_s"] for r in good)
        p50s = sorted(r["round_p50_ms"] for r in good)
        print(f"{args.transport}, {args.agents} agents on {args.hosts} hosts: "
              f"{len(good)}/{len(rows)} certified optimal"
              + (f", start-up median {startups[len(startups) // 2]} s"
                 f", wall median {walls[len(walls) // 2]} s, round p50 median "
                 f"{p50s[len(p50s) // 2]} ms" if good else ""))
    finally:
        if bridge:
            remove_hosts(bridge, hosts)


if __name__ == "__main__":
    sys.exit(main())
