"""Robots that are ROS 2 nodes: real rclpy nodes (examples/ros2/robot_node.py, separate
processes) drive a standing team of `admm-ta agent --ros2` members through ROS 2 topics.

Needs rclpy and std_msgs in this environment (`./test` installs the wheels from PyPI) and
an admm-ta built with `--features ros2` in ADMM_TA_ROS2_BIN (`./test` builds it); without
either the tests are skipped with the reason. DDS discovery stays on this machine
(ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST), in a domain of each test's own.
"""

import json
import os
import re
import signal
import subprocess
import sys
import time

import pytest

from test_elastic import optimum as stacked_optimum
from test_interrupt import alive, team_shm
from test_team import optimum

rclpy = pytest.importorskip(
    "rclpy", reason="rclpy is not installed (pip install 'ros-rclpy[fastrtps]' ros-std-msgs)")

ADMM_TA = os.environ.get("ADMM_TA_ROS2_BIN")
if not ADMM_TA or not os.access(ADMM_TA, os.X_OK):
    pytest.skip("ADMM_TA_ROS2_BIN names no admm-ta built with --features ros2 (./test sets it)",
                allow_module_level=True)

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ROBOT_NODE = os.path.join(REPO, "examples", "ros2", "robot_node.py")
ELASTIC_DRIVER = os.path.join(os.path.dirname(os.path.abspath(__file__)), "ros2_elastic.py")
_domains = iter(range(1 + os.getpid() % 50, 233))
_runs = iter(range(1_000_000))


# Waits until the nodes named in argv[1] (JSON [[namespace, name], ...]) are on the graph
# (its caller holds the deadline).
WAIT_FOR_NODES = """
import json, sys, rclpy
rclpy.init()
node = rclpy.create_node("wait_for_robots")
wanted = {tuple(w) for w in json.loads(sys.argv[1])}
while not wanted <= {(ns, n) for n, ns in node.get_node_names_and_namespaces()}:
    rclpy.spin_once(node, timeout_sec=0.1)
node.destroy_node()
rclpy.shutdown()
"""


# The signals of a crash (not of someone stopping the node).
CRASHES = {signal.SIGSEGV, signal.SIGBUS, signal.SIGABRT, signal.SIGILL, signal.SIGFPE}

# What robot_node.py's watchdog prints when the ROS 2 teardown hangs: faulthandler's dump,
# "Timeout (H:MM:SS)!" first.
STUCK_IN_TEARDOWN = re.compile(r"^Timeout \(\d+:\d\d:\d\d\)!", re.MULTILINE)


def ros_env():
    """A domain of this test's own, discovery on this machine."""
    env = dict(os.environ)
    env["ROS_DOMAIN_ID"] = str(next(_domains))
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    return env


def write_team(tmp_path, robots, tasks, extra=""):
    path = tmp_path / "team.toml"
    path.write_text(
        f'run = "ros2-{os.getpid()}-{next(_runs)}"\nrobots = {robots}\n'
        f'tasks = {tasks}\ncosts = "private"\ntopology = "ring"\n'
        f'round_timeout = 30.0\nepisode_timeout = 60.0\n{extra}')
    return path


