"""The first look's books (bridge/interfaces/mqtt/look.py, MQTT rule 14), without a broker: what a
look saw decides whether stale discovery is deleted, left alone, or the bridge refuses to run."""

from __future__ import annotations

import logging

import pytest

from bridge.interfaces.mqtt.claim import Claim, Instance
from bridge.interfaces.mqtt.limiter import EventLimiter
from bridge.interfaces.mqtt.look import FirstLook
from bridge.interfaces.mqtt.topics import Topics
from tests.support.clock import FakeClock

ME = Instance("rotor-me", "shack", 100, 1000.0)
OTHER = Instance("rotor-other", "attic", 200, 900.0)
INFO, STATE, HELLO = "t/bridge/info", "t/bridge/state", "t/bridge/hello"
STALE = "homeassistant/sensor/rotorbridge_t_r_gone/bearing/config"


def look() -> FirstLook:
    return FirstLook(Claim(ME, "t", INFO, HELLO), STATE)


def test_its_own_hello_ends_the_look_and_no_other() -> None:
    lk = look()
    hello = lk.begin()
    assert hello == b"rotor-me 1"
    assert lk.ended_by(b"rotor-other 1") is None  # another bridge's look
    assert lk.ended_by(b"rotor-me 0") is None  # one of an earlier look, come late
    assert lk.ended_by(hello) == 1


def test_a_base_topic_of_its_own_deletes_what_the_broker_held() -> None:
    lk = look()
    lk.begin()
    assert lk.saw(INFO, ME.info([]).encode()) and lk.saw(STATE, b"offline")
    assert lk.defer_clear(STALE)
    outcome = lk.end(timed_out=False)
    assert (outcome.refused, outcome.clear, outcome.clears) == (None, True, [STALE])
    assert not lk.defer_clear(STALE)  # the look is over: the client judges it now


def test_another_live_bridge_is_a_refusal_naming_it() -> None:
    lk = look()
    lk.begin()
    lk.saw(INFO, OTHER.info([]).encode())
    lk.saw(STATE, b"online")
    outcome = lk.end(timed_out=False)
    assert outcome.refused is not None and "rotor-other" in outcome.refused
    assert outcome.clears == []


def test_after_taking_over_or_a_look_that_timed_out_nothing_is_deleted() -> None:
    lk = look()
    lk.begin()
    lk.saw(INFO, OTHER.info([]).encode())
    lk.saw(STATE, b"offline")  # gone: taken over
    lk.defer_clear(STALE)
    taken = lk.end(timed_out=False)
    assert (taken.refused, taken.clear, taken.clears) == (None, False, [STALE])
    lk.begin()  # a reconnect: the base topic looks like ours now, but was not at first
    lk.saw(INFO, ME.info([]).encode())
    lk.defer_clear(STALE)
    assert not lk.end(timed_out=False).clear
    blind = look()
    blind.begin()
    blind.defer_clear(STALE)
    assert not blind.end(timed_out=True).clear  # nothing known: delete nothing


def test_only_info_and_state_belong_to_the_look_and_only_while_it_runs() -> None:
    lk = look()
    assert not lk.saw(INFO, b"{}")  # no look under way
    lk.begin()
    assert not lk.saw("t/bearing", b"10")


def test_a_younger_live_bridge_yields_to_an_older_one() -> None:
    lk = look()
    assert lk.live_info(OTHER.info([]).encode()) is not None  # OTHER started earlier
    younger = Instance("rotor-young", "attic", 300, 2000.0)
    assert lk.live_info(younger.info([]).encode()) is None
    assert lk.live_info(ME.info([]).encode()) is None


LOCK = "t/r/lock/state"


