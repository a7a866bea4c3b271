"""What a removed rotator or group left retained (interfaces/mqtt/stale.py): which messages
name a root no longer configured, and which topics are then deleted. Pure."""

from __future__ import annotations

from bridge.interfaces.mqtt.stale import StaleTopics
from bridge.interfaces.mqtt.topics import Topics


def several() -> StaleTopics:
    topics = Topics("rotor", {"a": "rotor/a", "b": "rotor/b"}, {"stack": "rotor/stack"})
    return StaleTopics(topics, {"rotor/a", "rotor/b", "rotor/stack"})


def test_a_removed_rotator_s_availability_deletes_everything_a_rotator_keeps_there() -> None:
    doomed = several().stale("rotor/c/availability")
    for leaf in ("availability", "bearing", "elevation", "state", "status", "version"):
        assert f"rotor/c/{leaf}" in doomed
    for leaf in ("presets", "info", "lock/state", "control", "health"):
        assert f"rotor/c/{leaf}" in doomed
    assert all(t.startswith("rotor/c/") for t in doomed)
    assert "rotor/c/target" not in doomed and "rotor/c/stop" not in doomed  # (commands)


def test_a_removed_rotator_s_option_state_is_deleted_by_itself() -> None:
    assert several().stale("rotor/c/option/jam/state") == ["rotor/c/option/jam/state"]


def test_what_the_bridge_has_now_is_never_stale() -> None:
    stale = several()
    for topic in (
        "rotor/a/availability",
        "rotor/b/option/jam/state",
        "rotor/stack/availability",  # a group's
        "rotor/bridge/state",
        "rotor/a/bearing",  # (no filter reads it)
        "elsewhere/c/availability",  # not under the base topic
        "rotor/c/d/availability",  # nor a root of it
    ):
        assert stale.stale(topic) == [], topic


def test_one_rotator_s_topics_on_the_base_topic_are_stale_once_there_are_several() -> None:
    doomed = several().stale("rotor/availability")
    assert "rotor/bearing" in doomed and "rotor/lock/state" in doomed
    assert not any(t.startswith("rotor/bridge/") for t in doomed)
    assert several().stale("rotor/option/jam/state") == ["rotor/option/jam/state"]


def test_with_one_rotator_on_the_base_topic_its_own_are_not_stale() -> None:
    topics = Topics("rotor", {"tower": "rotor"})
    stale = StaleTopics(topics, {"rotor"})
    assert stale.stale("rotor/availability") == []
    assert stale.stale("rotor/option/jam/state") == []
    assert "rotor/tower/bearing" in stale.stale("rotor/tower/availability")  # of several, once


def test_a_rotator_named_option_keeps_its_lock_and_feature_states() -> None:
    """review 93: a rotator whose id is ``option`` (several rotators, so its root is
    ``rotor/option``) publishes ``rotor/option/lock/state`` and ``rotor/option/follow/state``;
    ``rotor/option/+/state`` reads them as option states of a rotator once on the base topic,
    and the first look deleted the configured rotator's lock state (and took it out of the
    client's cache: it was not put back)."""
    topics = Topics("rotor", {"option": "rotor/option", "b": "rotor/b"})
    stale = StaleTopics(topics, {"rotor/option", "rotor/b"})
    assert stale.stale("rotor/option/lock/state") == []
    assert stale.stale("rotor/option/follow/state") == []
    assert stale.stale("rotor/option/jam/state") == ["rotor/option/jam/state"]  # (still stale)


def test_another_bridge_on_a_base_topic_nested_under_ours_is_left_alone() -> None:
    """review 93: a second bridge on ``rotor/site2`` with one rotator keeps its state on
    ``rotor/site2/...`` and says so on ``rotor/site2/bridge/state``; this bridge (base
    ``rotor``) read ``rotor/site2/availability`` as a removed rotator's and deleted the other
    bridge's bearing, state, status, lock and options."""
    stale = several()
    assert "rotor/+/bridge/state" in stale.subscriptions
    # its retained bridge state comes first (its filter is subscribed before the others)
    assert stale.subscriptions.index("rotor/+/bridge/state") < stale.subscriptions.index(
        "rotor/+/availability"
    )
    assert stale.stale("rotor/site2/bridge/state") == []
    assert stale.stale("rotor/site2/availability") == []
    assert stale.stale("rotor/site2/option/jam/state") == []
    assert "rotor/site3/bearing" in stale.stale("rotor/site3/availability")  # (still stale)


def test_a_rotator_replaced_by_a_group_of_its_id_leaves_no_ghost() -> None:
    """review 93, rule 4: rotator ``stack`` removed and a group ``stack`` added: the root's
    availability is the group's, and the rotator's bearing, lock, options and ``R/info`` (by
    which a remote finds rotators) stayed for ever."""
    stale = StaleTopics(
        Topics("rotor", {"a": "rotor/a", "b": "rotor/b"}, {"stack": "rotor/stack"}),
        {"rotor/a", "rotor/b", "rotor/stack"},
        {"rotor/stack"},
    )
    assert "rotor/stack/info" in stale.subscriptions
    doomed = stale.stale("rotor/stack/info")
    for leaf in ("info", "bearing", "state", "lock/state", "presets", "control"):
        assert f"rotor/stack/{leaf}" in doomed
    assert "rotor/stack/status" not in doomed and "rotor/stack/availability" not in doomed
    assert stale.stale("rotor/stack/option/jam/state") == ["rotor/stack/option/jam/state"]
    assert stale.stale("rotor/stack/availability") == []  # (the group's own)
    assert stale.stale("rotor/a/option/jam/state") == []


def test_another_bridge_s_base_topic_is_spared_whichever_came_first() -> None:
    """Rule 3: the nested bridge's availability may come before its ``bridge/state`` (a broker
    need not send retained messages in the order of the filters): what it asked to delete is
    spared at the look's end, once both have come."""
    stale = several()
    doomed = stale.stale("rotor/site2/availability")  # first: looks like a removed rotator's
    assert "rotor/site2/bearing" in doomed
    assert stale.stale("rotor/site2/bridge/state") == []
    assert all(stale.spared(t) for t in doomed)
    assert not stale.spared("rotor/c/bearing")