class Team:
    """The members and the robot nodes of a team, each a process."""

    def __init__(self, tmp_path, robots, tasks, episodes, robot_args=None, extra="",
                 nodes_first=False):
        self.tmp_path, self.robots, self.episodes = tmp_path, robots, episodes
        self.robot_args = robot_args or {}
        self.team = write_team(tmp_path, robots, tasks, extra)
        self.env = ros_env()
        self.members, self.nodes = [], []
        if nodes_first:
            self.start_nodes()
            try:
                self.wait_for_nodes()
            except BaseException:
                self.kill()
                raise
        # The members in one process group, as a terminal's foreground job.
        for i in range(robots):
            group = self.members[0].pid if self.members else 0
            self.members.append(subprocess.Popen(
                [ADMM_TA, "agent", "--team", str(self.team), "--robot", str(i), "--ros2"],
                env=self.env, stderr=subprocess.PIPE, text=True, process_group=group))
        if not nodes_first:
            self.start_nodes()

    def start_nodes(self):
        self.nodes = [self.start_node(i) for i in range(self.robots)]

    def start_node(self, i):
        # -X faulthandler: a crash inside the DDS says where on the node's stderr.
        return subprocess.Popen(
            [sys.executable, "-X", "faulthandler", ROBOT_NODE, "--team", str(self.team),
             "--robot", str(i), "--episodes", str(self.episodes), "--range", "1.5",
             "--timeout", "90", "--log", str(self.log(i)), *self.robot_args.get(i, [])],
            env=self.env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)

    def wait_for_nodes(self):
        """Until another ROS 2 node of the domain sees every robot's node. A node that
        crashes (SIGSEGV, SIGBUS, SIGABRT) before any member is up is started again, once:
        Fast DDS 3.2 (the wheels' DDS) crashed in its TypeLookup thread now and then while
        eight nodes discovered each other (a general protection fault in `dds.tls.replies`,
        no member involved). The tests that start the members first have no such retry."""
        crashes = {}
        while True:
            crashed = self.watch_nodes()
            if not crashed:
                return
            twice = [i for i in crashed if i in crashes]
            for i in crashed:
                crashes[i] = (f"robot node {i} crashed (exit {self.nodes[i].returncode}):\n"
                              f"{self.nodes[i].stderr.read()}")
            # Shown with the test's output if it fails.
            print("\n".join(crashes.values()))
            assert not twice, f"robot nodes {twice} crashed twice:\n" + "\n".join(
                crashes.values())
            for i in crashed:
                self.nodes[i] = self.start_node(i)

    def watch_nodes(self):
        """Waits for every robot's node on the graph; the nodes that crashed meanwhile, if any."""
        wanted = [(f"/robot{i}", "robot") for i in range(self.robots)]
        waiting = subprocess.Popen([sys.executable, "-c", WAIT_FOR_NODES, json.dumps(wanted)],
                                   env=self.env, stderr=subprocess.PIPE, text=True)
        deadline = time.monotonic() + 60
        while waiting.poll() is None:
            dead = [i for i, p in enumerate(self.nodes) if p.poll() is not None]
            if dead or time.monotonic() > deadline:
                waiting.kill()
                waiting.wait()
                if dead and all(-self.nodes[i].returncode in CRASHES for i in dead):
                    return dead
                why = "".join(f"robot node {i} exited with {self.nodes[i].returncode}: "
                              f"{self.nodes[i].stderr.read()}\n" for i in dead)
                raise AssertionError(
                    f"the robots' nodes did not come up: {why or 'not all seen in 60 s'}")
            time.sleep(0.05)
        assert waiting.returncode == 0, waiting.stderr.read()
        return []

    def log(self, i):
        return self.tmp_path / f"robot-{i}.jsonl"

    def entries(self, i):
        if not self.log(i).exists():
            return []
        return [json.loads(line) for line in self.log(i).read_text().splitlines()]

    def wait(self, timeout=300):
        codes = [p.wait(timeout=timeout) for p in self.nodes + self.members]
        errors = [p.stderr.read() for p in self.nodes + self.members]
        # A robot node whose ROS 2 teardown hung after its work (Fast DDS 3.2, see
        # robot_node.py) did what the tests ask of it: its log says what it got.
        for i, error in enumerate(errors[:len(self.nodes)]):
            if codes[i] == 1 and STUCK_IN_TEARDOWN.search(error) and self.answered_all(i):
                print(f"robot node {i}: its ROS 2 teardown hung (taken as done):\n{error}")
                codes[i] = 0
        return codes, errors

    def answered_all(self, i):
        """Whether robot i's log has an answer of every episode it was started for."""
        episodes = {e["answer"].get("episode") for e in self.entries(i) if "answer" in e
                    and "error" not in e["answer"]}
        return episodes == set(range(self.episodes))

    def kill(self):
        for p in self.members + self.nodes:
            if p.poll() is None:
                p.kill()
                p.wait()


@pytest.fixture
def teams():
    started = []
    yield lambda *a, **k: started.append(Team(*a, **k)) or started[-1]
    for team in started:
        team.kill()


