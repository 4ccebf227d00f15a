#!/usr/bin/env python3
"""Starts a standing team of robot programs (robot.py, standard library only), each with its
own admm-ta sidecar, and waits for them.

    python3 examples/robots/start_team.py --admm-ta target/release/admm-ta \\
        --robots 8 --tasks 6 --episodes 20 --topology ring

It writes the team file (costs = "private": every robot keeps its own costs) into --dir
(default: a new temporary directory), starts one robot.py per robot, and prints each
episode's assignment and total cost as the robots reported them. Exit code 0 when every
robot answered every episode and they all reported the same certified assignment (or all
said the episode had no feasible assignment: tasks beyond every robot's battery range).
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--admm-ta", default="admm-ta", help="the admm-ta binary")
    parser.add_argument("--robots", type=int, default=8)
    parser.add_argument("--tasks", type=int, default=6)
    parser.add_argument("--episodes", type=int, default=10)
    parser.add_argument("--topology", default="ring")
    parser.add_argument("--run", default=f"robots-{os.getpid()}", help="the team's name")
    parser.add_argument("--dir", help="where the team file and the answers go")
    args = parser.parse_args()

    directory = args.dir or tempfile.mkdtemp(prefix="admm-ta-robots-")
    os.makedirs(directory, exist_ok=True)
    team = os.path.join(directory, "team.toml")
    with open(team, "w", encoding="utf-8") as f:
        f.write(f'run = "{args.run}"\nrobots = {args.robots}\ntasks = {args.tasks}\n'
                f'costs = "private"\ntopology = "{args.topology}"\n'
                f'episode_timeout = 30.0\nround_timeout = 30.0\n')
    robots = []
    for i in range(args.robots):
        answers = os.path.join(directory, f"answers-{i}.jsonl")
        if os.path.exists(answers):
            os.remove(answers)
        robots.append(subprocess.Popen(
            [sys.executable, os.path.join(HERE, "robot.py"), "--admm-ta", args.admm_ta,
             "--team", team, "--id", str(i), "--episodes", str(args.episodes),
             "--answers", answers],
            stdout=subprocess.DEVNULL))
    codes = [r.wait() for r in robots]

    ok = all(c == 0 for c in codes)
    by_episode = {}
    for i in range(args.robots):
        with open(os.path.join(directory, f"answers-{i}.jsonl"), encoding="utf-8") as f:
            for line in f:
                answer = json.loads(line)
                if "episode" in answer and "task" in answer and not answer.get("left"):
                    by_episode.setdefault(answer["episode"], []).append(answer)
    for episode in sorted(by_episode):
        answers = by_episode[episode]
        views = {json.dumps(a.get("assignment")) for a in answers}
        same = len(views) == 1 and len(answers) == args.robots
        certified = all(a["certified"] for a in answers)
        # Tasks out of every robot's battery range: no feasible assignment, said by all.
        infeasible = all(a["feasible"] is False for a in answers)
        ok &= same and (certified or infeasible)
        first = answers[0]
        print(f"episode {episode}: assignment {first.get('assignment')} total "
              f"{first.get('total_cost')} rounds {first['rounds']} certified={certified}"
              f"{' (infeasible: ' + first.get('unsolved', '') + ')' if infeasible else ''}"
              f"{'' if same else ' (robots disagree)'}")
    if len(by_episode) != args.episodes:
        ok = False
    print(f"{args.robots} robots, {len(by_episode)} episodes, answers in {directory}: "
          f"{'ok' if ok else 'FAILED'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
