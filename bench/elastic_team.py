#!/usr/bin/env python3
"""What a change of members costs a standing team: episode latency and rounds in the episode
of a leave, a join and a crash, against the steady episodes around them, and how long a
robot takes from its process start to its first answer. Standard library only.

    python3 bench/elastic_team.py --binary target/release/admm-ta [--robots 8] \
        [--tasks 6] [--topology ring] [--transport ipc|shm|uds|zenoh|mixed] \
        [--steady 20] [--repeat 5] [--json out.json]

Each repeat starts a fresh team of `--robots` sidecars (zenoh and mixed: two hosts on
loopback, half the robots each), feeds them as robot programs would (fresh uniform costs
every episode) and runs, in this order:

* one episode (the team's first: start-up effects), then `--steady` episodes with every
  robot;
* **leave**: robot `n − 3` closes its input (it relays in that episode, the others solve);
  `--steady` episodes without it;
* **join**: a new process for that slot is started with its first row; the others run
  episodes until they name it in `joined` (its first answer); the episode of the join is
  the slower of the one that admitted it (after which the others move to the new roster)
  and its first; `--steady` episodes with it;
* **crash**: robot 1 is killed (SIGKILL) between episodes; the next episode (solved again
  without it after the survivors notice) is the crash episode; `--steady` episodes after.

An episode's latency is the wall time from the first row written to the last answer read.
Every episode must be certified with one assignment (else the script says so and exits 1).
Prints one row per phase (medians over repeats of each phase's p50, and of the change
episodes), and writes every measurement to `--json`.
"""

import argparse
import json
import os
import random
import socket
import statistics
import subprocess
import sys
import tempfile
import time


def percentile(values, q):
    values = sorted(values)
    if not values:
        return float("nan")
    return values[min(len(values) - 1, max(0, int(round(q / 100 * (len(values) - 1)))))]


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Robot:
    def __init__(self, binary, team, robot):
        self.robot = robot
        self.started = time.monotonic()
        self.process = subprocess.Popen(
            [binary, "agent", "--team", team, "--robot", str(robot), "--serve"],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, bufsize=1)

    def send(self, row):
        self.process.stdin.write(json.dumps({"costs": row}) + "\n")
        self.process.stdin.flush()

    def answer(self):
        line = self.process.stdout.readline()
        if not line:
            sys.exit(f"robot {self.robot} ended: exit {self.process.wait()}")
        return json.loads(line)


