"""Who owns a base topic (interfaces/mqtt/claim.py), pure."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest

from bridge.interfaces.mqtt.claim import (
    Claim,
    Instance,
    Post,
    Verdict,
    first_look,
    installation,
    refusal,
    refusal_on,
    stamp_stopped,
    standing,
    stopped,
    unusable_stamp,
    vouch_reads,
    yields_to,
)

ME = Instance("rotor-shack-1a2b3c", "shack", 100, 1000.0)
OTHER = Instance("rotor-tower-9f8e7d", "tower", 200, 900.0)


def test_an_info_payload_names_its_instance_and_junk_names_none() -> None:
    assert Instance.parse(ME.info(["x"]).encode()) == ME
    for junk in (
        b"",
        b"x",
        b"[]",
        b'{"problems": []}',
        b'{"instance": 5}',
        b"\xff",
        b'{"instance": "x"}',
    ):
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


POSTS = (  # ME's on base topic rotor/tower with one rotator (R = rotor/tower)
    Post("rotor/tower/bridge/info"),
    Post("rotor/tower/info"),
)
ROTATOR = b'{"id":"tower","bridge":{"instance":"rotor-tower-9f8e7d","base_topic":"rotor"}}'


def stands(seen: dict[str, bytes], base: str = "rotor/tower") -> tuple[str, str, bool] | None:
    found = standing(ME, base, POSTS, seen)
    return None if found is None else (found.other.id, found.beside, found.live)


def test_another_instance_live_on_a_post_stands_there_and_its_own_never() -> None:
    """Rule 5: a rotator's info or a bridge's info of another instance, ``online`` beside it."""
    live = {"rotor/tower/info": ROTATOR, "rotor/tower/availability": b"online"}
    assert stands(live) == ("rotor-tower-9f8e7d", "rotor/tower/availability", True)
    bridge = {"rotor/tower/bridge/info": OTHER.info([]).encode()}
    assert stands({**bridge, "rotor/tower/bridge/state": b"online"}) == (
        "rotor-tower-9f8e7d",
        "rotor/tower/bridge/state",
        True,
    )
    mine = {"rotor/tower/info": ROTATOR.replace(b"rotor-tower-9f8e7d", ME.id.encode())}
    assert stands({**mine, "rotor/tower/availability": b"online"}) is None
    old = {"rotor/tower/info": b'{"id":"tower"}', "rotor/tower/availability": b"online"}
    assert stands(old) is None  # an older bridge's info names no instance


def test_a_rotators_info_is_never_a_bridges_nor_a_bridges_info_a_rotators() -> None:
    """Review 77: a rotator's ``R/info`` names no bridge to rules 2 and 4; a bridge's info
    where rule 5 looks for a rotator's (``rotor/bridge/info``, a bridge on ``rotor``, read by
    one on ``rotor/bridge``) is a bridge's, live by its state beside it."""
    assert Instance.parse(ROTATOR) is None and Instance.stamped(ME.info([]).encode()) is None
    on_rotor = {"rotor/bridge/info": OTHER.info([]).encode(), "rotor/bridge/state": b"online"}
    found = standing(ME, "rotor/bridge", (Post("rotor/bridge/info"),), on_rotor)
    assert found is not None and (found.other, found.base, found.live) == (OTHER, "rotor", True)
    lone = {"rotor/bridge/info": ROTATOR.replace(b'"rotor"', b'"rotor/bridge"')}
    lone["rotor/bridge/availability"] = b"online"  # a bridge on rotor/bridge, read by one on rotor
    found = standing(ME, "rotor", (Post("rotor/bridge/info"),), lone)
    assert found is not None and (found.base, found.live) == ("rotor/bridge", True)


def test_a_stamp_of_this_installation_under_another_instance_id_never_stands() -> None:
    """Review 82: the default client id changes with the base topic; the stamp's
    ``installation`` does not. This installation's own ``R/info`` from its run on ``rotor``
    (another client id) refuses nothing; another installation's, or a stamp naming none,
    still does."""
    here = replace(ME, installation="0a1b2c3d4e5f")
    old = ROTATOR.replace(b'"rotor"}', b'"rotor","installation":"0a1b2c3d4e5f"}')
    seen = {"rotor/tower/info": old, "rotor/tower/availability": b"online"}
    assert Instance.stamped(old) is not None
    assert standing(here, "rotor/tower", POSTS, seen) is None
    for other in (ROTATOR, old.replace(b"0a1b2c3d4e5f", b"ffffffffffff")):
        seen["rotor/tower/info"] = other
        found = standing(here, "rotor/tower", POSTS, seen)
        assert found is not None and (found.other.id, found.live) == (OTHER.id, True)


