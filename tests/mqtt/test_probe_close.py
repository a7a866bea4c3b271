"""The tests' MQTT probe ends without paho's race (tests/support/mqtt.py ``end_paho``): paho's
own ``loop_stop`` reads its thread twice, and the thread, ending on the DISCONNECT, clears it
in between on a busy machine; a test then failed in its teardown with "'NoneType' object has
no attribute 'join'" (eclipse-paho/paho.mqtt.python issue 872). The machine's slowness is
played here: ``loop_stop``'s look at the current thread waits until paho's thread has ended."""

from __future__ import annotations

import threading
import types
from collections.abc import Callable

import paho.mqtt.client as paho_module
import pytest

from tests.support import Mosquitto, Probe
from tests.support.mqtt import end_paho
from tests.support.waiting import slow, wait_until


def loop_stop_slowed(monkeypatch: pytest.MonkeyPatch, probe: Probe) -> None:
    """paho's ``loop_stop`` takes the CPU back only once its thread has ended (a busy machine).
    paho's thread is held in its ``on_disconnect`` until ``loop_stop`` has read it: on a quiet
    machine the thread could otherwise end before ``loop_stop`` began, and there is no race."""
    real: Callable[[], threading.Thread] = threading.current_thread
    read = threading.Event()  # loop_stop has read paho's thread (it asks for ours next)
    probe.client.on_disconnect = lambda *_args: read.wait(slow(10))

    def current_thread() -> threading.Thread:
        read.set()
        wait_until(lambda: getattr(probe.client, "_thread", None) is None, 10, "paho's end")
        return real()

    shim = types.SimpleNamespace(**{**vars(threading), "current_thread": current_thread})
    monkeypatch.setattr(paho_module, "threading", shim)


def test_a_probe_closes_though_paho_ended_its_thread_inside_loop_stop(
    broker: Mosquitto, monkeypatch: pytest.MonkeyPatch
) -> None:
    probe = Probe(broker.port, "")
    thread = probe.client._thread  # noqa: SLF001 - paho's loop thread, to see it end
    assert thread is not None and thread.is_alive()
    loop_stop_slowed(monkeypatch, probe)
    probe.close()
    assert not thread.is_alive()


def test_paho_alone_loses_that_race(broker: Mosquitto, monkeypatch: pytest.MonkeyPatch) -> None:
    """What ``end_paho`` is for: the same close by paho's calls alone fails."""
    probe = Probe(broker.port, "")
    loop_stop_slowed(monkeypatch, probe)
    probe.client.disconnect()
    with pytest.raises(AttributeError, match="join"):
        probe.client.loop_stop()
    end_paho(probe.client)  # and ending it again is harmless