class Fleet:
    def __init__(self, args, directory, run):
        self.args = args
        self.rng = random.Random(hash(run) & 0xFFFF)
        n = args.robots
        self.team = os.path.join(directory, f"{run}.toml")
        text = (f'run = "{run}"\nrobots = {n}\ntasks = {args.tasks}\ncosts = "private"\n'
                f'topology = "{args.topology}"\nround_timeout = 30.0\nepisode_timeout = 60.0\n'
                f'startup_timeout = 60.0\ntransport = "{args.transport}"\n')
        self.hosts = []
        if args.transport in ("zenoh", "mixed"):
            half = n // 2
            for name, agents in (("alpha", range(half)), ("beta", range(half, n))):
                text += (f'\n[[hosts]]\nname = "{name}"\nagents = {list(agents)}\n'
                         f'endpoint = "tcp/127.0.0.1:{free_port()}"\n')
        with open(self.team, "w", encoding="utf-8") as f:
            f.write(text)
        for name in ("alpha", "beta") if text.count("[[hosts]]") else ():
            self.hosts.append(subprocess.Popen(
                [args.binary, "host", "--team", self.team, "--name", name],
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        self.members = {i: Robot(args.binary, self.team, i) for i in range(n)}
        self.joining = None

    def row(self):
        return [round(self.rng.random(), 6) for _ in range(self.args.tasks)]

    def episode(self):
        """One episode: (latency in ms, the first answer, the joiner's answer if it came)."""
        start = time.monotonic()
        for robot in self.members.values():
            robot.send(self.row())
        answers = {i: r.answer() for i, r in self.members.items()}
        first = next(iter(answers.values()))
        joined = None
        if self.joining is not None and self.joining.robot in first.get("joined", []):
            joined = self.joining.answer()
            answers[self.joining.robot] = joined
            self.members[self.joining.robot] = self.joining
            self.joining = None
        took = (time.monotonic() - start) * 1e3
        for i, a in answers.items():
            if not a.get("certified") or a["assignment"] != first["assignment"]:
                sys.exit(f"episode {first['episode']}: robot {i}: {a}")
        return took, first, joined

    def finish(self):
        for robot in self.members.values():
            robot.process.stdin.close()
        for robot in self.members.values():
            robot.process.wait()
        for host in self.hosts:
            host.wait()


def steady(fleet, count):
    out = [fleet.episode() for _ in range(count)]
    return {"ms": [t for t, _, _ in out], "rounds": [a["rounds"] for _, a, _ in out],
            "agreement_rounds": [a["agreement_rounds"] for _, a, _ in out]}


def one_repeat(args, directory, k):
    fleet = Fleet(args, directory, f"elastic{k}-{os.getpid()}")
    n = args.robots
    fleet.episode()  # the team's first episode (start-up effects)
    result = {"steady": steady(fleet, args.steady)}
    leaver = n - 3
    fleet.members[leaver].process.stdin.close()
    gone = fleet.members.pop(leaver)
    took, first, _ = fleet.episode()
    gone.process.wait()
    result["leave"] = {"ms": took, "rounds": first["rounds"], "left": first.get("left")}
    result["after leave"] = steady(fleet, args.steady)
    fleet.joining = Robot(args.binary, fleet.team, leaver)
    fleet.joining.send(fleet.row())
    episodes = []
    while fleet.joining is not None:
        took, first, joined = fleet.episode()
        episodes.append(took)
    # The episode that admitted it (the others moved to the new roster after it) and its
    # first one.
    result["join"] = {"ms": max(episodes[-2:]), "first_ms": took,
                      "episodes_until_joined": len(episodes),
                      "start_to_answer_ms": (time.monotonic() - fleet.members[leaver].started) * 1e3,
                      "rounds": first["rounds"]}
    result["after join"] = steady(fleet, args.steady)
    crashed = fleet.members.pop(1)
    crashed.process.kill()
    crashed.process.wait()
    took, first, _ = fleet.episode()
    result["crash"] = {"ms": took, "rounds": first["rounds"], "crashed": first.get("crashed")}
    result["after crash"] = steady(fleet, args.steady)
    fleet.finish()
    return result


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--binary", default="target/release/admm-ta")
    parser.add_argument("--robots", type=int, default=8)
    parser.add_argument("--tasks", type=int, default=6)
    parser.add_argument("--topology", default="ring")
    parser.add_argument("--transport", default="ipc")
    parser.add_argument("--steady", type=int, default=20)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--json")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="admm-ta-elastic-") as directory:
        repeats = [one_repeat(args, directory, k) for k in range(args.repeat)]
    med = statistics.median
    print(f"{args.robots} robots, {args.tasks} tasks, {args.topology}, {args.transport}, "
          f"{args.repeat} repeats (medians over repeats)")
    print("| phase | episode ms p50 | p99 | rounds p50 | agreement rounds |")
    print("| --- | --- | --- | --- | --- |")
    for phase in ("steady", "after leave", "after join", "after crash"):
        p50 = med(percentile(r[phase]["ms"], 50) for r in repeats)
        p99 = med(percentile(r[phase]["ms"], 99) for r in repeats)
        rounds = med(percentile(r[phase]["rounds"], 50) for r in repeats)
        agreement = med(percentile(r[phase]["agreement_rounds"], 50) for r in repeats)
        print(f"| {phase} | {p50:.2f} | {p99:.2f} | {rounds:g} | {agreement:g} |")
    for change in ("leave", "join", "crash"):
        ms = med(r[change]["ms"] for r in repeats)
        rounds = med(r[change]["rounds"] for r in repeats)
        print(f"| episode of the {change} | {ms:.2f} | max {max(r[change]['ms'] for r in repeats):.2f} "
              f"| {rounds:g} | |")
    joins = [r["join"]["start_to_answer_ms"] for r in repeats]
    until = [r["join"]["episodes_until_joined"] for r in repeats]
    print(f"join: process start to first answer {med(joins):.0f} ms (max {max(joins):.0f}), "
          f"named after {med(until):g} episodes (max {max(until)})")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump({"args": vars(args), "repeats": repeats}, f, indent=1)


if __name__ == "__main__":
    main()
