"""The control lease's payloads, pure (bridge/features/control/payload.py)."""

from __future__ import annotations

import pytest

from bridge.core.model import Control
from bridge.features.control.payload import control_json, parse_claim, parse_release
from bridge.interfaces.mqtt.payloads import PayloadError


def test_a_claim_names_an_operator_and_minutes_or_takes_the_messages_operator() -> None:
    assert parse_claim(b'{"operator": "DL1ABC", "minutes": 30}', None) == ("DL1ABC", 30)
    assert parse_claim(b'{"minutes": 5}', "G4XYZ") == ("G4XYZ", 5)
    assert parse_claim(b'{"operator": "DL1ABC", "minutes": 5}', "G4XYZ") == ("DL1ABC", 5)
    assert parse_claim(b'{"operator": "DL1ABC", "minutes": NaN}', None) == ("DL1ABC", "NaN")


@pytest.mark.parametrize(
    ("minutes", "read"), [('"30"', 30.0), ('" 7.5 "', 7.5), ('"1e1"', 10.0), ('"thirty"', "thirty")]
)
def test_a_claims_minutes_may_be_a_string_that_holds_a_number(minutes: str, read: object) -> None:
    """Attack 20: docs/mqtt.md's numbers, "in JSON a number, or a string that holds one", as
    R/target reads them; a string that holds none goes as sent, for the lease to refuse."""
    payload = f'{{"operator": "DL1ABC", "minutes": {minutes}}}'.encode()
    assert parse_claim(payload, None) == ("DL1ABC", read)


def test_a_claim_is_read_by_every_topics_word_rule() -> None:
    """payloads.py ``_words``: a byte-order mark before it and a C string's NUL after it."""
    assert parse_claim(b'\xef\xbb\xbf{"operator": "DL1ABC", "minutes": 30}\x00', None) == (
        "DL1ABC",
        30,
    )
    with pytest.raises(PayloadError, match="empty payload"):
        parse_claim(b"", None)


@pytest.mark.parametrize(
    ("payload", "why"),
    [
        (b"{not json", "bad JSON"),
        (b'{"operator": "DL1ABC", "minutes": 30, "minutes": 600}', "key 'minutes' given twice"),
        (b"30", "must be a JSON object"),
        (b'["DL1ABC", 30]', "must be a JSON object"),
        (b'{"operator": "DL1ABC"}', 'needs "minutes"'),
        (b'{"minutes": 30}', 'needs "operator"'),
        (
            b'{"operator": "DL1ABC", "minutes": 30, "force": true}',
            r"unknown key\(s\) in a claim: force",
        ),
        (b"\xff\xfe", "not UTF-8"),
        (b"{" + b" " * 300 + b"}", "too large"),
    ],
)
def test_a_claim_not_understood_says_what_was_wrong(payload: bytes, why: str) -> None:
    with pytest.raises(PayloadError, match=why):
        parse_claim(payload, None)


def test_a_release_may_name_who_released_it() -> None:
    assert parse_release(b'{"operator": "homeassistant"}') == "homeassistant"
    assert parse_release(b"") is None
    assert parse_release(b"RELEASE") is None
    assert parse_release(b'{"operator": "\\u001b[2J"}') is None  # not printable: nobody
    assert parse_release(b"{broken") is None
    # an attack pass: JSON nested past the parser's depth raised, and the release was lost
    assert parse_release(b'{"a":' + b"[" * 200_000) is None
    assert parse_release(b'{"a":' + b"[" * 100 + b"]" * 100 + b"}") is None
    assert parse_release(b'{"operator": "\\ud800"}') is None  # a lone surrogate: nobody


def test_r_control_says_who_and_until_when_or_nobody() -> None:
    held = Control("DL1ABC", 1_790_000_000.0)
    assert control_json(held) == '{"holder":"DL1ABC","until":"2026-09-21T14:13:20.000+00:00"}'
    assert control_json(None) == '{"holder":null,"until":null}'
