"""paho_client.py rule 11: what the network thread tells its ``hearing`` of one round of its
loop, the proof heartbeat.py rule 11 tells a broker's hold from a backlog by. A poll that found
nothing proves quiet up to its start, or, waited out whole, up to its start plus its wait (never
the clock after it: the thread may run long after the kernel looked); bytes a TLS socket has
already decrypted are read and never quiet, though the raw socket is not readable; a readable
socket is told before its read (its messages are judged after) and after it.

One round of ``Client._round`` with a scripted poller, socket and clock: no broker."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

from paho.mqtt.enums import CallbackAPIVersion, MQTTErrorCode

from bridge.core.polling import POLLIN, POLLOUT
from bridge.interfaces.mqtt.paho_client import Client, Waker


class Ears:
    """A hearing that notes what it is told, on a scripted clock."""

    def __init__(self, times: list[float]) -> None:
        self._times: Iterator[float] = iter(times)
        self.told: list[tuple[str, float | None]] = []

    def clock(self) -> float:
        return next(self._times)

    def quiet(self, until: float) -> None:
        self.told.append(("quiet", until))

    def reading(self) -> None:
        self.told.append(("reading", None))

    def read(self) -> None:
        self.told.append(("read", None))


class Sock:
    """The connection's socket as the round sees it: a descriptor, and (TLS) ``pending``."""

    def __init__(self, fd: int, pending: int | None = None) -> None:
        self._fd = fd
        if pending is not None:
            self.pending = lambda: pending

    def fileno(self) -> int:
        return self._fd


class Poller:
    """A poll that returns what it is scripted to, at once, noting the wait it was given."""

    def __init__(
        self, events: list[tuple[int, int]], then: list[tuple[int, int]] | None = None
    ) -> None:
        self.events = events
        self.then = events if then is None else then  # what every later poll returns
        self.waits: list[float] = []

    def register(self, fd: Any, mask: int = 0) -> None:
        pass

    def unregister(self, fd: Any) -> None:
        pass

    def poll(self, timeout: float | None = None) -> list[tuple[int, int]]:
        self.waits.append(0.0 if timeout is None else timeout)
        return self.events if len(self.waits) == 1 else self.then


SOCK_FD = 1000  # (never polled for real: the poller is scripted)
WAKER_FD = 1001  # another descriptor than the socket's: the round takes it for its waker


def one_round(sock: Sock, poller: Poller, ears: Ears) -> list[tuple[str, float | None]]:
    """One round of the loop with ``ears``; what it was told, and ``loop_read`` in its place."""
    c = Client(callback_api_version=CallbackAPIVersion.VERSION2)
    c._waker = Waker()
    c.hearing = ears

    def loop_read(max_packets: int = 1) -> MQTTErrorCode:
        ears.told.append(("loop_read", None))
        return MQTTErrorCode.MQTT_ERR_SUCCESS

    c.loop_read = loop_read  # type: ignore[method-assign]
    c.socket = lambda: sock  # type: ignore[method-assign,assignment,return-value]
    c.want_write = lambda: False  # type: ignore[method-assign]
    c.loop_misc = lambda: MQTTErrorCode.MQTT_ERR_SUCCESS  # type: ignore[method-assign]
    try:
        assert c._round(sock, poller)
    finally:
        c._waker.close()
    return ears.told


def test_a_poll_waited_out_proves_quiet_up_to_its_start_and_wait_not_the_clock_after_it() -> None:
    ears = Ears([10.0, 12.5])  # before the poll; after it (the thread ran late)
    told = one_round(Sock(SOCK_FD), Poller([]), ears)
    assert told == [("quiet", 11.0)]  # 1 s of wait: the kernel looked then, at least


def test_a_poll_waited_out_proves_no_more_than_the_clock_after_it() -> None:
    ears = Ears([10.0, 10.4])  # (a clock that says less: never more than it)
    assert one_round(Sock(SOCK_FD), Poller([]), ears) == [("quiet", 10.4)]


def test_a_poll_woken_by_another_thread_looks_again_and_proves_quiet_up_to_that_look() -> None:
    """Woken by another thread's message (the waker), or by the socket writable: the round looks
    once more without waiting, the clock read first; nothing then proves quiet up to that clock
    (review 61: up to the poll's start alone, a second of a stall went unseen at each wake-up),
    never the clock after the look (the thread may have run late after it)."""
    poller = Poller([(WAKER_FD, POLLIN)], then=[])
    woken = one_round(Sock(SOCK_FD), poller, Ears([10.0, 10.7, 99.0]))
    assert woken == [("quiet", 10.7)]
    assert poller.waits == [1000, 0]  # (the look waits for nothing)
    writable = one_round(
        Sock(SOCK_FD), Poller([(SOCK_FD, POLLOUT)], then=[]), Ears([10.0, 10.2, 99.0])
    )
    assert writable == [("quiet", 10.2)]


def test_bytes_the_look_after_a_wake_up_finds_are_read_at_once() -> None:
    """The look after a wake-up finds bytes: quiet is proven up to the poll's start alone, and
    the bytes are read in this round, told before their messages are handled."""
    poller = Poller([(WAKER_FD, POLLIN)], then=[(SOCK_FD, POLLIN)])
    told = one_round(Sock(SOCK_FD), poller, Ears([10.0, 10.7, 10.8, 10.9]))
    assert told == [("quiet", 10.0), ("reading", None), ("loop_read", None), ("read", None)]


def test_bytes_tls_already_decrypted_are_read_at_once_and_never_quiet() -> None:
    """The raw socket is not readable (the poll finds nothing) but the SSL socket holds bytes
    decrypted in userspace: they are read, and the round proves no quiet."""
    poller = Poller([])
    told = one_round(Sock(SOCK_FD, pending=37), poller, Ears([10.0, 10.0]))
    assert poller.waits == [0]  # (not waited on)
    assert told == [("reading", None), ("loop_read", None), ("read", None)]


def test_a_readable_socket_is_told_before_its_read_and_after_it_never_quiet() -> None:
    told = one_round(Sock(SOCK_FD, pending=0), Poller([(SOCK_FD, POLLIN)]), Ears([10.0]))
    assert told == [("reading", None), ("loop_read", None), ("read", None)]


def test_without_hearing_the_round_reads_as_before() -> None:
    c = Client(callback_api_version=CallbackAPIVersion.VERSION2)
    c._waker = Waker()
    reads: list[int] = []

    def loop_read(max_packets: int = 1) -> MQTTErrorCode:
        reads.append(max_packets)
        return MQTTErrorCode.MQTT_ERR_SUCCESS

    sock = Sock(SOCK_FD)
    c.loop_read = loop_read  # type: ignore[method-assign]
    c.socket = lambda: sock  # type: ignore[method-assign,assignment,return-value]
    c.want_write = lambda: False  # type: ignore[method-assign]
    c.loop_misc = lambda: MQTTErrorCode.MQTT_ERR_SUCCESS  # type: ignore[method-assign]
    try:
        assert c._round(sock, Poller([(SOCK_FD, POLLIN)]))
        assert c._round(sock, Poller([]))
    finally:
        c._waker.close()
    assert reads == [1]
