"""The owned-topic judge (bridge/interfaces/mqtt/owned.py, MQTT rule 10) in virtual time: which
values on the bridge's own topics are its own, when its value is put back, and when that is said."""

from __future__ import annotations

from paho.mqtt.client import topic_matches_sub
from paho.mqtt.subscribeoptions import SubscribeOptions

from bridge.interfaces.mqtt.owned import (
    FOREIGN_FIX_S,
    FOREIGN_LOG_S,
    SETTLE_AFTER_CONNECT_S,
    OwnedTopics,
)
from bridge.interfaces.mqtt.topics import Topics

STATE = "rotor/state"


class Clock:
    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


def judge(hears_own: bool = False) -> tuple[OwnedTopics, Clock]:
    clock = Clock()
    owned = OwnedTopics(clock, hears_own=hears_own)
    owned.watch(["rotor/state", "rotor/option/+/state"])
    owned.connected()
    return owned, clock


def test_the_filters_say_which_topics_are_owned() -> None:
    owned, _ = judge()
    assert owned.owns(STATE) and owned.owns("rotor/option/brake/state")
    assert not owned.owns("rotor/target") and not owned.owns("other/state")


def test_the_value_the_bridge_holds_is_its_own_and_another_is_a_strangers() -> None:
    owned, _ = judge()
    assert owned.ours(STATE, b"idle", held=b"idle")
    assert not owned.ours(STATE, b"turning", held=b"idle")


def test_a_stranger_just_after_a_connect_is_put_back_without_a_word() -> None:
    """What the broker held from before (our own last will) is no news."""
    owned, clock = judge()
    clock.now += SETTLE_AFTER_CONNECT_S / 2
    fix = owned.put_back(STATE, live=True)
    assert fix.send and not fix.say


def test_a_live_stranger_is_put_back_at_most_every_fix_interval_and_said_once_a_minute() -> None:
    owned, clock = judge()
    clock.now += SETTLE_AFTER_CONNECT_S + 1
    first = owned.put_back(STATE, live=True)
    assert first.send and first.say
    clock.now += FOREIGN_FIX_S / 2
    soon = owned.put_back(STATE, live=True)
    assert not soon.send and not soon.say  # a fight with a flow is not a flood from us
    clock.now += FOREIGN_FIX_S
    again = owned.put_back(STATE, live=True)
    assert again.send and not again.say  # put back, but the log heard it this minute
    clock.now += FOREIGN_LOG_S
    later = owned.put_back(STATE, live=True)
    assert later.send and later.say


def test_each_topic_has_its_own_intervals() -> None:
    owned, clock = judge()
    clock.now += SETTLE_AFTER_CONNECT_S + 1
    assert owned.put_back(STATE, live=True).say
    assert owned.put_back("rotor/option/brake/state", live=True).say


def test_under_mqtt_3_1_1_what_the_bridge_sent_comes_back_as_its_own_in_order() -> None:
    """A value it sent before the newest one is no stranger while it is on its way back; once
    the newer one came back, the older one heard again is another client's."""
    owned, _ = judge(hears_own=True)
    owned.sent(STATE, b"turning")
    owned.sent(STATE, b"idle")
    assert owned.ours(STATE, b"turning", held=b"idle")
    assert owned.ours(STATE, b"idle", held=b"idle")
    assert not owned.ours(STATE, b"turning", held=b"idle")


def test_a_new_connection_forgets_what_was_in_flight() -> None:
    owned, clock = judge(hears_own=True)
    owned.sent(STATE, b"turning")
    clock.now += 5
    owned.connected()
    assert owned.connected_at == clock.now
    assert not owned.ours(STATE, b"turning", held=b"idle")


def test_mqtt_5_keeps_no_echoes_and_unowned_topics_none_either() -> None:
    v5, _ = judge(hears_own=False)
    v5.sent(STATE, b"turning")
    assert not v5.ours(STATE, b"turning", held=b"idle")
    v311, _ = judge(hears_own=True)
    v311.sent("rotor/target", b"10")
    assert not v311.ours("rotor/target", b"10", held=b"")


def test_mqtt_5_subscribes_without_its_own_messages_and_3_1_1_hears_them() -> None:
    v5, _ = judge(hears_own=False)
    (topic, options), _option = v5.subscriptions()
    assert topic == STATE and not isinstance(options, int) and options.noLocal
    v311, _ = judge(hears_own=True)
    assert v311.subscriptions() == [(STATE, 0), ("rotor/option/+/state", 0)]


def test_under_mqtt_3_1_1_echoes_far_behind_a_flood_are_still_the_bridges_own() -> None:
    """The main connection reads a flood of targets before the bridge's own status messages
    come back: thousands of them are in flight, and each is still known as its own."""
    owned, _ = judge(hears_own=True)
    sent = [f'{{"bearing": {i}}}'.encode() for i in range(5000)]
    for data in sent:
        owned.sent(STATE, data)
    held = sent[-1]
    assert all(owned.ours(STATE, data, held) for data in sent)
    # every echo heard: a value sent before is a stranger's now (only the held one is ours)
    assert not owned.ours(STATE, sent[0], held)
    assert owned.ours(STATE, held, held)


def test_under_mqtt_3_1_1_a_stranger_among_the_echoes_is_still_a_stranger() -> None:
    owned, _ = judge(hears_own=True)
    for data in (b"moving", b"idle", b"moving"):
        owned.sent(STATE, data)
    assert owned.ours(STATE, b"moving", held=b"moving")
    assert not owned.ours(STATE, b"parked", held=b"moving")  # never sent on this connection
    assert owned.ours(STATE, b"idle", held=b"moving")  # still in flight


