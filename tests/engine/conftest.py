from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import pytest

from tests.engine.virtual import VirtualRotator


@pytest.fixture
def rig() -> Iterator[Callable[..., VirtualRotator]]:
    """rig(model, **kw): a VirtualRotator (tests/engine/virtual.py), closed after the test."""
    made: list[VirtualRotator] = []

    def make(model: str, **kw: Any) -> VirtualRotator:
        made.append(VirtualRotator(model, **kw))
        return made[-1]

    yield make
    for v in made:
        v.close()
