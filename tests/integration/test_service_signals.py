"""SIGTERM ends the service (app.run) in order, whatever its main thread was doing when the signal
came: Python runs the handler on that thread between two of its steps, also while it holds the
lock of the Event it waits on (Event.wait holds it around its wait). A handler that set that
Event waited on its own thread for ever, and ``systemctl stop`` hung until systemd killed the
bridge, its ``offline`` never said (core/ending.py)."""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import threading

import pytest

from bridge.app import App, run
from tests.support import slow
from tests.support.rig import Rig


def test_a_sigterm_while_the_main_thread_holds_its_events_lock_stops_the_service_in_order(
    rig: Rig, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    rig.add("tower", "rotorez")
    stop = threading.Event()  # a caller's stop, on the main thread: the one the old handler set
    inside_wait = stop._cond  # what Event.wait holds around its wait (a plain, one-owner lock)
    handled = threading.Event()
    hung: list[str] = []

    def release_if_hung() -> None:  # a hang fails the test instead of hanging the suite
        if not handled.wait(slow(10)):
            hung.append("the SIGTERM handler waited on a lock its own thread held")
            inside_wait.release()

    real_start = App.start

    def start_then_sigterm(app: App) -> None:
        real_start(app)
        rig.ready("tower")  # online, and its status on the broker
        watcher = threading.Thread(target=release_if_hung, daemon=True)
        watcher.start()
        inside_wait.acquire()
        try:
            os.kill(os.getpid(), signal.SIGTERM)  # the handler runs here, on this thread
            handled.set()
        finally:
            with contextlib.suppress(RuntimeError):  # (released by the watcher: a hang)
                inside_wait.release()
        watcher.join()

    monkeypatch.setattr(App, "start", start_then_sigterm)
    with caplog.at_level(logging.INFO, logger="bridge.app"):
        assert run(rig.settings, stop) == 0
    assert hung == []
    assert "SIGTERM received, shutting down" in caplog.text
    assert rig.retained()[f"{rig.base}/bridge/state"] == b"offline"  # the ordered stop said so


def test_the_service_puts_the_signal_handlers_back_when_it_ends(
    rig: Rig, monkeypatch: pytest.MonkeyPatch
) -> None:
    rig.add("tower", "rotorez")
    before = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    real_start = App.start

    def start_then_sigint(app: App) -> None:
        real_start(app)
        os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C: handled by the service, not KeyboardInterrupt

    monkeypatch.setattr(App, "start", start_then_sigint)
    assert run(rig.settings) == 0
    assert {sig: signal.getsignal(sig) for sig in before} == before
