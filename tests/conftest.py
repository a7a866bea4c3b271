from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support import Mosquitto, Probe


@pytest.fixture
def broker(tmp_path: Path) -> Iterator[Mosquitto]:
    m = Mosquitto(tmp_path).start()
    yield m
    m.stop()


@pytest.fixture
def probe(broker: Mosquitto) -> Iterator[Probe]:
    p = Probe(broker.port)
    yield p
    p.close()
