"""Ctrl-C during a long solve: KeyboardInterrupt promptly, no agent process and no shared
memory left behind, the interpreter usable afterwards."""

import os
import signal
import subprocess
import sys
import time

import pytest

SCRIPT = """
import sys, time, admm_ta, numpy
transport = sys.argv[1]
cost = numpy.random.default_rng(0).random((8, 8))
print("started", flush=True)
began = time.monotonic()
try:
    admm_ta.solve(cost, transport=transport, stop="max-iters", max_iters=10**9,
                  **({} if transport == "sim" else {"round_timeout": 30}))
    print("finished")
except KeyboardInterrupt:
    print("KeyboardInterrupt", round(time.monotonic() - began, 3), flush=True)
    # The interpreter and the package still work.
    r = admm_ta.solve(cost, transport=transport, check=True)
    print("again", r.certified, r.optimal, flush=True)
"""


def children(pid):
    """The processes whose parent is `pid`."""
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            found.append(int(entry))
    return found


def alive(pid):
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def team_shm():
    return {name for name in os.listdir("/dev/shm") if name.startswith("adta") or "iox2" in name}


@pytest.mark.parametrize("transport", ["sim", "threads", "ipc", "shm"])
def test_ctrl_c_stops_a_long_solve_and_leaves_nothing(transport):
    shm_before = team_shm()
    proc = subprocess.Popen([sys.executable, "-c", SCRIPT, transport], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "started"
        time.sleep(1.5)
        agents = children(proc.pid)
        if transport in ("ipc", "shm"):
            assert len(agents) == 8, agents
        sent = time.monotonic()
        proc.send_signal(signal.SIGINT)
        line = proc.stdout.readline().split()
        stopped_after = time.monotonic() - sent
        assert line and line[0] == "KeyboardInterrupt", (line, proc.stderr.read())
        assert stopped_after < 5, stopped_after
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, err
    assert out.split() == ["again", "True", "True"], (out, err)
    assert not [pid for pid in agents if alive(pid)]
    assert team_shm() - shm_before == set()


@pytest.mark.parametrize("transport", ["sim", "ipc"])
def test_python_s_own_handlers_are_back_after_a_solve(transport):
    import admm_ta

    calls = []
    previous = signal.signal(signal.SIGUSR1, lambda *_: calls.append(1))
    try:
        admm_ta.solve([[1, 2], [2, 1]], transport=transport)
        os.kill(os.getpid(), signal.SIGUSR1)
        time.sleep(0.05)
        assert calls == [1]
        with pytest.raises(KeyboardInterrupt):
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(1)
    finally:
        signal.signal(signal.SIGUSR1, previous)


LONG = dict(stop="max-iters", max_iters=10**9)


def test_a_python_signal_handler_that_raises_stops_the_team():
    """`signal.alarm` with a handler that raises: the timeout pattern."""
    import admm_ta

    def timeout(*_):
        raise TimeoutError("too long")

    previous = signal.signal(signal.SIGALRM, timeout)
    try:
        for transport in ["sim", "threads", "ipc"]:
            signal.setitimer(signal.ITIMER_REAL, 0.5)
            began = time.monotonic()
            with pytest.raises(TimeoutError, match="too long"):
                admm_ta.solve([[1, 2], [2, 1]], transport=transport, **LONG)
            assert time.monotonic() - began < 5
            assert admm_ta.solve([[1, 2], [2, 1]], transport=transport).certified
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def test_interrupt_main_stops_the_team():
    import _thread
    import threading

    import admm_ta

    timer = threading.Timer(0.5, _thread.interrupt_main)
    timer.start()
    began = time.monotonic()
    try:
        with pytest.raises(KeyboardInterrupt):
            admm_ta.solve([[1, 2], [2, 1]], transport="threads", **LONG)
    finally:
        timer.cancel()
    assert time.monotonic() - began < 5
