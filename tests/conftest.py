from __future__ import annotations

import gc
import os
import shutil
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from hypothesis import settings

from bridge.emulators.pty import EmulatedPort
from bridge.interfaces.mqtt.service import MqttService
from tests.support import Mosquitto, Probe
from tests.support.cpu import register as register_cpu_recorder
from tests.support.rig import Rig
from tests.support.waiting import FOLLOW, SLOWDOWN, slow

# Hypothesis fails an example that takes longer than 200 ms: a wall-clock upper bound, which a
# busy machine breaks; what an example proves is its outcome, never its speed
settings.register_profile("rotor-bridge", deadline=None)
settings.load_profile("rotor-bridge")


_fds_kept = 0  # the worker's open descriptors after its last collection


@pytest.hookimpl(trylast=True)
def pytest_runtest_teardown(item: pytest.Item) -> None:
    """A closed paho client keeps its wake-up socket pair until the garbage collector breaks the
    client's reference cycles; after some hundreds of bridges and probes a worker held more than
    1,024 descriptors, and pyserial's select() failed on the next port opened. Collected when 128
    more are open than after the last collection: a few times a worker."""
    global _fds_kept
    try:
        held = len(os.listdir("/proc/self/fd"))
    except OSError:
        return
    if held > _fds_kept + 128:
        gc.collect()
        _fds_kept = len(os.listdir("/proc/self/fd"))


def _escaped(text: str) -> str:
    return text.encode("utf-8", "backslashreplace").decode("utf-8")


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]) -> Iterator[None]:
    """A report holding a lone surrogate (a path in a home folder whose name is not UTF-8, as
    the review 69/76 tests make, in an assertion's values or a captured log line) cannot be sent
    from an xdist worker: execnet encodes it as UTF-8, fails, and the whole run ends in an
    INTERNALERROR. Such a report's text is escaped as the bridge's own log escapes it."""
    outcome = yield
    report = outcome.get_result()  # type: ignore[attr-defined]
    report.sections = [(key, _escaped(text)) for key, text in report.sections]
    if report.longrepr is not None:
        text = str(report.longrepr)
        if _escaped(text) != text:
            report.longrepr = _escaped(text)


def pytest_configure(config: pytest.Config) -> None:
    # each test's CPU-seconds into a file when ROTOR_TEST_CPU names one (tests/support/cpu.py)
    register_cpu_recorder(config)


@pytest.fixture(autouse=True, scope="session")
def _emulator_waits_scaled() -> Iterator[None]:
    """An emulator's waits (``wait_for``, ``wait_for_frame``, all through ``wait_until``) are
    the tests' deadlines, scaled like every other (tests/support/waiting.py rule 1): the
    emulators ship with the bridge, which knows nothing of the tests' factor. (The tests'
    mosquitto scales its own start: tests/support/mosquitto.py.)"""
    if SLOWDOWN == 1.0 and not FOLLOW:
        yield
        return
    original = EmulatedPort.wait_until

    def scaled(
        self: EmulatedPort[Any],
        probe: Callable[[Any, float], Any],
        predicate: Callable[[Any], bool],
        timeout_s: float = 5.0,
    ) -> Any:
        return original(self, probe, predicate, slow(timeout_s))

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(EmulatedPort, "wait_until", scaled)
        yield


@pytest.fixture(autouse=True)
def _mqtt_timers_end_with_the_test() -> Iterator[None]:
    """The timer of each MQTT service a test made (interfaces/mqtt/halts.py) ends with the test,
    as the bridge's stop ends it: a unit test's service, never stopped, with a hold or a marker
    out looked again every second for the rest of the worker's life, a new thread each time, and
    a later test's snapshot of the threads (the console's taken-port test) took one of them for
    a thread its failed start had left running."""
    made: list[MqttService] = []
    original = MqttService.__init__

    def recorded(self: MqttService, *args: Any, **kwargs: Any) -> None:
        original(self, *args, **kwargs)
        made.append(self)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(MqttService, "__init__", recorded)
        yield
    for service in made:
        service._halts.stop()


@pytest.fixture
def broker_conf() -> str:
    """Extra mosquitto.conf lines for the ``broker`` fixture (a suite's conftest may say others)."""
    return ""


@pytest.fixture
def broker(tmp_path: Path, broker_conf: str) -> Iterator[Mosquitto]:
    m = Mosquitto(tmp_path, extra_conf=broker_conf).start()
    yield m
    m.stop()


@pytest.fixture
def probe(broker: Mosquitto) -> Iterator[Probe]:
    p = Probe(broker.port)
    yield p
    p.close()


@pytest.fixture
def rig(tmp_path: Path, broker: Mosquitto, probe: Probe) -> Iterator[Rig]:
    with Rig(tmp_path, broker, probe) as r:
        yield r


@pytest.fixture(scope="session")
def rotctl_path() -> str:
    """Hamlib's rotctl, the independent judge of the emulators and of the rotctld port."""
    path = shutil.which("rotctl")
    if path is None:
        pytest.fail(
            "Hamlib's rotctl is not installed (Debian: apt-get install libhamlib-utils; "
            "./tests/run installs it): it is an independent judge, these tests cannot be skipped"
        )
    return path