def test_the_first_look_that_lets_the_bridge_run_hands_on_what_an_earlier_run_said() -> None:
    """Rule 14 (runtime/kept.py rule 10): a rotator's retained lock state seen during the look
    is handed on once, by the first look that opens; it stays the owned-topic judge's too."""
    lk = look()
    lk.witness({LOCK})
    assert not lk.saw(LOCK, b"ON")  # no look under way: nothing kept
    lk.begin()
    assert not lk.saw(LOCK, b"ON")  # kept, and left to the owned-topic judge (rule 10)
    lk.saw(INFO, OTHER.info([]).encode())
    lk.saw(STATE, b"online")
    assert lk.end(timed_out=False).heard is None  # refused: nothing runs, nothing handed on
    lk.begin()
    assert not lk.saw(LOCK, b"ON")
    lk.saw(STATE, b"offline")  # (the other one is gone now)
    assert lk.end(timed_out=False).heard == {LOCK: b"ON"}
    lk.begin()  # a reconnect: what the broker holds now is this run's own
    lk.saw(LOCK, b"OFF")
    assert lk.end(timed_out=False).heard is None


def test_a_look_that_timed_out_hands_on_what_it_saw() -> None:
    """An ACL that denies the hello leaves the look to its timeout: the lock it saw counts."""
    lk = look()
    lk.witness({LOCK})
    lk.begin()
    lk.saw(LOCK, b"ON")
    lk.saw("t/r/lock", b"ON")  # (no witness: not kept)
    assert lk.end(timed_out=True).heard == {LOCK: b"ON"}


def test_a_witness_the_broker_replays_after_the_hello_is_handed_on_on_that_connection_only() -> (
    None
):
    """Rule 14: aedes streams a subscription's retained messages beside what follows, so the
    lock ON an earlier run left can come after the hello; retained, on the connection of the
    look that opened, it is handed on still. A live value, a later connection's, or one before
    any look opened is not."""
    lk = look()
    lk.witness({LOCK})
    assert lk.late(LOCK, b"ON", retained=True) == {}  # no look has opened yet
    lk.begin()
    assert lk.end(timed_out=False).heard == {}  # the hello came back before the replay
    assert lk.late(LOCK, b"ON", retained=True) == {LOCK: b"ON"}
    assert lk.late(LOCK, b"ON", retained=False) == {}  # live: a stranger's, or the bridge's
    assert lk.late(STATE, b"offline", retained=True) == {}  # no witness
    lk.connection_ended()
    lk.begin()  # a reconnect: what the broker holds now is this run's own
    assert lk.end(timed_out=False).heard is None
    assert lk.late(LOCK, b"ON", retained=True) == {}


def test_the_first_look_that_opens_says_so_when_the_broker_held_nothing() -> None:
    """Rule 14: an empty hand-over, not none: the rotators that waited for it may move."""
    lk = look()
    lk.witness({LOCK})
    lk.begin()
    assert lk.end(timed_out=False).heard == {}
    lk.begin()
    assert lk.end(timed_out=False).heard is None


def test_a_deletion_asked_twice_in_one_look_is_sent_and_named_once() -> None:
    """A topic two overlapping filters read (a configured rotator's option state: rule 1's
    ``B/+/option/+/state`` and the owned-topic watch, interfaces/mqtt/stale.py rule 5) is
    asked to be deleted twice: it was sent and named twice."""
    lk = look()
    lk.begin()
    lk.saw(INFO, ME.info([]).encode())
    jam = "t/a/option/jam/state"
    for topic in (jam, STALE, jam):
        assert lk.defer_clear(topic)
    assert lk.end(timed_out=False).clears == [jam, STALE]


NEAR_INFO, NEAR_STATE = "t/tower/bridge/info", "t/tower/bridge/state"  # (claim rule 5)
A = Instance("rotor-a", "attic", 200, 900.0, ("t/tower", "t/yagi"))  # base "t", older
TOWER = Instance("rotor-me", "shack", 100, 1000.0, ("t/tower",))  # base "t/tower", one rotator


# claim rule 6: the R/info on t/tower, this bridge's one rotator's ("mast") or A's tower's
EVIDENCE = "t/tower/info"
MAST_INFO, A_TOWER_INFO = b'{"id":"mast","name":"Mast"}', b'{"id":"tower","name":"Tower"}'


def tower_look(said: EventLimiter | None = None) -> FirstLook:
    hello = "t/tower/bridge/hello"
    names = Topics("t", {}).names()
    claim = Claim(
        TOWER, "t/tower", NEAR_INFO, hello, names, rotator_ids=frozenset({"mast", "dish"})
    )
    return FirstLook(claim, NEAR_STATE, said)


