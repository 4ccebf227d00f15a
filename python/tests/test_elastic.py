"""Standing teams whose robots come and go: 100 episodes of a ring of sidecars (robot
programs driving ``admm-ta agent --serve`` through pipes, as any robot program would), with
a random leave, join or crash (SIGKILL) every 10 episodes; every solved episode certified
and equal to scipy's optimum of the stacked rows of the robots that took part, no hang,
nothing left in shared memory. Python's ``TeamMember`` leaves, is refused, and joins
again."""

import json
import os
import queue
import random
import subprocess
import sys
import threading

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment as scipy_lsap

import admm_ta

AGENT = "import sys; from admm_ta._core import main; sys.exit(main(['admm-ta', *sys.argv[1:]]))"

#: How long any line may take (a test never hangs).
LINE_WITHIN = 60


def optimum(rows):
    """The optimum of the stacked rows (every robot one task, every task a robot)."""
    cost = np.array(rows, dtype=float)
    n, m = cost.shape
    square = np.hstack([cost, np.repeat(cost.min(axis=1)[:, None], n - m, axis=1)])
    r, c = scipy_lsap(square)
    return float(square[r, c].sum())


class Sidecar:
    """One robot's sidecar, as its program sees it."""

    def __init__(self, team, robot, env=None):
        self.robot = robot
        self.process = subprocess.Popen(
            [sys.executable, "-c", AGENT, "agent", "--team", str(team), "--robot", str(robot), "--serve"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env={**os.environ, **(env or {})},
        )
        self.lines = queue.Queue()
        self.stderr = []
        threading.Thread(target=self._read, args=(self.process.stdout, self.lines), daemon=True).start()
        threading.Thread(target=self._err, daemon=True).start()

    @staticmethod
    def _read(stream, lines):
        for line in stream:
            lines.put(line)
        lines.put(None)

    def _err(self):
        for line in self.process.stderr:
            self.stderr.append(line)

    def send(self, row):
        self.process.stdin.write(json.dumps({"costs": row}) + "\n")
        self.process.stdin.flush()

    def next(self):
        try:
            line = self.lines.get(timeout=LINE_WITHIN)
        except queue.Empty:
            self.process.kill()
            pytest.fail(f"robot {self.robot}: no line within {LINE_WITHIN} s: {''.join(self.stderr)}")
        assert line is not None, f"robot {self.robot} ended: {''.join(self.stderr)}"
        return json.loads(line)

    def await_stderr(self, text):
        for _ in range(LINE_WITHIN * 100):
            if any(text in line for line in self.stderr):
                return
            threading.Event().wait(0.01)
        pytest.fail(f"robot {self.robot}: no {text!r} on stderr: {''.join(self.stderr)}")

    def close(self):
        self.process.stdin.close()

    def finish(self):
        if not self.process.stdin.closed:
            self.process.stdin.close()
        return self.process.wait(timeout=LINE_WITHIN)


def connected(ring, robots):
    """Whether `robots` are connected in a ring of `ring` slots."""
    robots = set(robots)
    if not robots:
        return True
    start = min(robots)
    seen, todo = {start}, [start]
    while todo:
        r = todo.pop()
        for s in ((r + 1) % ring, (r - 1) % ring):
            if s in robots and s not in seen:
                seen.add(s)
                todo.append(s)
    return seen == robots


def shm_left(run):
    """What the team `run` left in /dev/shm: its own files and its rosters' (their prefix is
    a hash of the team's, as the library writes it)."""
    prefix = f"adtat{os.geteuid()}-{run}_"
    h = 0xCBF29CE484222325
    for b in prefix.encode():
        h = ((h ^ b) * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    parts = "adtap%08x" % ((h ^ (h >> 32)) & 0xFFFFFFFF)
    try:
        names = os.listdir("/dev/shm")
    except FileNotFoundError:
        return []
    return [n for n in names if run in n or n.startswith(parts)]


@pytest.mark.parametrize("seed", [1, 2])
def test_a_hundred_episodes_with_robots_coming_and_going(tmp_path, seed):
    slots, tasks, episodes = 8, 4, 100
    run = f"pyelastic{seed}-{os.getpid()}"
    team = tmp_path / "team.toml"
    team.write_text(
        f'run = "{run}"\nrobots = {slots}\ntasks = {tasks}\ncosts = "private"\n'
        f'topology = "ring"\nstartup_timeout = 30.0\nround_timeout = 20.0\n'
        f"episode_timeout = 30.0\n"
    )
    rng = random.Random(seed)
    members = {i: Sidecar(team, i) for i in range(slots)}
    joining = None  # (sidecar, its first row)
    events = []
    solved = 0
    # Ten changes in a random order: as many robots come as go.
    kinds = rng.sample(["leave", "leave", "crash", "crash", "crash"] + ["join"] * 5, 10)
    for episode in range(episodes):
        if episode % 10 == 5:
            kind = kinds[episode // 10]
            free = [s for s in range(slots) if s not in members and joining is None]
            can_go = [r for r in members if connected(slots, set(members) - {r}) and len(members) > tasks]
            if kind == "join" and free:
                slot = rng.choice([s for s in free if (s + 1) % slots in members or (s - 1) % slots in members] or free)
                joiner = Sidecar(team, slot, {"RUST_LOG": "admm_ta_runtime=info"})
                joiner.await_stderr("asking to join the running team")
                first = [round(rng.random() * 10, 3) for _ in range(tasks)]
                joiner.send(first)
                joining = (joiner, first)
                events.append((episode, "join", slot))
            elif kind in ("leave", "crash") and can_go:
                robot = rng.choice(can_go)
                gone = members.pop(robot)
                if kind == "leave":
                    gone.close()
                    leaving = gone
                else:
                    gone.process.kill()
                    gone.process.wait()
                    leaving = None
                events.append((episode, kind, robot))
            else:
                leaving = None
        else:
            leaving = None
        rows = {i: [round(rng.random() * 10, 3) for _ in range(tasks)] for i in members}
        for i, s in members.items():
            s.send(rows[i])
        answers = {i: s.next() for i, s in members.items()}
        first = next(iter(answers.values()))
        if joining is not None and joining[0].robot in first.get("joined", []):
            joiner, row = joining
            answers[joiner.robot] = joiner.next()
            rows[joiner.robot] = row
            members[joiner.robot] = joiner
            joining = None
        if leaving is not None:
            assert leaving.finish() == 0, "".join(leaving.stderr)
        for i, a in answers.items():
            assert a["episode"] == first["episode"], (i, a, first)
            assert a["assignment"] == first["assignment"], (i, a, first)
        if first.get("unsolved"):
            # Only a crash may cost an episode (after another robot had answered it).
            assert first.get("crashed"), first
            continue
        solved += 1
        best = optimum([rows[i] for i in sorted(rows)])
        for i, a in answers.items():
            assert a["certified"], (episode, i, a)
            assert a["task"] == a["assignment"][i], (i, a)
            assert abs(a["total_cost"] - best) <= 1e-9 * max(1.0, abs(best)), (episode, a, best, events)
        taking = [i for i, t in enumerate(first["assignment"]) if t is not None]
        assert sorted(taking) == sorted(rows), (episode, first, sorted(rows))
    assert solved >= episodes - len(events), (solved, events)
    assert {kind for _, kind, _ in events} == {"leave", "crash", "join"}, events
    assert len(events) >= 6, events
    # Every program ends at once: they all leave in one episode.
    for s in members.values():
        s.close()
    for s in members.values():
        assert s.finish() == 0, "".join(s.stderr)
    if joining is not None:
        joining[0].process.kill()
        joining[0].process.wait()
    assert shm_left(run) == [], shm_left(run)


def test_python_members_leave_are_refused_and_join_again(tmp_path):
    """Three members on a chain 0-1-2: the middle one's leave is refused (``LeaveRefused``)
    and it stays; an end leaves; a new member takes its slot."""
    run = f"pyleave-{os.getpid()}"
    team = tmp_path / "team.toml"
    team.write_text(
        f'run = "{run}"\nrobots = 3\ntasks = 2\ncosts = "private"\ntopology = "chain"\n'
        f"round_timeout = 20.0\nepisode_timeout = 30.0\n"
    )
    results = {}
    errors = []

    def robot(i):
        try:
            member = admm_ta.TeamMember(team, i)
            out = [member.assign([1.0 + i, 2.0])]
            if i == 1:
                with pytest.raises(admm_ta.LeaveRefused, match="cannot leave"):
                    member.leave()
                out.append(member.roster)
                out.append(member.assign([1.0, 1.5]))
            elif i == 2:
                out.append(member.assign([3.0, 0.5]))
                member.leave()
                out.append(member.episode)
                with pytest.raises(ValueError, match="left the team"):
                    member.assign([1.0, 1.0])
                results[i] = out
                return
            else:
                out.append(member.assign([2.0, 2.0]))
                out.append(member.assign([2.0, 2.0]))
            results[i] = out
            member.leave()
        except Exception as error:  # reported below
            errors.append((i, error))

    threads = [threading.Thread(target=robot, args=(i,)) for i in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=120)
    assert not any(t.is_alive() for t in threads), "a member hung"
    assert not errors, errors
    # Episode 1: robot 1 asked to leave (relayed, refused); robots 0 and 2 solved.
    assert results[1][1] == [0, 1, 2]
    assert results[0][1]["leave_refused"] == [1]
    assert results[0][1]["assignment"][1] is None
    # Episode 2: robot 2 left.
    assert results[0][2]["left"] == [2]
    assert results[1][2]["left"] == [2]
    assert results[2][2] == 3
    assert shm_left(run) == []
