"""Who owns a base topic (interfaces/mqtt/claim.py), pure."""

from __future__ import annotations

from bridge.interfaces.mqtt.claim import Instance, Verdict, first_look, refusal, yields_to

ME = Instance("rotor-shack-1a2b3c", "shack", 100, 1000.0)
OTHER = Instance("rotor-tower-9f8e7d", "tower", 200, 900.0)


def test_an_info_payload_names_its_instance_and_junk_names_none() -> None:
    assert Instance.parse(ME.info(["x"]).encode()) == ME
    for junk in (b"", b"x", b"[]", b'{"problems": []}', b'{"instance": 5}', b"\xff"):
        assert Instance.parse(junk) is None


def test_the_first_look_refuses_only_a_live_other_instance() -> None:
    other = OTHER.info([]).encode()
    assert first_look(ME, None, None) is Verdict.OURS
    assert first_look(ME, None, b"online") is Verdict.OURS  # a bridge from before info existed
    assert first_look(ME, ME.info([]).encode(), b"online") is Verdict.OURS  # our own last run
    assert first_look(ME, other, b"online") is Verdict.REFUSE
    assert first_look(ME, other, b"offline") is Verdict.TAKE_OVER
    assert first_look(ME, other, None) is Verdict.TAKE_OVER
    assert first_look(ME, b'{"problems":[]}', b"online") is Verdict.OURS


def test_of_two_live_bridges_the_younger_yields_and_only_one() -> None:
    assert yields_to(ME, OTHER) and not yields_to(OTHER, ME)
    twin = Instance("rotor-a", "h", 1, 1000.0), Instance("rotor-b", "h", 2, 1000.0)
    assert yields_to(twin[1], twin[0]) != yields_to(twin[0], twin[1])
    assert not yields_to(ME, ME)


def test_the_refusal_names_the_other_bridge_and_what_to_do() -> None:
    text = refusal("rotor", OTHER, live_since_look=False)
    assert "rotor-tower-9f8e7d" in text and "'tower'" in text and "mqtt.base_topic" in text