def test_eight_rclpy_robots_drive_a_ring_team_for_twenty_episodes(tmp_path, teams):
    shm_before = team_shm()
    robots, tasks, episodes = 8, 6, 20
    team = teams(tmp_path, robots, tasks, episodes, robot_args={5: ["--bad-row-at", "3"]})
    codes, errors = team.wait()
    assert codes == [0] * (2 * robots), "\n".join(errors)
    rows, answers, row_errors = {}, {}, []
    for i in range(robots):
        for entry in team.entries(i):
            if "row" in entry:
                rows.setdefault(entry["row"]["episode"], {})[i] = entry["row"]["costs"]
            elif "error" in entry["answer"]:
                row_errors.append((i, entry["answer"]))
            else:
                answers.setdefault(entry["answer"]["episode"], {})[i] = entry["answer"]
    assert sorted(answers) == list(range(episodes))
    for episode in range(episodes):
        stacked = [rows[episode][i] for i in range(robots)]
        try:
            best = optimum(stacked)
        except ValueError:  # scipy: no feasible assignment (tasks out of battery range)
            best = float("inf")
        got = answers[episode]
        assert sorted(got) == list(range(robots))
        views = {json.dumps(a["assignment"]) for a in got.values()}
        assert len(views) == 1, f"episode {episode}: the robots disagree"
        if best == float("inf"):
            assert not any(a["feasible"] for a in got.values())
            continue
        for i, a in got.items():
            assert a["certified"] and a["feasible"], (episode, i, a)
            assert a["total_cost"] == pytest.approx(best, rel=1e-9, abs=1e-9), episode
            own = a["task"]
            assert a["cost"] == (None if own is None else pytest.approx(stacked[i][own]))
    # The bad row: its error on robot 5's answers' topic, and nothing changed.
    assert len(row_errors) == 1, row_errors
    robot, error = row_errors[0]
    assert robot == 5 and error["episode"] == 3 and "costs for 6 tasks" in error["error"]
    assert team_shm() <= shm_before


def test_members_launched_together_join_robots_already_up(tmp_path, teams):
    # The robots' nodes (Fast DDS) are up first, then the eight members start at once: each
    # member's topics must be matched by its robot's node (members starting within a few
    # milliseconds of each other used to be missed by Fast DDS now and then).
    robots, episodes = 8, 3
    team = teams(tmp_path, robots, robots, episodes, nodes_first=True)
    codes, errors = team.wait(timeout=120)
    assert codes == [0] * (2 * robots), "\n".join(errors)
    for i in range(robots):
        answered = [e["answer"] for e in team.entries(i) if "answer" in e]
        assert [a["episode"] for a in answered] == list(range(episodes)), i
        assert all(a["certified"] for a in answered), answered


def test_robots_leave_crash_and_join_through_ros_2(tmp_path):
    # A ring of 6 members fed by one rclpy node: robot 2 leaves ({"leave": true} on its rows'
    # topic), robot 3's member is killed, a new member takes slot 2 again; every solved
    # episode is certified and scipy's optimum of the rows of the robots that took part.
    shm_before = team_shm()
    slots, tasks, episodes = 6, 3, 20
    plan = {5: ["leave", 2], 10: ["crash", 3], 14: ["join", 2]}
    team = write_team(tmp_path, slots, tasks, "startup_timeout = 30.0\n")
    done = subprocess.run(
        [sys.executable, ELASTIC_DRIVER, ADMM_TA, str(team), str(slots), str(tasks),
         str(episodes), json.dumps(plan), str(tmp_path)],
        env=ros_env(), capture_output=True, text=True, timeout=600)
    logs = "".join(p.read_text() for p in tmp_path.glob("member-*.log"))
    assert done.returncode == 0, done.stderr + logs[-3000:]
    lines = [json.loads(line) for line in done.stdout.splitlines()]
    assert [e["episode"] for e in lines] == list(range(episodes))
    solved = 0
    for entry in lines:
        rows = {int(i): r for i, r in entry["rows"].items()}
        answers = {int(i): a for i, a in entry["answers"].items()}
        first = next(iter(answers.values()))
        for i, a in answers.items():
            assert a["episode"] == first["episode"] and a["assignment"] == first["assignment"]
        if first.get("unsolved"):
            assert first.get("crashed"), entry  # only a crash may cost an episode
            continue
        solved += 1
        best = stacked_optimum([rows[i] for i in sorted(rows)])
        for i, a in answers.items():
            assert a["certified"] and a["task"] == a["assignment"][i], (entry["episode"], i, a)
            assert a["total_cost"] == pytest.approx(best, rel=1e-9, abs=1e-9), entry
        taking = sorted(i for i, t in enumerate(first["assignment"]) if t is not None)
        assert taking == sorted(rows), entry
    assert solved >= episodes - 1
    # Robot 2 came back: the last episodes have it, and not robot 3.
    assert sorted(int(i) for i in lines[-1]["rows"]) == [0, 1, 2, 4, 5]
    assert team_shm() <= shm_before


