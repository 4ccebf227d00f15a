#!/usr/bin/env python3
"""One robot program of a standing admm-ta team, with the Python standard library only.

The robot knows only its own costs: its distance to each task, and which tasks its battery
cannot reach (null: forbidden). It starts its own agent as a sidecar,

    admm-ta agent --team TEAM --robot I --serve

writes one JSON line per episode to it ({"costs": [...]}) and reads its task back
({"episode": k, "task": j, "certified": true, ...}). After each episode it drives to its
task, spending battery; the tasks move. Closing the sidecar's input leaves the team.

    python3 robot.py --admm-ta target/release/admm-ta --team team.toml --id 3 --episodes 20

Every answer is also appended, as the sidecar wrote it, to --answers FILE (one JSON line
each). Exit code: 0 when every episode was answered, 1 otherwise (the sidecar's error is on
standard error).
"""

import argparse
import json
import math
import random
import re
import subprocess
import sys


def tasks_at(episode, tasks, seed):
    """Where the tasks are in an episode: public, the same at every robot."""
    rng = random.Random(f"{seed}-tasks-{episode}")
    return [(rng.random(), rng.random()) for _ in range(tasks)]


def tasks_of(team):
    """The team file's `tasks` (the tasks every episode has here)."""
    with open(team, encoding="utf-8") as f:
        for line in f:
            match = re.match(r"\s*tasks\s*=\s*(\d+)", line)
            if match:
                return int(match.group(1))
    raise SystemExit(f"{team}: no tasks = N")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--admm-ta", required=True, help="the admm-ta binary")
    parser.add_argument("--team", required=True, help="the team file (costs = \"private\")")
    parser.add_argument("--id", type=int, required=True, help="this robot's number")
    parser.add_argument("--episodes", type=int, default=10)
    parser.add_argument("--seed", type=int, default=1, help="where the tasks are")
    parser.add_argument("--range", type=float, default=1.2,
                        help="farthest task a full battery reaches (farther: forbidden)")
    parser.add_argument("--answers", help="append every answer here (JSON lines)")
    args = parser.parse_args()

    # This robot's own state: nobody else knows it.
    me = random.Random(f"{args.seed}-robot-{args.id}")
    x, y, battery = me.random(), me.random(), 1.0

    sidecar = subprocess.Popen(
        [args.admm_ta, "agent", "--team", args.team, "--robot", str(args.id), "--serve"],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, bufsize=1)
    answers = open(args.answers, "a", encoding="utf-8") if args.answers else None

    def read():
        line = sidecar.stdout.readline()
        if not line:
            return None
        if answers:
            answers.write(line)
            answers.flush()
        return json.loads(line)

    tasks = tasks_of(args.team)
    answered = 0
    for episode in range(args.episodes):
        places = tasks_at(episode, tasks, args.seed)
        reach = args.range * battery
        costs = []
        for (tx, ty) in places:
            d = math.hypot(tx - x, ty - y)
            costs.append(round(d, 6) if d <= reach else None)
        # The episode number: a row that missed its episode's deadline is refused, not
        # used for the next one.
        sidecar.stdin.write(json.dumps({"costs": costs, "episode": episode}) + "\n")
        sidecar.stdin.flush()
        answer = read()
        while answer is not None and "error" in answer:
            print(f"robot {args.id}: {answer['error']}", file=sys.stderr)
            answer = read()
        if answer is None:
            break
        answered += 1
        task = answer.get("task")
        print(f"robot {args.id} episode {answer['episode']}: task {task}"
              f" certified={answer['certified']} rounds={answer['rounds']}"
              f" team total={answer.get('total_cost')}", flush=True)
        if answer.get("left"):
            break
        if task is not None:
            tx, ty = places[task]
            battery = max(0.2, battery - 0.3 * math.hypot(tx - x, ty - y))
            x, y = tx, ty
        battery = min(1.0, battery + 0.05)
    sidecar.stdin.close()  # leave the team
    for line in sidecar.stdout:  # the team's last word
        if answers:
            answers.write(line)
    code = sidecar.wait()
    if code != 0:
        print(f"robot {args.id}: the sidecar exited with {code}", file=sys.stderr)
    return 0 if answered == args.episodes and code == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
