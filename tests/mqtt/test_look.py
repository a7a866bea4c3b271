"""The first look's books (bridge/interfaces/mqtt/look.py, MQTT rule 14), without a broker: what a
look saw decides whether stale discovery is deleted, left alone, or the bridge refuses to run."""

from __future__ import annotations

import json

from bridge.interfaces.mqtt.claim import Claim, Instance, Post, stamp
from bridge.interfaces.mqtt.look import MAX_ROUNDS, FirstLook

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


def test_a_vouch_read_heard_before_the_look_asks_for_it_still_vouches() -> None:
    """Review 90 (claim.py rule 5): a bridge on ``rotor`` with a rotator ``tower``, beside a
    live bridge on ``rotor/shack`` whose tower has ``topic = "rotor/tower"`` (its controller
    off: ``offline``). That bridge's ``rotor/shack/bridge/info`` and ``state`` are also read by
    another filter of the looking bridge (stale.py's ``rotor/+/bridge/state``), so the broker
    sends them before the stamp that names them, and never again: kept from the look's start,
    they vouch for the stamp, and the bridge refuses to run. Not heard at all: taken for gone."""
    posts = (Post("rotor/bridge/info"), Post("rotor/tower/bridge/info"), Post("rotor/tower/info"))
    claim = Claim(ME, "rotor", "rotor/bridge/info", "rotor/bridge/hello", posts)
    shack = {
        "rotor/shack/bridge/info": OTHER.info([]).encode(),
        "rotor/shack/bridge/state": b"online",
    }
    tower = {
        "rotor/tower/info": json.dumps(
            {"id": "tower", "bridge": stamp(OTHER.id, "rotor/shack")}
        ).encode(),
        "rotor/tower/availability": b"offline",
    }
    for heard_first, refused in ((shack, True), ({}, False)):
        lk = FirstLook(claim, "rotor/bridge/state")
        hello = lk.begin()
        for topic, payload in {**heard_first, **tower}.items():
            lk.saw(topic, payload)
        assert lk.ended_by(hello) == 1
        lk.next_round()  # once the hello is back: what it reads (these are read already)
        outcome = lk.end(timed_out=False)
        assert (outcome.refused is not None) == refused, heard_first
        if refused:
            assert outcome.refused is not None and "rotor/shack/bridge/state" in outcome.refused


def test_a_stamp_seen_after_the_vouch_reads_were_chosen_is_read_in_one_more_round() -> None:
    """Review 94 (rule 14): aedes hands a subscription's retained messages beside what follows,
    so a stamp on ``rotor/tower/info`` can come after the first hello, when the vouch reads are
    chosen. The look then asks once more: its vouch reads, subscribed before a hello more, whose
    return ends the look. A round in which the broker was still handing over what it held asks
    again too (nothing to subscribe); at most MAX_ROUNDS of them."""
    posts = (Post("rotor/bridge/info"), Post("rotor/tower/bridge/info"), Post("rotor/tower/info"))
    claim = Claim(ME, "rotor", "rotor/bridge/info", "rotor/bridge/hello", posts)
    stamped = json.dumps({"id": "tower", "bridge": stamp(OTHER.id, "shack")}).encode()
    lk = FirstLook(claim, "rotor/bridge/state")
    hello = lk.begin()
    assert lk.ended_by(hello) == 1
    assert lk.next_round() == ([], [], b"")  # nothing to ask, nothing late: the look ends
    hello = lk.begin()
    assert lk.ended_by(hello) == 2
    first = lk.next_round(replaying=True)  # (the broker still handing over what it held)
    assert first == ([], [], b"rotor-me 2 probe")
    lk.saw("rotor/tower/info", stamped)  # the stamp, late
    lk.saw("rotor/tower/availability", b"offline")
    assert lk.ended_by(b"rotor-me 2") is None and lk.ended_by(first[2]) == 2
    reads = ["shack/bridge/info", "shack/bridge/state"]
    second = lk.next_round()
    assert second == ([], reads, b"rotor-me 2 probe 2")
    lk.saw("shack/bridge/info", OTHER.info([]).encode())
    lk.saw("shack/bridge/state", b"online")
    assert lk.ended_by(second[2]) == 2
    assert lk.next_round() == ([], [], b"")  # (asked already: not again)
    outcome = lk.end(timed_out=False)
    assert outcome.refused is not None and "shack/bridge/state" in outcome.refused
    lk.begin()
    rounds = 0
    while lk.next_round(replaying=True)[2]:  # a broker that never stops handing over
        rounds += 1
    assert rounds == MAX_ROUNDS
