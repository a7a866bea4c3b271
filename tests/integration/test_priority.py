"""Which threads give way on a busy host (core/priority.py): every front end runs below the
process's priority, the stop's path at it. Real parts: mosquitto, the bridge (App, in this
process) with a rotctld port, a PstRotator UDP port, WSJT-X and the console, the stop express
(its own process) and a Rotor-EZ emulator. A thread's nice value is the kernel's, read from
/proc (a thread inherits its starter's and an unprivileged process can never raise it back, so
a stop-path thread started by a lowered one would stay lowered: rule 2 there)."""

from __future__ import annotations

import os
import socket
import threading
from pathlib import Path

import pytest

from bridge.app import App
from bridge.core import priority
from bridge.core.priority import FRONT_NICE, MAX_NICE
from tests.support.console import web_section
from tests.support.mosquitto import Mosquitto, free_port
from tests.support.rig import Rig
from tests.support.udp_logger import free_udp_port, reserve_pst_ports
from tests.support.waiting import slow, wait_until

pytestmark = pytest.mark.skipif(
    not Path("/proc/self/task").is_dir(), reason="a thread's nice value is read from /proc"
)


def nice(tid: int, pid: str = "self") -> int:
    """Field 19 of /proc/<pid>/task/<tid>/stat (after the name in parentheses: field 3 on)."""
    stat = Path(f"/proc/{pid}/task/{tid}/stat").read_text()
    return int(stat[stat.rindex(")") + 2 :].split()[16])


def process_nices(pid: int) -> set[int]:
    """Every thread of another process."""
    return {nice(int(tid), str(pid)) for tid in os.listdir(f"/proc/{pid}/task")}


def tid_of(thread: threading.Thread | None) -> int:
    assert thread is not None and thread.native_id is not None
    return thread.native_id


def named(prefix: str) -> list[threading.Thread]:
    return [t for t in threading.enumerate() if t.name.startswith(prefix) and t.is_alive()]


