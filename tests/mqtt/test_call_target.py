"""``R/target`` ``{"call": ...}`` (call_payload.py, service.py): parsed, handed to the DX
cluster's aimer with who asked, or refused with a reason; nothing moves on a bad one."""

from __future__ import annotations

import pytest

from bridge.core.model import Origin, Source
from bridge.interfaces.mqtt.call_payload import Called
from bridge.interfaces.mqtt.payloads import PayloadError, parse_aim
from bridge.interfaces.mqtt.ports import RotatorPort
from tests.mqtt.test_service import service


def test_the_call_form_is_parsed() -> None:
    assert parse_aim(b'{"call": "ja1abc"}') == Called("JA1ABC")
    assert parse_aim(b'{"call": " VK2XYZ/P ", "path": "long"}') == Called("VK2XYZ/P", True)


@pytest.mark.parametrize(
    ("payload", "message"),
    [
        (b'{"call": "not a call"}', '"call" must be a call sign'),
        (b'{"call": "ABCDEF"}', '"call" must be a call sign'),  # no digit
        (b'{"call": 12}', '"call" must be a call sign'),
        (b'{"call": "JA1ABC", "band": 20}', "unknown key(s) in a call target: band"),
        (b'{"call": "JA1ABC", "path": "sideways"}', '"path" must be "short" or "long"'),
    ],
)
def test_a_bad_call_is_refused(payload: bytes, message: str) -> None:
    with pytest.raises(PayloadError, match=message.replace("(", r"\(").replace(")", r"\)")):
        parse_aim(payload)
    svc, _, rots = service({"tower": "rotorez"})
    asked: list[object] = []
    svc.aim_calls_with(lambda *a: asked.append(a))
    svc.on_message("rotor/target", payload, False)
    assert rots["tower"].calls[0][0] == "refused" and message in str(rots["tower"].calls[0][1])
    assert asked == []


def test_without_the_dx_cluster_a_call_is_refused() -> None:
    svc, _, rots = service({"tower": "rotorez"})
    svc.on_message("rotor/target", b'{"call": "JA1ABC"}', False)
    assert rots["tower"].calls == [
        (
            "refused",
            "a target by call needs [dxcluster] enabled = true",
            'target \'{"call": "JA1ABC"}\'',
        )
    ]


def test_a_call_goes_to_the_aimer_with_who_asked() -> None:
    svc, _, rots = service({"tower": "rotorez"})
    asked: list[tuple[RotatorPort, str, bool, str, Origin, int, float | None]] = []
    svc.aim_calls_with(lambda *a: asked.append(a))
    svc.on_message("rotor/target", b'{"call": "ja1abc", "path": "long"}', False, "G4ABC")
    ((rot, call, long_path, what, origin, since, not_after_s),) = asked
    assert since == rots["tower"].halts  # (service.py rule 11)
    assert rot is rots["tower"] and (call, long_path) == ("JA1ABC", True)
    assert what == 'target \'{"call": "ja1abc", "path": "long"}\''
    assert origin == Origin(Source.MQTT, "G4ABC")
    assert not_after_s is None  # (unstamped: no expiry of its own; service.py rule 9)
    svc.on_message("rotor/target", b'{"call": "JA1ABC"}', True)  # retained: never a command
    assert len(asked) == 1