def test_a_live_bridge_whose_rotator_topic_is_this_ones_base_topic_refuses_its_first_look() -> None:
    """Claim rule 5 (attack 18): base ``t/tower`` beside a live bridge on ``t`` whose rotator
    ``tower`` is ``t/tower``: its info and state on ``t/bridge/`` are read and, with its
    rotator's ``R/info`` on ``t/tower`` (rule 6: ``t`` is outside this bridge's tree), refuse."""
    lk = tower_look()
    assert lk.near_topics == [INFO, STATE, EVIDENCE]
    lk.begin()
    assert lk.saw(INFO, A.info([]).encode()) and lk.saw(STATE, b"online")
    assert not lk.saw(EVIDENCE, A_TOWER_INFO)  # (left to the owned topics' judge too)
    outcome = lk.end(timed_out=False)
    assert outcome.refused is not None and "rotor-a" in outcome.refused
    assert "mqtt.base_topic 't/tower'" in outcome.refused


def test_a_gone_bridges_leftovers_and_a_bridge_beside_this_ones_topics_never_refuse() -> None:
    for info, state in [
        (A.info([]), b"offline"),  # a clean stop, or its last will
        (A.info([]), None),  # no state at all
        (Instance("rotor-b", "h", 1, 1.0, ("t/mast",)).info([]), b"online"),  # its own
        (Instance("rotor-c", "h", 1, 1.0, ("t",)).info([]), b"online"),  # one rotator on t
        (TOWER.info([]), b"online"),  # this installation's, an earlier configuration
    ]:
        lk = tower_look()
        lk.begin()
        lk.saw(INFO, info.encode())
        lk.saw(EVIDENCE, A_TOWER_INFO)  # (a rotator of another bridge there, rule 6)
        if state is not None:
            lk.saw(STATE, state)
        assert lk.end(timed_out=False).refused is None, (info, state)


def test_an_overlapping_bridge_met_while_running_the_older_says_it_and_the_younger_yields() -> None:
    lk = tower_look()
    lk.begin()
    lk.saw(EVIDENCE, A_TOWER_INFO)
    lk.end(timed_out=False)
    assert lk.near(INFO, A.info([]).encode()) == (None, False)  # no state yet: not live
    refused, said = lk.near(STATE, b"online")  # A is older: this one yields
    assert refused is not None and "rotor-a" in refused and not said
    lk = tower_look()
    lk.begin()
    lk.saw(EVIDENCE, A_TOWER_INFO)
    lk.end(timed_out=False)
    young = Instance("rotor-young", "attic", 300, 2000.0, ("t/tower",))
    lk.near(STATE, b"online")
    assert lk.near(INFO, young.info([]).encode()) == (None, True)  # said, goes on
    assert len(lk.saying) == 1 and "rotor-young" in lk.saying[0]
    assert lk.near(INFO, young.info(["x"]).encode()) == (None, False)  # said already
    assert lk.near(STATE, b"offline") == (None, True) and lk.saying == []  # gone: unsaid
    lk.near(STATE, b"online")
    assert lk.saying
    lk.begin()  # a reconnect's look: said, not refused (this one ran, and is the older)
    lk.saw(EVIDENCE, A_TOWER_INFO)  # (the broker hands it over again)
    lk.saw(INFO, young.info([]).encode())
    lk.saw(STATE, b"online")
    assert lk.end(timed_out=False).refused is None and len(lk.saying) == 1


