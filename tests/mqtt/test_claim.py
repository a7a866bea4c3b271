"""Who owns a base topic (interfaces/mqtt/claim.py), pure."""

from __future__ import annotations

from bridge.interfaces.mqtt.claim import (
    Instance,
    Post,
    Verdict,
    first_look,
    refusal,
    refusal_on,
    standing,
    yields_to,
)

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


POSTS = (
    Post("rotor/bridge/info", "rotor/bridge/state", bridge=True),
    Post("rotor/tower/bridge/info", "rotor/tower/bridge/state", bridge=True),
    Post("rotor/tower/info", "rotor/tower/availability"),
)


def test_another_instance_live_on_a_post_stands_there_and_its_own_never() -> None:
    """Rule 5: a rotator's info or a bridge's info of another instance, ``online`` beside it."""
    rotator = {"rotor/tower/info": b'{"id":"tower","instance":"rotor-tower-9f8e7d"}'}
    live = {**rotator, "rotor/tower/availability": b"online"}
    assert standing(ME, POSTS, live) == (
        Instance("rotor-tower-9f8e7d", "?", 0, 0.0),
        POSTS[2],
        True,
    )
    bridge = {"rotor/tower/bridge/info": OTHER.info([]).encode()}
    assert standing(ME, POSTS, {**bridge, "rotor/tower/bridge/state": b"online"}) == (
        OTHER,
        POSTS[1],
        True,
    )
    mine = {"rotor/tower/info": b'{"instance":"rotor-shack-1a2b3c"}'}
    assert standing(ME, POSTS, {**mine, "rotor/tower/availability": b"online"}) is None
    old = {"rotor/tower/info": b'{"id":"tower"}', "rotor/tower/availability": b"online"}
    assert standing(ME, POSTS, old) is None  # an older bridge's info names no instance


def test_a_gone_instance_stands_nowhere_whatever_its_rotators_say() -> None:
    """Rule 5: a rotator that said ``offline`` (a clean stop), or an instance whose bridge info
    here says it is not online (its last will), is gone: found, not standing."""
    rotator = {"rotor/tower/info": b'{"instance":"rotor-tower-9f8e7d"}'}
    offline = {**rotator, "rotor/tower/availability": b"offline"}
    assert standing(ME, POSTS, offline) == (
        Instance.parse(rotator["rotor/tower/info"]),
        POSTS[2],
        False,
    )
    killed = {  # its last will on its bridge state; its rotator's availability left online
        "rotor/bridge/info": OTHER.info([]).encode(),
        "rotor/bridge/state": b"offline",
        "rotor/tower/info": b'{"instance":"rotor-tower-9f8e7d"}',
        "rotor/tower/availability": b"online",
    }
    found = standing(ME, POSTS, killed)
    assert found is not None and not found[2]


def test_the_refusal_on_a_post_names_the_other_and_the_topic() -> None:
    text = refusal_on(OTHER, POSTS[1])
    assert "rotor-tower-9f8e7d" in text and "'rotor/tower/bridge/info'" in text
    assert "mqtt.base_topic" in text and "\n" not in text
