"""Review 61 of attack 13's fix: what the network thread's rounds (paho_client.py rule 11) tell
the echo (heartbeat.py rule 11) when a stalled broker held a target, in virtual time: the real
``Client._round`` with a scripted poller and clock, the real ``_Ears`` and ``Echo`` behind it,
the messages read played by a scripted ``loop_read`` that asks ``broker_late`` as the service
does (service.py rule 12) before a target is handled. No broker."""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import pytest
from paho.mqtt.enums import CallbackAPIVersion, MQTTErrorCode

from bridge.core.model import Target
from bridge.core.polling import POLLIN
from bridge.interfaces.mqtt.client import _Ears
from bridge.interfaces.mqtt.heartbeat import Echo, Stamp
from bridge.interfaces.mqtt.paho_client import Client, Waker
from bridge.interfaces.mqtt.service import MqttService
from bridge.interfaces.mqtt.topics import Topics
from tests.mqtt.test_broker_late import Link
from tests.mqtt.test_service import NOW_UNIX, RecordingPublisher, RecordingRotator
from tests.support.clock import FakeClock

SOCK_FD = 1000  # (never polled for real: the poller is scripted)
WAKER_FD = 1001  # another descriptor than the socket's: the round takes it for its waker
WOKEN = [(WAKER_FD, POLLIN)]  # another thread's publish woke the loop (paho_client rule 6)
READABLE = [(SOCK_FD, POLLIN)]
WAITED_OUT: list[tuple[int, int]] = []


class Sock:
    def fileno(self) -> int:
        return SOCK_FD


class Poller:
    """Each poll takes the scripted time on the fake clock and returns the scripted events."""

    def __init__(self, clock: FakeClock) -> None:
        self.clock = clock
        self.script: list[tuple[float, list[tuple[int, int]]]] = []

    def register(self, fd: Any, mask: int = 0) -> None:
        pass

    def unregister(self, fd: Any) -> None:
        pass

    def poll(self, timeout: float | None = None) -> list[tuple[int, int]]:
        if timeout == 0:  # the look after a wake-up (rule 11): the socket as the stall has it
            return []
        took_s, events = self.script.pop(0)
        assert took_s <= 1.001, "a poll waits 1 s at most (paho_client.py rule 2)"
        self.clock.t += took_s
        return events


class Thread:
    """The main connection's network thread: its rounds on a fake clock, the echo told what
    they saw; ``read`` is what the next read that finds bytes does."""

    def __init__(self) -> None:
        self.clock = FakeClock(0.0)
        self.echo = Echo()
        self.lock = threading.Lock()
        self.echo.connected()
        self.poller = Poller(self.clock)
        self.client = Client(callback_api_version=CallbackAPIVersion.VERSION2)
        self.client._waker = Waker()
        self.client.hearing = _Ears(self.echo, self.lock, self.clock)
        self.read: Callable[[], None] = lambda: None
        sock = Sock()
        self.sock = sock

        def loop_read(max_packets: int = 1) -> MQTTErrorCode:
            self.read()
            return MQTTErrorCode.MQTT_ERR_SUCCESS

        self.client.loop_read = loop_read  # type: ignore[method-assign]
        self.client.socket = lambda: sock  # type: ignore[method-assign,assignment,return-value]
        self.client.want_write = lambda: False  # type: ignore[method-assign]
        self.client.loop_misc = lambda: MQTTErrorCode.MQTT_ERR_SUCCESS  # type: ignore[method-assign]

    def round(self, took_s: float, events: list[tuple[int, int]]) -> None:
        self.poller.script.append((took_s, events))
        assert self.client._round(self.sock, self.poller)

    def send(self) -> bytes:
        """A beat, as ``_tick`` sends it after a round (named by its send time)."""
        payload = f"{self.clock():.4f}".encode()
        with self.lock:
            self.echo.sent(payload, self.clock())
        return payload

    def broker_late(self) -> float | None:
        with self.lock:
            return self.echo.late(self.clock())

    def close(self) -> None:
        self.client._waker.close()


