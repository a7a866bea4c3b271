"""Plain value types: the error kinds are published API, listed once (tests/test_docs.py checks
that docs/mqtt.md documents each)."""

from __future__ import annotations

import json

import pytest

from bridge.core.model import ErrorEvent, ErrorKind, Target, combine

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


# combine with stamped targets (Target.not_after_s, session.py rule 13): two halves of one
# sender's target expire with the sooner of the two; a newer one that takes nothing keeps its own
def test_an_axis_taken_from_an_older_stamped_target_brings_its_sooner_expiry() -> None:
    older = Target(200.0, None, not_after_s=10.0)
    assert combine(Target(None, 30.0, not_after_s=15.0), older).not_after_s == 10.0
    assert combine(Target(None, 30.0), older).not_after_s == 10.0
    assert combine(Target(None, 30.0, not_after_s=5.0), older).not_after_s == 5.0


def test_a_newer_target_that_takes_nothing_keeps_its_own_expiry() -> None:
    older = Target(200.0, 10.0, not_after_s=10.0)
    assert combine(Target(100.0, 20.0), older).not_after_s is None
    assert combine(Target(100.0, 20.0, not_after_s=15.0), older).not_after_s == 15.0
    assert combine(Target(None, 30.0, not_after_s=15.0), Target(200.0)).not_after_s == 15.0


def test_an_azimuth_taken_from_an_older_target_names_the_end_it_named() -> None:
    """A group member's azimuth names neither end of its travel (Target.az_either_end,
    pointing.py rule 2): a later elevation alone from the same sender keeps it so, and an
    azimuth of the newer's own is as it names it."""
    older = Target(0.0, None, az_either_end=True)
    assert combine(Target(None, 30.0), older).az_either_end
    assert not combine(Target(0.0, 30.0), older).az_either_end
