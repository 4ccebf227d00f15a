"""Drives a standing team of `admm-ta agent --ros2` members through ROS 2 topics while its
robots come and go: one rclpy node publishes every robot's rows and takes every answer, a
robot leaves by publishing {"leave": true}, a member is killed (SIGKILL), and a new member
joins a free slot. Run by test_ros2.py (as its own process, in the test's DDS domain).

    python ros2_elastic.py ADMM_TA TEAM_FILE SLOTS TASKS EPISODES PLAN_JSON LOG_DIR

PLAN_JSON maps an episode to [kind, robot] (kind: leave, crash or join). Prints one JSON
line per episode: {"episode", "rows", "answers", "event"}, rows and answers keyed by robot.
"""

import json
import os
import queue
import random
import subprocess
import sys
import threading
import time

import rclpy
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import String

#: How long anything may take (the driver never hangs).
WITHIN = 60


class Member:
    """One `--ros2` member process; its standard error goes to a file and is watched."""

    def __init__(self, admm_ta, team, robot, log_dir):
        self.robot = robot
        self.lines = queue.Queue()
        self.log = open(os.path.join(log_dir, f"member-{robot}-{time.monotonic_ns()}.log"), "w")
        env = {**os.environ, "RUST_LOG": "admm_ta_runtime=info"}
        self.process = subprocess.Popen(
            [admm_ta, "agent", "--team", team, "--robot", str(robot), "--ros2"],
            stderr=subprocess.PIPE, text=True, env=env)
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self):
        for line in self.process.stderr:
            self.log.write(line)
            self.log.flush()
            self.lines.put(line)

    def await_line(self, text):
        end = time.monotonic() + WITHIN
        while time.monotonic() < end:
            try:
                if text in self.lines.get(timeout=end - time.monotonic()):
                    return
            except queue.Empty:
                break
        sys.exit(f"member {self.robot}: no {text!r} within {WITHIN} s")


class Driver:
    """Every robot's rows out and answers in, through one node."""

    def __init__(self, slots):
        self.node = rclpy.create_node("elastic_driver")
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.inbox = {i: [] for i in range(slots)}
        self.rows = [self.node.create_publisher(String, f"/robot{i}/admm_ta/costs", 10)
                     for i in range(slots)]
        for i in range(slots):
            self.node.create_subscription(
                String, f"/robot{i}/admm_ta/assignment",
                lambda m, i=i: self.inbox[i].append(json.loads(m.data)), qos)

    def spin_until(self, done, what):
        end = time.monotonic() + WITHIN
        while not done():
            if time.monotonic() > end:
                sys.exit(f"no {what} within {WITHIN} s")
            rclpy.spin_once(self.node, timeout_sec=0.05)

    def matched(self, robot):
        self.spin_until(lambda: self.rows[robot].get_subscription_count() > 0,
                        f"subscription of robot {robot}'s member")

    def readers(self, robot):
        """The subscriptions to robot's rows on the graph (a member that has gone stays
        there until its DDS lease runs out)."""
        return {bytes(info.endpoint_gid) for info in
                self.node.get_subscriptions_info_by_topic(f"/robot{robot}/admm_ta/costs")}

    def new_reader(self, robot, before):
        """Until a subscription to robot's rows that is not in `before` is on the graph."""
        self.spin_until(lambda: self.readers(robot) - before,
                        f"new subscription of robot {robot}'s member")

    def send(self, robot, value):
        self.rows[robot].publish(String(data=json.dumps(value)))

    def answer(self, robot):
        self.spin_until(lambda: self.inbox[robot], f"answer from robot {robot}")
        return self.inbox[robot].pop(0)


def main():
    admm_ta, team, slots, tasks, episodes, plan, log_dir = sys.argv[1:8]
    slots, tasks, episodes = int(slots), int(tasks), int(episodes)
    plan = {int(k): v for k, v in json.loads(plan).items()}
    rng = random.Random(7)
    rclpy.init()
    driver = Driver(slots)
    members = {i: Member(admm_ta, team, i, log_dir) for i in range(slots)}
    for i in members:
        driver.matched(i)
    joining = None  # (member, its first row)
    try:
        for episode in range(episodes):
            event = plan.get(episode)
            leaving = None
            if event and event[0] == "leave":
                # It goes once the others have taken this episode's rows without it.
                leaving = members.pop(event[1])
                driver.send(event[1], {"leave": True})
            elif event and event[0] == "crash":
                gone = members.pop(event[1])
                gone.process.kill()  # SIGKILL
                gone.process.wait(timeout=WITHIN)
            elif event and event[0] == "join":
                before = driver.readers(event[1])
                joiner = Member(admm_ta, team, event[1], log_dir)
                joiner.await_line("asking to join the running team")
                driver.new_reader(event[1], before)
                first = [round(rng.random() * 10, 3) for _ in range(tasks)]
                driver.send(event[1], {"costs": first})
                joining = (joiner, first)
            rows = {i: [round(rng.random() * 10, 3) for _ in range(tasks)] for i in members}
            for i, row in rows.items():
                driver.send(i, {"costs": row})
            answers = {i: driver.answer(i) for i in members}
            first = next(iter(answers.values()))
            if joining is not None and joining[0].robot in first.get("joined", []):
                joiner, row = joining
                answers[joiner.robot] = driver.answer(joiner.robot)
                rows[joiner.robot] = row
                members[joiner.robot] = joiner
                joining = None
            if leaving is not None and leaving.process.wait(timeout=WITHIN) != 0:
                sys.exit(f"robot {leaving.robot} left with exit code {leaving.process.returncode}")
            print(json.dumps({"episode": episode, "rows": rows, "answers": answers,
                              "event": event}), flush=True)
        for i in members:
            driver.send(i, {"leave": True})
        codes = {i: m.process.wait(timeout=WITHIN) for i, m in members.items()}
        if any(codes.values()):
            sys.exit(f"members exited {codes}")
    finally:
        for m in list(members.values()) + ([joining[0]] if joining else []):
            if m.process.poll() is None:
                m.process.kill()
                m.process.wait()
    return 0


if __name__ == "__main__":
    sys.exit(main())
