from __future__ import annotations

import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support import Mosquitto, Probe
from tests.support.rig import Rig


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
