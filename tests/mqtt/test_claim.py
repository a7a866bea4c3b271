"""Who owns a base topic, and a tree of topics (interfaces/mqtt/claim.py), pure."""

from __future__ import annotations

import json

from bridge.interfaces.mqtt.claim import (
    MAX_TOPICS,
    Claim,
    Instance,
    Verdict,
    first_look,
    lies_in,
    overlap,
    overlapping,
    refusal,
    yields_to,
)
from bridge.interfaces.mqtt.topics import Topics

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


NAMES = Topics("rotor", {}).names()


def test_an_info_names_the_bridges_rotator_and_group_topics_and_junk_there_is_dropped() -> None:
    me = Instance("rotor-a", "h", 1, 1.0, ("rotor/tower", "rotor/yagi"))
    assert json.loads(me.info([]))["topics"] == ["rotor/tower", "rotor/yagi"]
    assert Instance.parse(me.info([]).encode()) == me
    odd = b'{"instance": "x", "topics": ["rotor/tower", 5, "", null]}'
    assert Instance.parse(odd) == Instance("x", "?", 0, 0.0, ("rotor/tower",))
    assert Instance.parse(b'{"instance": "x", "topics": "rotor"}') == Instance("x", "?", 0, 0.0)
    flood = json.dumps({"instance": "x", "topics": ["a"] * (MAX_TOPICS + 10)}).encode()
    parsed = Instance.parse(flood)
    assert parsed is not None and len(parsed.topics) == MAX_TOPICS


def test_two_bridges_overlap_when_a_topic_of_one_lies_in_the_others_tree() -> None:
    """Claim rule 5, attack 18: a base topic on another bridge's rotator topic, either way
    round; not a bridge nested by a name no root uses (review 93's ``rotor/site2``)."""
    a = ["rotor", "rotor/tower", "rotor/yagi"]  # base rotor, two rotators
    assert overlap(["rotor/tower"], a, NAMES) == ("rotor/tower", "rotor/tower")
    assert overlap(["rotor/yagi/lock"], a, NAMES) is not None  # (R/lock/state is the yagi's)
    assert overlap(["rotor/tower/option/x"], a, NAMES) is not None
    assert overlap(["rotor/bridge"], a, NAMES) is not None  # (its own B/bridge/info)
    assert overlap(["rotor", "rotor/x", "rotor/y"], ["rotor/x"], NAMES) is not None
    assert overlap(["rotor/site2"], a, NAMES) is None
    assert overlap(["rotor/site2"], ["rotor"], NAMES) is None  # (one rotator on rotor)
    assert overlap(["rotor/tower/site2"], a, NAMES) is None
    assert overlap(["shack"], a, NAMES) is None
    assert overlap(["rotor/towers"], a, NAMES) is None  # (a level, not a prefix)
    assert lies_in("rotor/tower", "rotor/tower", NAMES)
    assert not lies_in("rotor", "rotor/tower", NAMES)


def test_a_look_watches_every_topic_at_or_above_its_own_but_its_base_topic() -> None:
    me = Instance("rotor-b", "h", 1, 1.0, ("rotor/tower/m1", "shack/mast"))
    claim = Claim(me, "rotor/tower", "rotor/tower/bridge/info", "rotor/tower/bridge/hello", NAMES)
    assert claim.watched == ["rotor", "rotor/tower/m1", "shack", "shack/mast"]
    assert Claim(me, "rotor/tower", "i", "h").watched == []  # no names: rule 2 alone


def test_the_overlap_error_is_one_line_naming_both_topics_and_the_base_topic_setting() -> None:
    text = overlapping("rotor/tower", "rotor", OTHER, "rotor/tower", "rotor/tower")
    assert "\n" not in text and "mqtt.base_topic 'rotor/tower'" in text
    assert "rotor-tower-9f8e7d" in text and "base topic 'rotor'" in text