def test_the_bridges_own_last_will_is_known_under_mqtt_3_1_1_only() -> None:
    owned, _ = judge(hears_own=True)
    owned.will = ("rotor/bridge/state", b"offline")
    assert owned.is_will("rotor/bridge/state", b"offline")
    assert not owned.is_will("rotor/bridge/state", b"online")
    owned.hears_own = False  # MQTT 5 subscribes with no-local: the broker never sends it to us
    assert not owned.is_will("rotor/bridge/state", b"offline")


def test_owned_topics_are_those_mqtt_matches_for_every_kind_of_filter() -> None:
    """The set and the compiled pattern answer as paho's matcher does, one filter at a time: a
    table of filters (the bridge's own, several rotators' with their ``option/+/state``, and the
    other wildcard forms) against topics at the edges (``$`` topics, empty levels, a parent of
    ``#``, a level too many or too few)."""
    own = Topics("rotor", {f"r{i}": f"rotor/r{i}" for i in range(3)}).owned()
    others = ["a/#", "#", "+", "+/b", "+/+/c", "$SYS/#", "$SYS/+/x", "x/+", "x/#/y", "a.b/c*d"]
    filters = own + others
    topics = {t.replace("+", "brake").replace("/#", "/x") for t in filters}
    topics |= {t.replace("/+", "").replace("#", "") for t in filters}
    topics |= {
        "", "/", "a", "a/", "a/b/c", "b", "/b", "x/b", "q/w/c", "q//c", "$SYS", "$SYS/x",
        "$SYS/q/x", "$x/b", "$x", "x", "x/", "x/y", "x/#/y", "x/q/y", "a.b/c*d", "aXb/c*d",
        "rotor/r1/option//state", "rotor/r1/option/a/b/state", "rotor/r1/state/x",
        "rotor/r9/state", "rotor/r1/option/brake", "rotor/r1/option/brake/state\n",
    }  # fmt: skip
    for chosen in (own, others, filters, [], ["a/b"]):
        owned = OwnedTopics(Clock(), hears_own=False)
        owned.watch(chosen)
        for topic in sorted(topics):
            expected = any(topic_matches_sub(f, topic) for f in chosen)
            assert owned.owns(topic) == expected, (topic, chosen[:3])
    owned.watch(own)
    assert owned.owns("rotor/r2/option/brake/state") and not owned.owns("rotor/r2/target")


def test_a_stranger_within_the_fix_interval_is_put_back_once_it_is_over() -> None:
    """A review: a second stray ``lock/state OFF`` within FOREIGN_FIX_S of the first was never
    put back, and stayed on the broker for as long as the lock stayed on."""
    owned, clock = judge()
    clock.now += SETTLE_AFTER_CONNECT_S + 1
    assert owned.put_back(STATE, live=True).send
    clock.now += FOREIGN_FIX_S / 2
    assert not owned.put_back(STATE, live=True).send
    assert owned.owing and owned.owed() == []  # not yet: the interval is not over
    clock.now += FOREIGN_FIX_S / 2
    assert owned.owed() == [STATE]
    assert not owned.owing and owned.owed() == []  # once
    clock.now += FOREIGN_FIX_S / 2
    assert not owned.put_back(STATE, live=True).send  # the owed put-back counts as one


def test_a_value_the_broker_held_within_the_fix_interval_is_not_owed() -> None:
    """A held value (its retain flag set: the broker answered a subscription with it) that comes
    within FOREIGN_FIX_S is older than the put-back already sent: putting it back again would
    tell every subscriber the bridge's value a second time."""
    owned, clock = judge()
    assert owned.put_back(STATE, live=False, settling=True).send
    clock.now += FOREIGN_FIX_S / 2
    assert not owned.put_back(STATE, live=False).send
    assert not owned.owing
    clock.now += FOREIGN_FIX_S
    assert owned.owed() == []


def test_mqtt5_hears_its_own_topics_with_the_retain_flag_of_the_delivery() -> None:
    """Live from held (owned.py rule 10): MQTT 5 subscribes without retain-as-published, so a
    value another client publishes while the bridge listens comes with the retain flag clear."""
    owned, _clock = judge()
    for _topic, opts in owned.subscriptions():
        assert isinstance(opts, SubscribeOptions)
        assert opts.noLocal and not opts.retainAsPublished


def test_nothing_is_owed_once_the_bridge_has_sent_its_value_again() -> None:
    """A review: an owed put-back outlived a reconnect (which sends every value again) and the
    bridge's own new value (the lock released meanwhile): every subscriber was told twice."""
    owned, clock = judge()
    clock.now += SETTLE_AFTER_CONNECT_S + 1
    assert owned.put_back(STATE, live=True).send
    assert not owned.put_back(STATE, live=True).send and owned.owing
    owned.connected()  # a new connection
    clock.now += FOREIGN_FIX_S
    assert owned.owed() == []
    clock.now += SETTLE_AFTER_CONNECT_S + FOREIGN_FIX_S
    assert owned.put_back(STATE, live=True).send
    assert not owned.put_back(STATE, live=True).send and owned.owing
    owned.sent(STATE, b"idle")  # the bridge's own new value
    clock.now += FOREIGN_FIX_S
    assert owned.owed() == []