def test_a_rotator_offline_stands_live_when_its_bridge_above_says_online() -> None:
    """Review 77: a live bridge's rotator whose controller is off says ``offline``; the bridge
    info above (``rotor/bridge/info``, read on an ``above`` post) naming the stamp's instance,
    ``online`` beside it, makes it live. Another instance's info there, or its state not
    ``online``, does not; and what stands above never refuses by itself."""
    posts = (*POSTS, Post("rotor/bridge/info", above=True))
    off = {"rotor/tower/info": ROTATOR, "rotor/tower/availability": b"offline"}
    above = {"rotor/bridge/info": OTHER.info([]).encode(), "rotor/bridge/state": b"online"}
    found = standing(ME, "rotor/tower", posts, {**off, **above})
    assert found is not None and (found.other.id, found.beside, found.live) == (
        OTHER.id,
        "rotor/bridge/state",
        True,
    )
    assert "rotor/bridge/state says online" in refusal_on(found)
    stranger = Instance("rotor-else-000000", "else", 1, 1.0).info([]).encode()
    for seen in (
        {**off, **above, "rotor/bridge/info": stranger},
        {**off, **above, "rotor/bridge/state": b"offline"},
    ):
        found = standing(ME, "rotor/tower", posts, seen)
        assert found is not None and not found.live
    assert standing(ME, "rotor/tower", posts, above) is None  # above alone refuses nothing


def test_a_forged_online_above_never_vouches_for_a_stamp_its_bridge_stopped() -> None:
    """Review 85: a bridge stopped cleanly stamps its rotators' ``R/info`` ``stopped``; an
    ``online`` forged on the bridge state above (a client kept off our topics) never makes
    that leftover live. The same stamp from a running bridge (its controller off) is vouched
    for as ever."""
    posts = (*POSTS, Post("rotor/bridge/info", above=True))
    above = {"rotor/bridge/info": OTHER.info([]).encode(), "rotor/bridge/state": b"online"}
    left = stopped(ROTATOR.decode()).encode()
    assert stamp_stopped(left) and not stamp_stopped(ROTATOR)
    assert Instance.stamped(left) == Instance.stamped(ROTATOR)
    assert stopped("junk") == "junk" and stopped('{"id":"x"}') == '{"id":"x"}'
    seen = {"rotor/tower/info": left, "rotor/tower/availability": b"offline", **above}
    found = standing(ME, "rotor/tower", posts, seen)
    assert found is not None and not found.live
    found = standing(ME, "rotor/tower", posts, {**seen, "rotor/tower/info": ROTATOR})
    assert found is not None and found.live


def test_a_rotator_of_a_bridge_on_this_base_topic_is_left_to_rules_2_and_4() -> None:
    """Review 77: a computer killed outright on ``rotor`` left its rotators' ``R/info`` and
    ``online``; the station that took ``rotor`` over (its own ``B/bridge/info`` there now) is
    not refused by them."""
    seen = {"rotor/tower/info": ROTATOR, "rotor/tower/availability": b"online"}
    assert (
        standing(ME, "rotor", (Post("rotor/bridge/info"), Post("rotor/tower/info")), seen) is None
    )


def test_a_gone_instance_stands_nowhere_whatever_its_rotators_say() -> None:
    """Rule 5: a rotator that said ``offline`` (a clean stop), or an instance whose bridge info
    on the same base topic says it is not online (its last will), is gone: found, not
    standing; gone on that base topic alone (review 77: a live station's old bridge state on a
    base topic it ran on before)."""
    offline = {"rotor/tower/info": ROTATOR, "rotor/tower/availability": b"offline"}
    assert stands(offline) == ("rotor-tower-9f8e7d", "rotor/tower/availability", False)
    below = ROTATOR.replace(b'"rotor"', b'"rotor/tower/x"')
    posts = (Post("rotor/tower/x/bridge/info"), Post("rotor/tower/x/info"))
    killed = {  # its last will on its bridge state; its rotator's availability left online
        "rotor/tower/x/bridge/info": OTHER.info([]).encode(),
        "rotor/tower/x/bridge/state": b"offline",
        "rotor/tower/x/info": below,
        "rotor/tower/x/availability": b"online",
    }
    found = standing(ME, "rotor/tower", posts, killed)
    assert found is not None and not found.live
    moved = {  # its old bridge state, where it ran before; its rotator live on rotor
        "rotor/tower/bridge/info": OTHER.info([]).encode(),
        "rotor/tower/bridge/state": b"offline",
        "rotor/tower/info": ROTATOR,
        "rotor/tower/availability": b"online",
    }
    assert stands(moved) == ("rotor-tower-9f8e7d", "rotor/tower/availability", True)


