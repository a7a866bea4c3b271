"""Review 68: a78850c1 made one rule read every topic's words (payloads.py ``_words``: a
byte-order mark before them and NULs after them dropped) and e4b1d054 read a claim through it,
but ``R/control/release`` still reads its raw bytes (control/payload.py ``parse_release``): the
same tool that took the lease as DL1ABC releases it as nobody, and the audit trail's who
(``last_operator``, ``R/audit``) loses the name."""

from __future__ import annotations

import pytest

from bridge.core.model import Origin, Source
from tests.mqtt.test_service import service

# what a Windows script (a UTF-8 byte-order mark first) and an Arduino sketch (strlen + 1
# bytes: the C string's NUL) put round a JSON document, as docs/mqtt.md says every topic drops
FRAMES = [
    pytest.param(b"\xef\xbb\xbf", b"", id="bom"),
    pytest.param(b"", b"\0", id="trailing-nul"),
]


@pytest.mark.parametrize(("before", "after"), FRAMES)
def test_a_release_names_its_operator_in_the_framing_a_claim_is_read_in(
    before: bytes, after: bytes
) -> None:
    svc, _, rots = service({"tower": "rotorez"})
    rot = rots["tower"]
    claim = before + b'{"operator": "DL1ABC", "minutes": 30}' + after
    release = before + b'{"operator": "DL1ABC"}' + after
    svc.on_message("rotor/control/claim", claim, False)
    svc.on_message("rotor/control/release", release, False)
    taken = [c for c in rot.calls if c[0] in ("claim", "release_control")]
    assert [c[0] for c in taken] == ["claim", "release_control"]
    assert taken[0][1:3] == ("DL1ABC", 30)  # the claim read the words: the lease is DL1ABC's
    assert rot.origins[-1] == Origin(Source.MQTT, "DL1ABC")  # and so does its release
