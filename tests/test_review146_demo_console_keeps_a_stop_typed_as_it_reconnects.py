"""Review 146, finding 1: since 9b73f8b9 the demo's console (bridge/demo/console.py rule 6)
holds a STOP or a lock ON typed while it has lost the broker, and sends what it holds when the
next connection comes up (``_again``, in paho's thread, in on_connect). ``_again`` takes the
held list first and sets ``connected`` only at its end, after it has said and sent the rest: a
STOP typed in between (the input thread, while paho's thread is in on_connect) is refused as
"the console has lost the broker", appended to a list already taken, and said "held: it goes
first when the broker is back", though the broker is back. Nothing sends it: it waits for the
next reconnect, which may never come, while every command typed after it goes at once. The
rotor the user stopped runs on to its target; a lock ON alike leaves the rotator unlocked (and
goes, if ever, after a lock OFF typed later). Its parent 1998b9a5 handed the STOP to paho, which
sent it on the connection coming up.

Real mosquitto (MQTT 5, the demo's usual broker); the console's connection through review 139's
dead path, so that the reconnect has a bearing to say unsure; the user types ``s`` while paho's
thread says so (its screen's log line, the console's only wait there, widened till the STOP is
typed, or till the typing waits for the console's lock); what reaches the broker read by an MQTT
3.1.1 client there.

Fixed: one lock orders typed commands against the connection coming up (console.py rule 6)."""

from __future__ import annotations

import contextlib
import threading

import pytest

from bridge.demo.console import Console
from bridge.demo.screen import Screen
from bridge.interfaces.mqtt.topics import Topics
from tests.support.mosquitto import Mosquitto
from tests.support.waiting import slow, wait_until
from tests.test_review134_demo_console_replays_a_typed_target import BASE, Watcher
from tests.test_review139_demo_console_drops_a_typed_stop import DeadPath, typed_on_a_dead_path


class WatchedLock:
    """The console's lock, which says when a thread had to wait for it."""

    def __init__(self) -> None:
        self._lock = threading.RLock()
        self.waited = threading.Event()

    def __enter__(self) -> None:
        if not self._lock.acquire(blocking=False):
            self.waited.set()
            self._lock.acquire()

    def __exit__(self, *_: object) -> None:
        self._lock.release()


class TypedDuringReconnect(Screen):
    """A screen whose user types ``line`` (on a thread of its own, as the demo's input thread)
    while paho's thread, in on_connect, says a command was not sure to have gone: it goes on
    once the line is typed, or the typing waits for the console's lock (a fix: typed commands
    ordered against the connection coming up)."""

    def __init__(self, line: str) -> None:
        super().__init__()
        self.line = line
        self.console: Console | None = None
        self.lock = WatchedLock()
        self.users: list[threading.Thread] = []  # the user's typing
        self.typed = threading.Event()

    def log(self, text: str, *, quiet: bool = False) -> None:
        super().log(text, quiet=quiet)
        if "not sure it was sent" in text and self.console and not self.typed.is_set():
            user = threading.Thread(target=self.console.command, args=(self.line,))
            self.users.append(user)
            user.start()
            wait_until(
                lambda: not user.is_alive() or self.lock.waited.is_set(), 20, "the user's typing"
            )
            self.typed.set()


@pytest.mark.parametrize(("typed", "word"), [("s", "STOP"), ("lock on", "ON")])
def test_a_stop_typed_while_the_console_reconnects_reaches_the_broker(
    broker: Mosquitto, capsys: pytest.CaptureFixture[str], typed: str, word: str
) -> None:
    relay = DeadPath(broker.port)
    watcher = Watcher(broker.port)
    topics = Topics(BASE, {"rotorez": BASE})
    r = topics.rotator("rotorez")
    screen = TypedDuringReconnect(typed)
    console = Console(
        "127.0.0.1",
        relay.port,
        client_id=f"{BASE}-ui",
        topics=topics,
        rotator_ids=["rotorez"],
        discovery_filters=[],
        screen=screen,
        mqtt5=True,
    )
    screen.console = console
    try:
        assert console.sync(slow(20)), "the console never connected through the relay"
        console._lock = screen.lock  # type: ignore[assignment]  # (each ``with`` binds its own)
        typed_on_a_dead_path(console, relay, watcher, "200", "bearing")
        assert screen.typed.is_set(), "the reconnect said no bearing unsure"
        # the typing may still wait for the console's lock: its line, once it is through
        wait_until(lambda: not screen.users or not screen.users[0].is_alive(), 20, "the typing")
        topic = r.stop if word == "STOP" else r.lock
        with contextlib.suppress(AssertionError):
            watcher.wait_for(topic, word)
        said = capsys.readouterr().out
    finally:
        console.close()
        watcher.close()
        relay.close()
    assert (topic, word) in watcher.got, (
        f"the {typed!r} typed as the console reconnected never reached the broker: "
        f"{watcher.got}; the console said: {said}"
    )