def test_the_refusal_on_a_post_names_the_other_and_the_topic() -> None:
    seen = {"rotor/tower/bridge/info": OTHER.info([]).encode()}
    found = standing(ME, "rotor/tower", POSTS, {**seen, "rotor/tower/bridge/state": b"online"})
    assert found is not None
    text = refusal_on(found)
    assert "rotor-tower-9f8e7d" in text and "'rotor/tower/bridge/info'" in text
    assert "mqtt.base_topic" in text and "\n" not in text


def test_the_installation_hashes_the_state_files_resolved_path(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Review 85: ``state_file = "state.json"`` run from two directories is two installations;
    the same file named through a link, or relative from its own directory, is one."""
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "a")
    monkeypatch.chdir(tmp_path / "a")
    here = installation("state.json")
    assert here == installation(tmp_path / "a" / "state.json")
    assert here == installation(tmp_path / "link" / "state.json")
    monkeypatch.chdir(tmp_path / "b")
    assert installation("state.json") != here


def test_the_look_reads_the_bridge_posts_on_the_base_topic_a_stamp_names() -> None:
    """Review 85: a live bridge on ``shack`` whose rotator has ``topic = "rotor/tower"`` (its
    controller off: ``offline``) is vouched for by ``shack/bridge/info`` and ``state``, read
    once the stamp is seen (``vouch_reads``); nothing is read for a rotator ``online``, a
    stopped stamp, or one of this bridge's base topic."""
    claim = Claim(ME, "rotor/tower", "rotor/tower/bridge/info", "rotor/tower/bridge/hello", POSTS)
    on_shack = ROTATOR.replace(b'"rotor"}', b'"shack"}')
    seen = {"rotor/tower/info": on_shack, "rotor/tower/availability": b"offline"}
    assert vouch_reads(claim, seen) == ["shack/bridge/info", "shack/bridge/state"]
    assert vouch_reads(claim, {**seen, "rotor/tower/availability": b"online"}) == []
    assert (
        vouch_reads(claim, {**seen, "rotor/tower/info": stopped(on_shack.decode()).encode()}) == []
    )
    mine = on_shack.replace(b'"shack"}', b'"rotor/tower"}')
    assert vouch_reads(claim, {**seen, "rotor/tower/info": mine}) == []
    above = {"shack/bridge/info": OTHER.info([]).encode(), "shack/bridge/state": b"online"}
    found = standing(ME, "rotor/tower", POSTS, {**seen, **above})
    assert found is not None and found.live and found.beside == "shack/bridge/state"


@pytest.mark.parametrize(
    "base",
    ["#", "rotor/+", "\ud800", "a\x00b", "$SYS", "x" * 70000],
    ids=["hash", "plus", "surrogate", "nul", "dollar", "past-mqtt-length"],
)
def test_a_stamp_naming_a_base_topic_no_bridge_could_have_is_no_stamp(base: str) -> None:
    """Review 94: a stamp's base topic is read as a topic (its vouch reads are subscribed): one
    the configuration would refuse as a base topic (a wildcard, a lone surrogate, a NUL, '$',
    past MQTT's length) is junk, no bridge's stamp: nothing is read for it, it stands nowhere,
    and ``unusable_stamp`` says why, for the log."""
    claim = Claim(ME, "rotor/tower", "rotor/tower/bridge/info", "rotor/tower/bridge/hello", POSTS)
    forged = json.dumps({"id": "tower", "bridge": {"instance": OTHER.id, "base_topic": base}})
    seen = {"rotor/tower/info": forged.encode(), "rotor/tower/availability": b"online"}
    assert Instance.stamped(forged.encode()) is None
    assert vouch_reads(claim, {**seen, "rotor/tower/availability": b"offline"}) == []
    assert standing(ME, "rotor/tower", POSTS, seen) is None
    said = unusable_stamp(forged.encode())
    assert said is not None and said[0] == base
    assert unusable_stamp(ROTATOR) is None and unusable_stamp(b"junk") is None
