#!/usr/bin/env python3
"""Episode latency of a standing team fed through ROS 2 topics (`admm-ta agent --ros2`)
against the same team fed through the sidecar's pipes (`--serve`), in one run.

    target/python-venv/bin/python bench/ros2_team.py --binary target/release/admm-ta \
        --robots 8,50 [--episodes 40] [--topology ring] [--method primal]

Needs rclpy (`pip install "ros-rclpy[fastrtps]" ros-std-msgs`; `./test` puts it in
target/python-venv) and an admm-ta built with `--features ros2`.

For each team size N (N robots, N tasks, private costs) the same sequence of rows (uniform
costs, each moved by up to ±1 % of the range per episode, warm starts) goes to two teams,
both up at once, episode by episode (the first team alternating), so that machine noise
falls on both alike:

* **pipes**: N `--serve` sidecars, one driver writing each robot's row to its sidecar's
  standard input and reading the answers from their standard output;
* **ros2**: N `--ros2` members, one rclpy node publishing each robot's row on
  `/robotI/admm_ta/costs` and taking the answers from `/robotI/admm_ta/assignment`
  (reliable; answers transient local), in a DDS domain of its own. Discovery is ROS 2's
  default (SUBNET: every participant is on this machine, so is the traffic); with
  ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, Fast DDS reaches only the first 32 participants
  of the machine, too few for a driver and 50 members (docs/ros2.md).

The driver takes the answers with rclpy's SingleThreadedExecutor (`--executor single`, the
default) or its EventsExecutor (`--executor events`), whose overhead per message is far
smaller. An episode's latency is the wall time from the first row sent to the last answer in. The
first `--warmup` episodes of each team are left out. Every episode must be certified with
the same assignment at every robot, and both teams must find the same total cost. Prints
p50 / p99 per team and the difference of the p50s.
"""

import argparse
import importlib
import json
import os
import random
import subprocess
import sys
import tempfile
import time

import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import String


def percentile(values, q):
    values = sorted(values)
    k = min(len(values) - 1, max(0, int(round(q / 100 * (len(values) - 1)))))
    return values[k]


def drift(robots, episodes, seed):
    """Rows per episode: uniform costs moving by up to ±1 % each episode."""
    rng = random.Random(seed)
    costs = [[rng.random() for _ in range(robots)] for _ in range(robots)]
    for _ in range(episodes):
        yield [[round(c, 6) for c in row] for row in costs]
        costs = [[min(1.0, max(0.0, c + rng.uniform(-0.01, 0.01))) for c in row]
                 for row in costs]


def write_team(directory, run, robots, topology, method):
    path = os.path.join(directory, f"{run}.toml")
    with open(path, "w", encoding="utf-8") as f:
        f.write(f'run = "{run}"\nrobots = {robots}\ntasks = {robots}\ncosts = "private"\n'
                f'topology = "{topology}"\nmethod = "{method}"\nround_timeout = 30.0\n'
                f'episode_timeout = 60.0\nstartup_timeout = 60.0\n')
    return path


def check(answers, robots, episode):
    views = {json.dumps(a["assignment"]) for a in answers}
    if len(answers) != robots or len(views) != 1 or not all(a["certified"] for a in answers):
        sys.exit(f"episode {episode}: not certified or the robots disagree: {answers[:2]}")
    return answers[0]["total_cost"]


class Members:
    """A team's member processes."""

    members = ()

    def kill(self):
        for m in self.members:
            if m.poll() is None:
                m.kill()
                m.wait()


class Pipes(Members):
    """N sidecars on pipes."""

    def __init__(self, binary, team, robots):
        self.members = [
            subprocess.Popen([binary, "agent", "--team", team, "--robot", str(i), "--serve"],
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
                             bufsize=1)
            for i in range(robots)]

    def episode(self, rows):
        for member, row in zip(self.members, rows):
            member.stdin.write(json.dumps({"costs": row}) + "\n")
            member.stdin.flush()
        return [json.loads(m.stdout.readline()) for m in self.members]

    def close(self):
        for m in self.members:
            m.stdin.close()
        return [m.wait(timeout=60) for m in self.members]