@pytest.fixture(autouse=True)
def _express_on(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(Rig, "express", True)
    monkeypatch.setattr(priority, "_enabled", False)  # as a new process has it (rule 4)


def _front_ends(rig: Rig) -> tuple[int, socket.socket]:
    """The rig's one rotator with a rotctld port and a PstRotator port; WSJT-X and the console
    on. Returns the rotctld port and the PST replies' socket (closed by the caller)."""
    rotctld = free_port()
    pst, replies = reserve_pst_ports()
    rig.sections = {
        "web": web_section(),
        "wsjtx": {"enabled": True, "port": free_udp_port(), "bind": "127.0.0.1"},
        "audit_file": str(rig.tmp / "audit.log"),
    }
    rig.add("tower", rotctld_port=rotctld, pst_udp_port=pst)
    return rotctld, replies


def _express_up(app: App, starts: int = 1) -> None:
    wait_until(lambda: app.express.starts == starts, 10, "the express started")
    wait_until(app.express.up.is_set, 10, "the express is up")
    wait_until(lambda: "tower" in app.express.held, 10, "the express holds the port")


def _check(app: App, rotctld: int) -> None:
    """Front ends lowered, the stop's path not: the main connection once the lane and the
    express were started, a rotctld client's thread as its listener's."""
    base = nice(threading.get_native_id())  # the test's thread started the app
    front = min(MAX_NICE, base + FRONT_NICE)
    main = tid_of(app.client._client.network_thread)
    wait_until(lambda: nice(main) == front, 10, "the main connection's thread lowered")
    with socket.create_connection(("127.0.0.1", rotctld), timeout=slow(10)) as c:
        c.sendall(b"p\n")
        assert c.recv(64)  # its thread serves it: answered
        lowered = {
            "rotctld listener and client": named("rotctld-tower"),
            "loggers": named("loggers"),
            "wsjtx": named("wsjtx"),
            "web": named("web"),
            "audit": named("audit"),
        }
        for what, threads in lowered.items():
            assert threads, what
            assert {nice(tid_of(t)) for t in threads} == {front}, what
        assert len(lowered["rotctld listener and client"]) >= 2  # the client's thread too
    lane = app.lane._client.network_thread
    assert lane is not None
    stops_path = {
        "serial-lines": named("serial-lines"),
        "stop lane": [lane],
        "stop express's reader": named("stop express"),
    }
    for what, threads in stops_path.items():
        assert threads, what
        assert {nice(tid_of(t)) for t in threads} == {base}, what
    child = app.express._child
    assert child is not None
    assert process_nices(child.pid) == {raised(base)}, "the stop express's process"


def test_front_ends_give_way_and_the_stops_path_keeps_the_process_priority(
    rig: Rig, broker: Mosquitto
) -> None:
    """Then a reconnect (the broker restarted) and an express restarted after a kill: the lane
    and the new express still at the process's priority."""
    rotctld, replies = _front_ends(rig)
    with replies:
        app = rig.start()
        rig.ready("tower")
        _express_up(app)
        _check(app, rotctld)
        lane = app.lane._client.network_thread
        broker.restart()
        wait_until(app.client.connected.is_set, slow(20), "the main connection back")
        wait_until(app.lane.connected.is_set, slow(20), "the stop lane back")
        assert app.lane._client.network_thread is lane  # reconnected on its own thread
        child = app.express._child
        assert child is not None
        child.kill()
        _express_up(app, starts=2)
        _check(app, rotctld)


def test_a_bridge_that_starts_before_its_broker_starts_its_stops_path_unlowered(
    rig: Rig, broker: Mosquitto
) -> None:
    """The first connection comes on a reconnect of the main connection's thread, which then
    starts the lane and the express (app.py): they keep the process's priority."""
    rotctld, replies = _front_ends(rig)
    with replies:
        broker.stop()
        app = rig.start()
        wait_until(lambda: named("serial-lines"), 10, "the lines thread runs")
        broker.start()
        rig.ready("tower", slow(30))
        _express_up(app)
        _check(app, rotctld)


def test_only_a_process_that_enabled_it_lowers_its_front_ends(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """core/priority.py rule 4: the remote runs the same rotctld server and console, where they
    carry the operator's stop; only the service (app.py) lowers them."""

    def nice_on_a_thread() -> int:
        seen: list[int] = []
        thread = threading.Thread(target=priority.lowered(lambda: seen.append(own_nice())))
        thread.start()
        thread.join()
        return seen[0]

    base = own_nice()
    monkeypatch.setattr(priority, "_enabled", False)
    assert nice_on_a_thread() == base
    priority.enable()
    assert nice_on_a_thread() == min(MAX_NICE, base + FRONT_NICE)


def own_nice() -> int:
    return nice(threading.get_native_id())


def test_a_bridge_whose_stops_the_express_does_not_all_carry_lowers_nothing(rig: Rig) -> None:
    """core/priority.py rule 4: a SPID's stop is carried inside the bridge (the stop lane, the
    serial-lines thread), under the interpreter lock a lowered front end may hold while the
    kernel runs another program: with such a rotator nothing is lowered."""
    rotctld = free_port()
    rig.add("tower", rotctld_port=rotctld)
    rig.add("dish", model="rot2prog")
    app = rig.start()
    rig.ready("tower")
    rig.ready("dish")
    base = own_nice()
    with socket.create_connection(("127.0.0.1", rotctld), timeout=slow(10)) as c:
        c.sendall(b"p\n")
        assert c.recv(64)
        threads = [app.client._client.network_thread, *named("rotctld-tower")]
        assert len(threads) >= 3  # the main connection, the listener, the client's thread
        assert {nice(tid_of(t)) for t in threads} == {base}


def raised(base: int) -> int:
    """core/priority.py rule 5: the nice value a process started at ``base`` can raise itself to
    on this system (EXPRESS_RAISE above, as root or with CAP_SYS_NICE; ``base`` without)."""
    seen: list[int] = []

    def attempt() -> None:  # on a thread of its own: the test's threads keep their priority
        try:
            os.setpriority(os.PRIO_PROCESS, threading.get_native_id(), max(-20, base - 10))
        except OSError:
            pass
        seen.append(own_nice())

    thread = threading.Thread(target=attempt)
    thread.start()
    thread.join()
    return seen[0]
