#!/usr/bin/env python3
"""One robot of a standing admm-ta team, as a ROS 2 node (rclpy).

The robot knows only its own costs: its distance to each task, and which tasks its battery
cannot reach (null: forbidden). Its team member is a separate process,

    admm-ta agent --team TEAM --robot I --ros2

a ROS 2 node `/robotI/admm_ta` that takes this robot's rows from the topic
`/robotI/admm_ta/costs` and publishes its answers on `/robotI/admm_ta/assignment`, both
`std_msgs/String` carrying one JSON line each (the sidecar protocol of docs/standing-teams.md).
Each episode this node publishes {"costs": [...], "episode": k}, waits for the answer of
episode k ({"episode": k, "task": j, "certified": true, ...}), drives to its task, spending
battery, and the tasks move. At the end it publishes {"leave": true}: the robot leaves the
team and its member exits.

    python3 robot_node.py --team team.toml --robot 3 --episodes 20

Every row and answer goes to --log FILE (JSON lines {"row": ...} and {"answer": ...}).
--bad-row-at K first publishes a row of the wrong length in episode K (its error comes back
on the answers' topic, and the episode goes on). Exit code 0 when every episode was
answered; 1 otherwise, or when the ROS 2 teardown at the end hangs for 10 s (where every
thread was goes to standard error).
"""

import argparse
import faulthandler
import json
import math
import random
import re
import sys
import time

import rclpy
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import String

# The answers' QoS: the member keeps its latest answer for subscribers that come late
# (transient local). A depth of 10 keeps an error line that comes just before an answer;
# answers are told apart by their "episode".
ANSWERS_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=10,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)


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


class Robot(Node):
    """Publishes rows, collects answers."""

    def __init__(self, namespace):
        super().__init__("robot", namespace=namespace)
        # Relative names: /robotI/admm_ta/costs and /robotI/admm_ta/assignment.
        self.rows = self.create_publisher(String, "admm_ta/costs", 10)
        self.inbox = []
        self.create_subscription(String, "admm_ta/assignment", self.on_answer, ANSWERS_QOS)

    def on_answer(self, message):
        self.inbox.append(json.loads(message.data))

    def publish(self, value):
        self.rows.publish(String(data=json.dumps(value)))

    def wait_for_member(self, timeout):
        """Until the member subscribes to the rows (a row published before is lost)."""
        deadline = time.monotonic() + timeout
        while self.rows.get_subscription_count() == 0:
            if time.monotonic() > deadline:
                return False
            rclpy.spin_once(self, timeout_sec=0.05)
        return True

    def next_message(self, timeout):
        """The next message on the answers' topic, or None after `timeout` seconds."""
        deadline = time.monotonic() + timeout
        while not self.inbox:
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            rclpy.spin_once(self, timeout_sec=min(left, 0.5))
        return self.inbox.pop(0)


def answer_of(robot, episode, timeout, log):
    """The answer of `episode`; errors about rows are printed and skipped."""
    while True:
        message = robot.next_message(timeout)
        if message is None:
            print(f"{robot.get_namespace()}: no answer for episode {episode}", file=sys.stderr)
            return None
        log({"answer": message})
        if message.get("failed"):
            print(f"{robot.get_namespace()}: the team failed: {message['error']}",
                  file=sys.stderr)
            return None
        if "error" in message:
            print(f"{robot.get_namespace()}: {message['error']}", file=sys.stderr)
            continue
        if message.get("episode") == episode:
            return message


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--team", required=True, help="the team file (costs = \"private\")")
    parser.add_argument("--robot", type=int, required=True, help="this robot's number")
    parser.add_argument("--namespace", help="the member's namespace (default /robotI)")
    parser.add_argument("--episodes", type=int, default=10)
    parser.add_argument("--seed", type=int, default=1, help="where the tasks are")
    parser.add_argument("--range", type=float, default=1.2,
                        help="farthest task a full battery reaches (farther: forbidden)")
    parser.add_argument("--timeout", type=float, default=120.0,
                        help="seconds to wait for the member and for each answer")
    parser.add_argument("--log", help="append every row and answer here (JSON lines)")
    parser.add_argument("--bad-row-at", type=int, help="publish a bad row first in episode K")
    args = parser.parse_args()

    log_file = open(args.log, "a", encoding="utf-8") if args.log else None

    def log(value):
        if log_file:
            log_file.write(json.dumps(value) + "\n")
            log_file.flush()

    # This robot's own state: nobody else knows it.
    me = random.Random(f"{args.seed}-robot-{args.robot}")
    x, y, battery = me.random(), me.random(), 1.0
    tasks = tasks_of(args.team)

    rclpy.init()
    robot = Robot(args.namespace or f"/robot{args.robot}")
    answered = 0
    try:
        if not robot.wait_for_member(args.timeout):
            print(f"robot {args.robot}: no member subscribed to the rows", file=sys.stderr)
            return 1
        for episode in range(args.episodes):
            places = tasks_at(episode, tasks, args.seed)
            reach = args.range * battery
            costs = []
            for (tx, ty) in places:
                d = math.hypot(tx - x, ty - y)
                costs.append(round(d, 6) if d <= reach else None)
            if episode == args.bad_row_at:
                robot.publish({"costs": costs[:-1], "episode": episode})
            row = {"costs": costs, "episode": episode}
            log({"row": row})
            robot.publish(row)
            answer = answer_of(robot, episode, args.timeout, log)
            if answer is None:
                break
            answered += 1
            task = answer.get("task")
            print(f"robot {args.robot} episode {episode}: task {task}"
                  f" certified={answer['certified']} rounds={answer['rounds']}"
                  f" team total={answer.get('total_cost')}", flush=True)
            if task is not None:
                tx, ty = places[task]
                battery = max(0.2, battery - 0.3 * math.hypot(tx - x, ty - y))
                x, y = tx, ty
            battery = min(1.0, battery + 0.05)
        robot.publish({"leave": True})
        # The leave is on its way before the node goes.
        end = time.monotonic() + 0.5
        while time.monotonic() < end:
            rclpy.spin_once(robot, timeout_sec=0.1)
    finally:
        # Fast DDS 3.2 (the PyPI wheels' DDS) now and then never returns from a
        # participant's teardown (seen in this project's tests: a node that had every answer
        # never exited). rclpy holds the interpreter's lock in there, so no Python thread
        # could step in: faulthandler's own thread prints where every thread is and exits
        # with 1 after TEARDOWN_LIMIT seconds, instead of a hang.
        faulthandler.dump_traceback_later(TEARDOWN_LIMIT, exit=True)
        robot.destroy_node()
        rclpy.try_shutdown()
    return 0 if answered == args.episodes else 1


# How long the ROS 2 teardown may take (seconds).
TEARDOWN_LIMIT = 10.0


if __name__ == "__main__":
    sys.exit(main())