class Topics(Members):
    """N `--ros2` members, one rclpy node with a publisher and a subscription per robot."""

    def __init__(self, binary, team, robots, env, executor):
        self.members = [
            subprocess.Popen([binary, "agent", "--team", team, "--robot", str(i), "--ros2"],
                             env=env)
            for i in range(robots)]
        self.node = rclpy.create_node(f"bench_driver_{robots}")
        self.executor = executor()
        self.executor.add_node(self.node)
        answers_qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                                 durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.inbox = {}
        self.rows = [self.node.create_publisher(String, f"/robot{i}/admm_ta/costs", 10)
                     for i in range(robots)]
        for i in range(robots):
            self.node.create_subscription(
                String, f"/robot{i}/admm_ta/assignment",
                lambda m, i=i: self.inbox.__setitem__(i, json.loads(m.data)), answers_qos)
        end = time.monotonic() + 120
        while any(p.get_subscription_count() == 0 for p in self.rows):
            if time.monotonic() > end:
                self.kill()
                sys.exit("the ROS 2 members did not subscribe within 120 s")
            self.executor.spin_once(timeout_sec=0.05)

    def episode(self, rows):
        self.inbox.clear()
        for publisher, row in zip(self.rows, rows):
            publisher.publish(String(data=json.dumps({"costs": row})))
        deadline = time.monotonic() + 120
        while len(self.inbox) < len(self.rows):
            if time.monotonic() > deadline or any(m.poll() is not None for m in self.members):
                codes = [m.poll() for m in self.members]
                self.kill()
                sys.exit(f"a ROS 2 member exited, or no answer within 120 s: exit codes {codes}, "
                         f"answers from {sorted(self.inbox)}")
            self.executor.spin_once(timeout_sec=1.0)
        return [self.inbox[i] for i in range(len(self.rows))]

    def close(self):
        for publisher in self.rows:
            publisher.publish(String(data=json.dumps({"leave": True})))
        end = time.monotonic() + 0.5
        while time.monotonic() < end:
            self.executor.spin_once(timeout_sec=0.1)
        codes = [m.wait(timeout=60) for m in self.members]
        self.executor.remove_node(self.node)
        self.executor.shutdown()
        self.node.destroy_node()
        return codes


def measure(teams, sequence, robots, warmup):
    """Each episode's rows to every team in turn (the first team alternating), so that both
    see the same machine; the wall times per team after the warmup, and the total costs."""
    times = [[] for _ in teams]
    totals = [[] for _ in teams]
    for episode, rows in enumerate(sequence):
        order = range(len(teams)) if episode % 2 == 0 else reversed(range(len(teams)))
        for k in order:
            began = time.perf_counter()
            answers = teams[k].episode(rows)
            elapsed = time.perf_counter() - began
            totals[k].append(check(answers, robots, episode))
            if episode >= warmup:
                times[k].append(elapsed * 1e3)
    for team in teams:
        codes = team.close()
        if any(codes):
            sys.exit(f"members exited {codes}")
    return times, totals


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--binary", default="target/release/admm-ta")
    parser.add_argument("--robots", default="8,50")
    parser.add_argument("--episodes", type=int, default=40)
    parser.add_argument("--warmup", type=int, default=3)
    parser.add_argument("--topology", default="ring")
    parser.add_argument("--method", default="primal")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--executor", choices=("single", "events"), default="single",
                        help="the driver's rclpy executor (events: rclpy's EventsExecutor)")
    args = parser.parse_args()
    env = dict(os.environ)
    env.setdefault("ROS_DOMAIN_ID", str(60 + os.getpid() % 40))
    os.environ.update(env)
    rclpy.init()
    if args.executor == "single":
        executor = SingleThreadedExecutor
    else:
        executor = importlib.import_module("rclpy.experimental").EventsExecutor
    directory = tempfile.mkdtemp(prefix="admm-ta-ros2-bench-")
    print("| robots | pipes p50 / p99 (ms) | ROS 2 p50 / p99 (ms) | ROS 2 − pipes, p50 (ms) |")
    print("| --- | --- | --- | --- |")
    teams = []
    try:
        for k, robots in enumerate(int(r) for r in args.robots.split(",")):
            compare(args, executor, directory, env, f"ros2bench-{os.getpid()}-{k}-{robots}",
                    robots, teams)
    finally:
        # Whatever stopped the run (a check, a dead member, Ctrl-C), no member stays.
        for team in teams:
            team.kill()
        rclpy.shutdown()


def compare(args, executor, directory, env, run, robots, teams):
    """One team size: both teams up, the same episodes, one line of the table."""
    sequence = list(drift(robots, args.episodes, args.seed))
    teams.append(Pipes(args.binary, write_team(directory, run + "p", robots, args.topology,
                                               args.method), robots))
    teams.append(Topics(args.binary, write_team(directory, run + "r", robots, args.topology,
                                                args.method), robots, env, executor))
    (pipes, topics), (pipe_totals, topic_totals) = measure(
        teams[-2:], sequence, robots, args.warmup)
    if any(abs(a - b) > 1e-9 * max(1.0, abs(a)) for a, b in zip(pipe_totals, topic_totals)):
        sys.exit("the two teams found different optima")
    p50p, p50r = percentile(pipes, 50), percentile(topics, 50)
    print(f"| {robots} | {p50p:.2f} / {percentile(pipes, 99):.2f} | "
          f"{p50r:.2f} / {percentile(topics, 99):.2f} | {p50r - p50p:+.2f} |", flush=True)


if __name__ == "__main__":
    main()