def test_an_info_above_the_base_topic_is_believed_only_with_another_rotator_on_it() -> None:
    """Claim rule 6 (review 67): ``t/bridge/info`` is outside this bridge's tree (``t/tower``),
    where a client the ACL keeps off it may write: an online info there naming ``t/tower``,
    older, refuses nothing and ends nothing, unless the ``R/info`` on ``t/tower`` is another
    rotator's (a bridge's own rotator's info is written inside this bridge's tree)."""
    forged = Instance("rotor-forged", "nowhere", 1, 1.0, ("t/tower",))
    dish = b'{"id":"dish"}'  # (its one rotator on t/tower before it had two)
    for held in (None, MAST_INFO, dish, b"", b"junk", b'{"id":7}'):  # none, this bridge's own
        lk = tower_look()
        lk.begin()
        lk.saw(INFO, forged.info([]).encode())
        lk.saw(STATE, b"online")
        if held is not None:
            lk.saw(EVIDENCE, held)
        assert lk.end(timed_out=False).refused is None, held
        assert lk.near(INFO, forged.info(["x"]).encode()) == (None, False), held
        assert lk.saying == []
    # the rotator comes: the younger yields (this one), and says it offline, but A's tower
    lk = tower_look()
    lk.begin()
    lk.saw(INFO, forged.info([]).encode())
    lk.saw(STATE, b"online")
    lk.saw(EVIDENCE, MAST_INFO)
    lk.end(timed_out=False)
    refused, _ = lk.near(EVIDENCE, A_TOWER_INFO)
    assert refused is not None and "rotor-forged" in refused
    assert lk.left_offline() == [NEAR_STATE]  # t/tower/availability: the other's rotator's


def test_a_bridge_from_before_topics_above_the_base_refuses_with_its_rotator_there() -> None:
    """Claim rule 6 (review 67): an info without ``topics`` (a station of the version before
    rule 5) on ``t``, online, with its rotator's ``R/info`` on this bridge's base topic: its
    rotator is there, and the start is refused naming it."""
    old = Instance("rotor-old", "attic", 200, 900.0)  # no topics
    lk = tower_look()
    lk.begin()
    lk.saw(INFO, old.info([]).encode())
    lk.saw(STATE, b"online")
    lk.saw(EVIDENCE, A_TOWER_INFO)
    refused = lk.end(timed_out=False).refused
    assert refused is not None and "rotor-old" in refused and "'t/tower'" in refused


def test_a_yielding_bridge_says_offline_on_its_own_state_and_rotators_not_the_others() -> None:
    """Claim rule 5 (review 67): base ``t`` with the rotators ``t/tower`` and ``t/yagi`` yields
    to an older bridge on ``t/tower`` (one rotator, on its base topic): its own state and
    ``t/yagi/availability`` are left offline; ``t/tower/availability`` is the other's."""
    me = Instance("rotor-me", "shack", 100, 1000.0, ("t/tower", "t/yagi"))
    lk = FirstLook(Claim(me, "t", INFO, HELLO, Topics("t", {}).names()), STATE)
    assert lk.left_offline() == []
    lk.begin()
    lk.end(timed_out=False)
    older = Instance("rotor-older", "attic", 200, 900.0, ("t/tower",))
    lk.near(NEAR_INFO, older.info([]).encode())
    refused, _ = lk.near(NEAR_STATE, b"online")
    assert refused is not None
    assert lk.left_offline() == [STATE, "t/yagi/availability"]


def test_a_flapping_overlapping_bridge_is_logged_a_few_times_then_once_a_minute(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """Claim rule 7 (review 67): each online and offline of a younger overlapping bridge
    changes what is said, but the log has a few lines, then one a minute, saying how many it
    left out."""
    clock = FakeClock()
    lk = tower_look(EventLimiter(clock, 3, 1 / 60))
    lk.begin()
    lk.saw(EVIDENCE, A_TOWER_INFO)
    lk.end(timed_out=False)
    young = Instance("rotor-young", "attic", 300, 2000.0, ("t/tower",))
    lk.near(INFO, young.info([]).encode())
    with caplog.at_level(logging.INFO, logger="bridge.interfaces.mqtt.look"):
        for _ in range(100):
            assert lk.near(STATE, b"online") == (None, True)
            assert lk.near(STATE, b"offline") == (None, True)
        assert len(caplog.records) == 3
        clock.t += 60
        lk.near(STATE, b"online")
    assert len(caplog.records) == 4
    assert "197 more line(s) of that bridge not logged" in caplog.records[-1].getMessage()
    assert lk.saying and "rotor-young" in lk.saying[0]  # B/bridge/info: the last verdict
