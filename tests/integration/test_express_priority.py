"""The stop express runs ahead of busy programs (interfaces/mqtt/express.py rule 10): its process
EXPRESS_RAISE nice steps above the bridge where the system lets it, every thread of it, also
after it was started again; the bridge's own threads keep the bridge's priority. Real parts:
mosquitto, the bridge (App, in this process), the express (its own process), a Rotor-EZ
emulator. A thread's nice value is the kernel's, read from /proc."""

from __future__ import annotations

import os
import signal
import threading
from pathlib import Path

import pytest

from bridge.app import App
from bridge.interfaces.mqtt.express import EXPRESS_RAISE
from tests.support.rig import Rig
from tests.support.waiting import wait_until

pytestmark = pytest.mark.skipif(
    not Path("/proc/self/task").is_dir(), reason="a thread's nice value is read from /proc"
)


def nice(tid: int | str, pid: int | str = "self") -> int:
    """Field 19 of /proc/<pid>/task/<tid>/stat (after the name in parentheses: field 3 on)."""
    stat = Path(f"/proc/{pid}/task/{tid}/stat").read_text()
    return int(stat[stat.rindex(")") + 2 :].split()[16])


def nices(pid: int | str) -> set[int]:
    """Every thread of a process."""
    return {nice(tid, pid) for tid in os.listdir(f"/proc/{pid}/task")}


def raised(base: int) -> int:
    """What a process started at ``base`` can raise itself to on this system: EXPRESS_RAISE
    above it as root or with CAP_SYS_NICE (or a nice limit allowing it), ``base`` without."""
    seen: list[int] = []

    def attempt() -> None:  # on a thread of its own: the test's keep their priority
        try:
            os.setpriority(os.PRIO_PROCESS, 0, max(-20, base - EXPRESS_RAISE))
        except OSError:
            pass
        seen.append(nice(threading.get_native_id()))

    thread = threading.Thread(target=attempt)
    thread.start()
    thread.join()
    return seen[0]


def bridges(before: set[str]) -> set[int]:
    """The nice values of the threads started since ``before`` (the bridge's: serial-lines, the
    MQTT connections' and the express's reader among them)."""
    started = set(os.listdir("/proc/self/task")) - before
    assert len(started) >= 4
    return {nice(tid) for tid in started}


def express_up(app: App, starts: int) -> int:
    wait_until(lambda: app.express.starts == starts, 10, "the express started")
    wait_until(app.express.up.is_set, 10, "the express is up")
    child = app.express._child
    assert child is not None
    return child.pid


def test_the_express_runs_ahead_and_the_bridge_at_its_priority(
    rig: Rig, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(Rig, "express", True)
    rig.add("tower")
    base = nice(threading.get_native_id())  # the test's thread starts the bridge
    expected = raised(base)
    before = set(os.listdir("/proc/self/task"))  # (threads of earlier tests: theirs)
    app = rig.start()
    rig.ready("tower")
    first = express_up(app, 1)
    assert nices(first) == {expected}, "every thread of the express"
    assert bridges(before) == {base}, "the bridge's own threads"
    os.kill(first, signal.SIGKILL)  # started again by the bridge, raised again
    again = express_up(app, 2)
    assert again != first
    assert nices(again) == {expected}
    assert bridges(before) == {base}