def test_a_move_held_over_7_s_is_refused_though_publishes_woke_the_thread_in_the_stall() -> None:
    """docs/mqtt.md and heartbeat.py rule 11: "A move held up 7 s or more is always refused
    (3 s of quiet, a beat period and up to 2 s of the bridge's loop)". The 2 s are a beat up to
    a poll late and the poll under way when the broker runs on; but a poll woken by another
    thread proves quiet only up to its start (rule 11), so one woken late in its wait loses up
    to a second more. Here: a beat back at 0.001, the broker frozen right after it (the target
    published then, into its socket), the next beat due at 2 and sent at 2.9995 (the round
    before it ended at 1.9995), polls woken at 5.9985 and 6.998 by the bridge's own status
    publishes, the broker running on at 7.898: the quiet proven with the beat out is 2.999 s,
    no hold, and the target, held 7.9 s, is carried out."""
    t = Thread()
    try:
        b0 = t.send()

        def echo_of_b0() -> None:
            with t.lock:
                assert t.echo.back(b0, t.clock())

        t.read = echo_of_b0
        t.round(0.001, READABLE)  # b0 back; the broker freezes now, the target in its socket
        frozen = t.clock()
        t.read = lambda: pytest.fail("nothing comes from a frozen broker")
        t.round(0.9985, WOKEN)  # a status published at 0.9995 (another thread)
        t.round(1.0, WAITED_OUT)  # to 1.9995: the beat not due yet (2 s after b0)
        t.round(1.0, WAITED_OUT)  # to 2.9995: due, and sent after this round
        t.send()
        t.round(0.0, WOKEN)  # (the beat's own wake-up)
        t.round(1.0, WAITED_OUT)
        t.round(1.0, WAITED_OUT)  # to 4.9995: the next beat
        t.send()
        t.round(0.0, WOKEN)
        t.round(0.999, WOKEN)  # a status published at 5.9985
        t.round(0.9995, WOKEN)  # another at 6.998
        verdicts: list[float | None] = []
        t.read = lambda: verdicts.append(t.broker_late())  # the held target, handled
        t.round(0.9, READABLE)  # the broker runs on at 7.898
        held_s = t.clock() - frozen
    finally:
        t.close()
    assert held_s > 7.8
    assert verdicts[0] is not None, f"a target held {held_s:.1f} s was carried out"


def test_the_same_stall_without_wake_ups_is_refused() -> None:
    """The same timeline with every poll waited out (nothing else published meanwhile): the
    quiet proven reaches the poll under way, and the target is refused (the scripted rounds
    tell what the first test is about)."""
    t = Thread()
    try:
        b0 = t.send()

        def echo_of_b0() -> None:
            with t.lock:
                assert t.echo.back(b0, t.clock())

        t.read = echo_of_b0
        t.round(0.001, READABLE)
        t.read = lambda: pytest.fail("nothing comes from a frozen broker")
        t.round(0.9985, WOKEN)
        t.round(1.0, WAITED_OUT)
        t.round(1.0, WAITED_OUT)
        t.send()
        t.round(0.0, WOKEN)
        t.round(1.0, WAITED_OUT)
        t.round(1.0, WAITED_OUT)
        t.send()
        t.round(0.0, WOKEN)
        t.round(1.0, WAITED_OUT)  # to 5.9995
        t.round(0.9985, WAITED_OUT)  # (a poll returns at its timeout: scripted a hair short)
        verdicts: list[float | None] = []
        t.read = lambda: verdicts.append(t.broker_late())
        t.round(0.9, READABLE)
    finally:
        t.close()
    assert verdicts[0] is not None


def test_a_newer_unstamped_target_is_not_refused_while_an_older_stamped_one_held_with_it_goes() -> (
    None
):
    """The broker frozen 10 s; 1 s into the stall a remote operator (``command_expiry_s`` 15:
    a slow link) sends P 200, stamped; a second later Home Assistant sends target 100, no
    stamp. The broker passes both on when it runs on, in that order. The stamped one is 9 s old
    by its stamp, within its expiry: carried out (service.py rule 9); the unstamped one, newer,
    is refused as held up (rule 12). The last word (docs/architecture.md rule 11) is 100: the
    rotor must not end at 200 (the fix: a stamped move read in the window is refused too)."""
    link = Link()
    link.send()  # a beat out through the stall
    link.quiet(10.0)
    link.read()  # the broker runs on: the hold is judged before what it held is handled
    assert link.late() is not None
    svc = MqttService(
        Topics("rotor", {"tower": "rotor"}),
        RecordingPublisher(),
        wall=lambda: NOW_UNIX,
        broker_late=link.late,
    )
    tower = RecordingRotator("tower", "rotorez")
    svc.attach(tower)
    svc.on_message("rotor/target", b"200", False, stamp=Stamp.of(NOW_UNIX - 9.0, 15.0))
    svc.on_message("rotor/target", b"100", False)  # newer: sent 1 s after the remote's
    targets = [c[1] for c in tower.calls if c[0] == "submit" and isinstance(c[1], Target)]
    # the older never stands over the newer: both refused (rule 12 takes a stamped move read
    # in the window too), or the newer last
    assert not targets or targets[-1].az_deg == 100.0, (
        f"the rotor ends at {targets[-1].az_deg:g}: {tower.calls}"
    )
    assert [c[0] for c in tower.calls].count("refused") == 2 - len(targets)
