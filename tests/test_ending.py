"""core/ending.py: a signal ends the main thread's wait without taking a lock, at once, whichever
thread the system delivered it to; another thread's end does too; nothing asked before the wait
is lost; the handlers are put back as they were.

Each wait here that could hang has a watchdog: a thread that ends the wait itself after a
deadline, with a reason of its own, so a hang fails the test (the reason says who ended it)
instead of hanging the suite."""

from __future__ import annotations

import os
import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from bridge.core.ending import Ending
from tests.support import slow, wait_until

ROOT = Path(__file__).resolve().parent.parent
WATCHDOG = "the watchdog (nothing else ended the wait)"


@contextmanager
def watchdog(ending: Ending, deadline_s: float = 10) -> Iterator[None]:
    over = threading.Event()

    def watch() -> None:
        if not over.wait(slow(deadline_s)):
            ending.end(WATCHDOG)

    thread = threading.Thread(target=watch, daemon=True)
    thread.start()
    try:
        yield
    finally:
        over.set()
        thread.join()


def _main_thread_in_poll() -> bool:
    """The main thread sleeps in poll (its kernel wait channel says so; a kernel that hides
    it says 0, and then the test goes on as soon as it can)."""
    path = f"/proc/self/task/{threading.main_thread().native_id}/wchan"
    try:
        with open(path) as f:
            where = f.read()
    except OSError:
        return True
    return "poll" in where or where.strip() in ("", "0")


def test_another_threads_end_wakes_the_wait_and_its_reason_is_kept() -> None:
    ending = Ending()
    threading.Thread(target=lambda: (wait_until(_main_thread_in_poll), ending.end("q"))).start()
    with watchdog(ending):
        assert ending.wait() is True
    assert ending.reason == "q"
    ending.end("later")  # a second end changes nothing, and needs no wait to be taken
    assert ending.reason == "q" and ending.is_set()
    ending.close()
    ending.end("after close")  # harmless: nobody waits any more


def test_a_wait_that_nothing_ends_returns_false_at_its_timeout() -> None:
    ending = Ending()
    assert ending.wait(0.01) is False  # not a deadline: the timeout is what is tested
    assert not ending.is_set() and ending.reason is None


def test_a_signal_before_the_wait_is_not_lost() -> None:
    """A Ctrl-C during start-up: the wait that comes after it returns at once."""
    ending = Ending()
    with ending.on_signals(signal.SIGINT):
        os.kill(os.getpid(), signal.SIGINT)
        with watchdog(ending):
            assert ending.wait() is True
    assert ending.reason == "SIGINT"


def test_a_signal_delivered_to_another_thread_wakes_the_main_threads_wait_at_once() -> None:
    """Python runs the handler on the main thread only when that thread wakes: the wake-up
    socket wakes it (without it, the watchdog would end this wait)."""
    ending = Ending()
    stay = threading.Event()
    other = threading.Thread(target=stay.wait, daemon=True)
    other.start()
    assert other.ident is not None

    def kill_other() -> None:
        wait_until(_main_thread_in_poll, what="the main thread asleep in poll")
        signal.pthread_kill(other.ident, signal.SIGTERM)  # type: ignore[arg-type]

    try:
        with ending.on_signals(signal.SIGTERM), watchdog(ending):
            threading.Thread(target=kill_other, daemon=True).start()
            assert ending.wait() is True
    finally:
        stay.set()
    assert ending.reason == "SIGTERM"


def test_a_second_signal_keeps_the_first_reason_and_the_handlers_are_put_back() -> None:
    before = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    wakeup_before = signal.set_wakeup_fd(-1)
    signal.set_wakeup_fd(wakeup_before)
    ending = Ending()
    with ending.on_signals(signal.SIGINT, signal.SIGTERM):
        os.kill(os.getpid(), signal.SIGINT)
        os.kill(os.getpid(), signal.SIGINT)  # a second Ctrl-C during the ordered shutdown
        os.kill(os.getpid(), signal.SIGTERM)
        assert ending.is_set() and ending.reason == "SIGINT"
    assert {sig: signal.getsignal(sig) for sig in before} == before
    assert signal.set_wakeup_fd(wakeup_before) == wakeup_before


def test_off_the_main_thread_no_handler_is_set() -> None:
    before = signal.getsignal(signal.SIGTERM)
    seen: list[object] = []

    def on_a_thread() -> None:
        ending = Ending()
        with ending.on_signals(signal.SIGTERM):
            seen.append(signal.getsignal(signal.SIGTERM))
        ending.close()

    thread = threading.Thread(target=on_a_thread)
    thread.start()
    thread.join()
    assert seen == [before]


def test_no_signal_handler_in_bridge_but_the_endings() -> None:
    """A handler of its own (one that sets an Event, logs, takes any lock) could wait for ever
    on a lock its own thread held when the signal came; ignoring a signal is no handler."""
    found = [
        f"{path.relative_to(ROOT)}:{n}"
        for path in sorted((ROOT / "bridge").rglob("*.py"))
        if path != ROOT / "bridge" / "core" / "ending.py"
        for n, line in enumerate(path.read_text().splitlines(), 1)
        if "signal.signal(" in line and "signal.SIG_IGN" not in line
    ]
    assert not found, f"a signal handler of its own, not core/ending.py's: {found}"
