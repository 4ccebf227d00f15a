#!/usr/bin/env python3
"""Starts a standing team of ROS 2 robots: per robot, its admm-ta member (`admm-ta agent
--ros2`, a ROS 2 node) and its robot node (robot_node.py, rclpy); waits for them.

    python3 examples/ros2/start_team.py --admm-ta target/release/admm-ta \\
        --robots 8 --tasks 6 --episodes 20 --topology ring

It writes the team file (costs = "private": every robot keeps its own costs) into --dir
(default: a new temporary directory), starts the processes, and prints each episode's
assignment and total cost as the robots logged them. ROS_DOMAIN_ID and
ROS_AUTOMATIC_DISCOVERY_RANGE pass through to every process (this script sets LOCALHOST
unless the environment says otherwise). Ctrl-C stops them all. Exit code 0 when every robot
answered every episode and they all reported the same certified assignment.
"""

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))


def episodes_of(directory, robots):
    """Every robot's answers, by episode."""
    by_episode = {}
    for i in range(robots):
        with open(os.path.join(directory, f"robot-{i}.jsonl"), encoding="utf-8") as f:
            for line in f:
                answer = json.loads(line).get("answer")
                if answer and "task" in answer:
                    by_episode.setdefault(answer["episode"], []).append(answer)
    return by_episode


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--admm-ta", default="admm-ta", help="the admm-ta binary (--features ros2)")
    parser.add_argument("--robots", type=int, default=8)
    parser.add_argument("--tasks", type=int, default=6)
    parser.add_argument("--episodes", type=int, default=10)
    parser.add_argument("--topology", default="ring")
    parser.add_argument("--method", default="primal", help="primal, dual or inexact-dual")
    parser.add_argument("--run", default=f"ros2-{os.getpid()}", help="the team's name")
    parser.add_argument("--dir", help="where the team file and the logs go")
    args = parser.parse_args()

    directory = args.dir or tempfile.mkdtemp(prefix="admm-ta-ros2-")
    os.makedirs(directory, exist_ok=True)
    team = os.path.join(directory, "team.toml")
    with open(team, "w", encoding="utf-8") as f:
        f.write(f'run = "{args.run}"\nrobots = {args.robots}\ntasks = {args.tasks}\n'
                f'costs = "private"\ntopology = "{args.topology}"\nmethod = "{args.method}"\n'
                f'episode_timeout = 30.0\nround_timeout = 30.0\n')
    env = dict(os.environ)
    env.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    members, robots = [], []
    try:
        for i in range(args.robots):
            log = os.path.join(directory, f"robot-{i}.jsonl")
            if os.path.exists(log):
                os.remove(log)
            members.append(subprocess.Popen(
                [args.admm_ta, "agent", "--team", team, "--robot", str(i), "--ros2"], env=env))
            robots.append(subprocess.Popen(
                [sys.executable, os.path.join(HERE, "robot_node.py"), "--team", team,
                 "--robot", str(i), "--episodes", str(args.episodes), "--log", log],
                stdout=subprocess.DEVNULL, env=env))
        codes = [p.wait() for p in robots + members]
    except KeyboardInterrupt:
        # The members stop the team cleanly on SIGINT; the robot nodes just go.
        for p in members + robots:
            p.send_signal(signal.SIGINT)
        for p in members + robots:
            p.wait()
        return 130

    ok = all(c == 0 for c in codes)
    by_episode = episodes_of(directory, args.robots)
    for episode in sorted(by_episode):
        answers = by_episode[episode]
        same = len({json.dumps(a.get("assignment")) for a in answers}) == 1
        same &= len(answers) == args.robots
        certified = all(a["certified"] for a in answers)
        ok &= same and certified
        first = answers[0]
        print(f"episode {episode}: assignment {first.get('assignment')} total "
              f"{first.get('total_cost')} rounds {first['rounds']} certified={certified}"
              f"{'' if same else ' (robots disagree)'}")
    ok &= len(by_episode) == args.episodes
    print(f"{args.robots} robots, {len(by_episode)} episodes, logs in {directory}: "
          f"{'ok' if ok else 'FAILED'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
