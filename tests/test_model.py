"""Plain value types: the error kinds are published API, listed once (tests/test_docs.py checks
that docs/mqtt.md documents each)."""

from __future__ import annotations

import json

import pytest

from bridge.core.model import ErrorEvent, ErrorKind

PUBLISHED_KINDS = {
    "refused",
    "stalled",
    "stop",
    "serial",
    "protocol",
    "state",
    "internal",
    "audit",
    "wind",
}


def test_the_error_kinds_are_exactly_the_published_ones() -> None:
    assert {kind.value for kind in ErrorKind} == PUBLISHED_KINDS


def test_an_event_of_any_other_kind_cannot_be_made() -> None:
    with pytest.raises(ValueError):
        ErrorEvent("config", "no such kind")  # type: ignore[arg-type]


def test_a_kind_given_as_text_is_the_kind_and_published_as_text() -> None:
    event = ErrorEvent("serial", "port gone", None, 12.5)  # type: ignore[arg-type]
    assert event.kind is ErrorKind.SERIAL
    assert json.dumps(event.as_dict()) == (
        '{"kind": "serial", "message": "port gone", "time": 12.5}'
    )