def test_a_late_subscriber_and_ctrl_c_of_an_eight_robot_team(tmp_path, teams):
    shm_before = team_shm()
    robots = 8
    team = teams(tmp_path, robots, 6, 10_000)
    deadline = time.monotonic() + 120
    while not all(sum("answer" in e for e in team.entries(i)) >= 3 for i in range(robots)):
        assert time.monotonic() < deadline, "no answers"
        assert all(p.poll() is None for p in team.members), [p.poll() for p in team.members]
        time.sleep(0.1)
    logged = max(e["answer"]["episode"] for e in team.entries(2)
                 if "episode" in e.get("answer", {}))
    latest = subprocess.run(
        [sys.executable, "-c", LATE_SUBSCRIBER], env=team.env, capture_output=True, text=True,
        timeout=60)
    assert latest.returncode == 0, latest.stderr
    late = json.loads(latest.stdout)
    # The answer of the episode robot 2 had when the subscriber came, or a later one.
    assert late["robot"] == 2 and late["episode"] >= logged and "assignment" in late, late
    os.killpg(team.members[0].pid, signal.SIGINT)  # Ctrl-C
    codes = [p.wait(timeout=30) for p in team.members]
    # The signal's exit code (130): none of them left.
    assert codes == [130] * robots, codes
    for p in team.nodes:
        p.send_signal(signal.SIGINT)
        p.wait(timeout=30)
    assert not any(alive(p.pid) for p in team.members + team.nodes)
    assert team_shm() <= shm_before
    # Each robot program heard why its team stopped.
    for i in range(robots):
        failed = [e["answer"] for e in team.entries(i) if e.get("answer", {}).get("failed")]
        assert failed and "SIGINT" in failed[-1]["error"], (i, team.entries(i)[-2:])


LATE_SUBSCRIBER = """
import json, sys, time, rclpy
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import String
rclpy.init()
node = rclpy.create_node("late")
got = []
qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                 durability=DurabilityPolicy.TRANSIENT_LOCAL)
node.create_subscription(String, "/robot2/admm_ta/assignment", lambda m: got.append(m.data), qos)
end = time.monotonic() + 30
while not got and time.monotonic() < end:
    rclpy.spin_once(node, timeout_sec=0.1)
# RustDDS may hand a late subscriber a few older answers first (docs/ros2.md): the latest is
# the one with the greatest episode among those that come at once.
end = time.monotonic() + 0.5
while got and time.monotonic() < end:
    rclpy.spin_once(node, timeout_sec=0.05)
answers = [json.loads(text) for text in got]
print(json.dumps(max(answers, key=lambda a: a.get("episode", -1))) if got else "null")
sys.exit(0 if got else 1)
"""


@pytest.mark.parametrize("args, env, said", [
    (["--ros2-namespace", "3robots"], {}, "ROS 2 namespace"),
    (["--ros2-namespace", "a//b"], {}, "ROS 2 namespace"),
    ([], {"ROS_DOMAIN_ID": "999"}, "domain id"),
    ([], {"ROS_AUTOMATIC_DISCOVERY_RANGE": "EVERYWHERE"}, "ROS_AUTOMATIC_DISCOVERY_RANGE"),
])
def test_a_member_refuses_what_ros_2_cannot_take(tmp_path, args, env, said):
    team = write_team(tmp_path, 2, 2)
    run = subprocess.run([ADMM_TA, "agent", "--team", str(team), "--robot", "0", "--ros2",
                          *args], env={**ros_env(), **env}, capture_output=True, text=True,
                         timeout=30)
    assert run.returncode == 2, run.stderr
    assert said in run.stderr and run.stderr.count("\n") == 1, run.stderr
