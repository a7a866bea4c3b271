"""What a removed rotator or group left retained (interfaces/mqtt/stale.py): which messages
name a root no longer configured, and which topics are then deleted. Pure."""

from __future__ import annotations

from bridge.interfaces.mqtt.service import never_published
from bridge.interfaces.mqtt.stale import StaleTopics
from bridge.interfaces.mqtt.topics import RotatorTopics, Topics
from bridge.protocols import REGISTRY
from bridge.protocols.axes import Axis, axis_spec, composite_spec


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
    # (review 85: the group's G/info is one of the bridge's own topics: handed here first)
    assert stale.peeked == ["rotor/stack/info"]
    doomed = stale.stale("rotor/stack/info", b'{"id":"stack","model":"gs232b"}')
    for leaf in ("bearing", "state", "lock/state", "presets", "control"):
        assert f"rotor/stack/{leaf}" in doomed
    assert "rotor/stack/status" not in doomed and "rotor/stack/availability" not in doomed
    assert "rotor/stack/info" not in doomed  # (the group's own G/info is put over it)
    own = b'{"group":"stack","name":"Stack","members":["a","b"]}'  # (claim rule 5)
    assert stale.stale("rotor/stack/info", own) == []
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


def test_a_state_a_configured_rotator_no_longer_publishes_is_deleted_by_itself() -> None:
    """Rule 5: ``R/tracking`` of a rotator whose station was taken out; its other topics and
    another rotator's tracking are left."""
    topics = Topics("rotor", {"a": "rotor/a", "b": "rotor/b"})
    stale = StaleTopics(topics, {"rotor/a", "rotor/b"}, unpublished={"rotor/a/tracking"})
    assert not [s for s in stale.subscriptions if s.endswith("/tracking")]  # (rule 10 reads it)
    assert stale.stale("rotor/a/tracking") == ["rotor/a/tracking"]
    assert stale.stale("rotor/b/tracking") == []
    assert stale.stale("rotor/a/availability") == []


def test_a_status_topic_a_configured_rotator_s_model_never_fills_is_deleted_by_itself() -> None:
    """Rule 5, a review: a controller swapped for another model left the old one's
    ``R/elevation``, ``R/version`` and ``R/bearing`` retained for ever; read through the owned-
    topic watch (no filter of its own), each is deleted by itself, and nothing else is."""
    topics = Topics("rotor", {"a": "rotor/a", "b": "rotor/b"})
    gone = {"rotor/a/elevation", "rotor/a/version", "rotor/a/bearing"}
    stale = StaleTopics(topics, {"rotor/a", "rotor/b"}, unpublished=gone)
    assert not gone & set(stale.subscriptions)  # (client.py rule 10 reads them)
    for topic in gone:
        assert stale.stale(topic) == [topic]
    for topic in ("rotor/b/elevation", "rotor/b/version", "rotor/a/state", "rotor/a/status"):
        assert stale.stale(topic) == [], topic


def test_an_option_state_a_configured_rotator_s_model_has_not_is_deleted_by_itself() -> None:
    """Rule 5: a Rotor-EZ's ``R/option/jam/state`` once the rotator is a GS-232B (whose one
    option is ``speed``); its speed, a rotator that still has jam, and its lock are left."""
    topics = Topics("rotor", {"a": "rotor/a", "option": "rotor/option"})
    options = {"rotor/a": ("speed",), "rotor/option": ("jam",)}
    stale = StaleTopics(topics, {"rotor/a", "rotor/option"}, options=options)
    assert stale.stale("rotor/a/option/jam/state") == ["rotor/a/option/jam/state"]
    assert stale.stale("rotor/a/option/speed/state") == []
    assert stale.stale("rotor/option/option/jam/state") == []
    assert stale.stale("rotor/option/lock/state") == []  # (its own lock: rule 3)
    assert stale.stale("rotor/a/option/jam") == []  # (a command topic)
    one = StaleTopics(Topics("rotor", {"tower": "rotor"}), {"rotor"}, options={"rotor": ()})
    assert one.stale("rotor/option/jam/state") == ["rotor/option/jam/state"]  # (on the base)


def test_what_a_model_publishes_is_never_among_the_topics_it_never_fills() -> None:
    """Rule 5's other edge (interfaces/mqtt/service.py ``never_published``): an MD-01's and a
    composite rotator's elevation, a composite's version joined from its boxes', a Rotor-EZ's
    version (however late it comes) stay; a DCU-1 fills neither bearing, elevation nor version."""
    t = RotatorTopics("rotor/a")
    assert never_published(t, REGISTRY["md01"]) == [t.version]
    assert never_published(t, REGISTRY["rotorez"]) == [t.elevation]
    assert never_published(t, REGISTRY["dcu1"]) == [t.bearing, t.elevation, t.version]
    az, el = REGISTRY["rotorez"], REGISTRY["easycomm3"]
    both = composite_spec(az, el)
    assert (
        never_published(t, both, (axis_spec(az, Axis.AZIMUTH), axis_spec(el, Axis.ELEVATION))) == []
    )
    quiet = (axis_spec(REGISTRY["rt21"], Axis.AZIMUTH), axis_spec(REGISTRY["md01"], Axis.ELEVATION))
    assert never_published(t, composite_spec(REGISTRY["rt21"], REGISTRY["md01"]), quiet) == [
        t.version
    ]
