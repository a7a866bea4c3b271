"""The last word's bookkeeping (interfaces/mqtt/lastword.py), pure: a clock passed in."""

from __future__ import annotations

from bridge.interfaces.mqtt.lastword import (
    FENCE_MARKERS_OUT,
    LONG_HOLD_S,
    RESEND_MAX_S,
    RESEND_S,
    Copy,
    LastWord,
)

HOUR_S = 3600.0


def test_a_lane_halt_holds_until_its_marker_and_a_later_marker_ends_every_hold_before_it() -> None:
    w = LastWord(token="t")
    n1 = w.lane_halt("a", "stop", 0.0)
    n2 = w.lane_halt("b", "lock", 0.1)
    assert (n1, n2) == (1, 2) and w.holding
    assert w.marker(2).startswith("t 2 ")
    assert w.marker_back(w.marker(1).encode()) == (1, ["a"])
    assert w.marker_back(b"other 2") == (0, [])  # not this process's
    assert w.marker_back(b"t x") == (0, [])
    assert w.marker_back(w.marker(5).encode()) == (5, ["b"])
    assert not w.holding


def test_a_marker_nobody_but_this_process_made_is_no_marker() -> None:
    """Rule 10, an attack pass: whoever reads the base topic learns the token (every marker
    carries it), and "<token> 999999999" published on the fence topic ended every hold."""
    w = LastWord(token="t")
    n = w.lane_halt("a", "stop", 0.0)
    assert n == 1
    seen = w.marker(1)  # what a reader of the fence topic saw
    other = LastWord(token="t")  # another process that happens to share the token
    for forged in (
        "t 999999999",
        "t 2",
        f"t 2 {seen.split()[2]}",  # a seal moved to another number
        f"t 999999999 {seen.split()[2]}",
        other.marker(5),
        f"{seen} ",
        "t " + "9" * 5000 + " 0",  # (int() refuses so many digits: no marker, no raise)
        "t 1 \u00e9\u00e9\u00e9",  # (a review: a seal outside ASCII raised in compare_digest)
        "t \u0661 0",  # an Arabic-Indic one is a digit to str.isdigit
    ):
        assert w.marker_back(forged.encode()) == (0, []), forged
        w.lane_marker_back(forged.encode())
    assert w.holding
    assert w.marker_back(seen.encode()) == (1, ["a"])


def test_a_lane_marker_copied_to_the_main_connections_topic_is_no_marker() -> None:
    """Rule 10, an attack pass: lane markers are counted apart, and one republished on
    B/bridge/fence ended the holds up to its number (targets from before a STOP went out)."""
    w = LastWord(token="t")
    copy = w.main_halt("b", "stop")  # the main connection read a halt first: a lane marker
    assert copy.lane_marker == 1
    w.lane_halt("a", "stop", 0.0)  # then the lane's stop for another rotator: hold 1
    lane_marker = w.marker(1, lane=True).encode()
    assert w.marker_back(lane_marker) == (0, []) and w.holding
    w.lane_marker_back(w.marker(1).encode())  # nor a main marker as the lane's
    assert w.lane_halt("b", "stop", 1.0) is None  # the note stands: the lane's copy is its echo


def test_the_main_connections_copy_accounts_for_the_lanes_and_a_main_first_halt_eats_its_echo() -> (
    None
):
    w = LastWord(token="t")
    assert w.lane_halt("a", "stop", 0.0) == 1
    copy = w.main_halt("a", "stop")  # the copy of the lane's: no note; a fresh marker
    assert copy == Copy(echo=True, upto=1, marker=2)
    assert not w.held("a") and w.waits("a")  # rule 13: moves wait for a marker, not refused
    assert w.marker_back(w.marker(2).encode()) == (2, ["a"])
    assert w.main_halt("a", "stop") == Copy(lane_marker=1)  # read first on the main one
    assert w.lane_halt("a", "stop", 0.3) is None  # its echo on the lane
    assert w.lane_halt("a", "stop", 0.4) == 3  # a new stop: carried out at once
    assert w.main_halt("a", "lock").lane_marker == 2
    assert w.lane_halt("a", "stop", 1.1) == 4  # notes are per kind
    assert w.lane_halt("b", "lock", 1.2) == 5  # and per rotator


def test_notes_end_with_their_lane_marker_and_when_the_lane_reconnects() -> None:
    """Rule 4: a note never costs a later stop more than the lane's own round trip."""
    w = LastWord(token="t")
    assert w.main_halt("a", "stop").lane_marker == 1  # the lane missed this one (it was down)
    w.lane_connected()  # so its note is forgotten
    w.marker_back(w.marker(w.lane_subscribed(0.4) or 0).encode())  # (in step: rule 9)
    assert w.lane_halt("a", "stop", 0.5) == 2
    assert w.main_halt("a", "stop") == Copy(echo=True, upto=2, marker=3)
    n = w.main_halt("a", "stop").lane_marker  # read first on the main connection
    w.lane_marker_back(w.marker(n or 0, lane=True).encode())  # the lane has no copy of it
    assert w.lane_halt("a", "stop", 0.6) == 4  # a new stop, not taken for an echo
    w.lane_marker_back(b"other 99")  # not ours: nothing
    w.echoes = False  # the lane cannot read its markers: nothing noted
    assert w.main_halt("a", "stop") == Copy(echo=True, upto=4, marker=5)
    assert w.main_halt("a", "stop") == Copy()
    assert w.lane_halt("a", "stop", 0.7) == 6


def test_a_lock_off_is_older_than_a_lane_lock_on_waiting_for_its_copy() -> None:
    w = LastWord(token="t")
    assert w.main_lock_off("a")
    w.lane_halt("a", "lock", 0.0)
    assert not w.main_lock_off("a") and w.main_lock_off("b")
    w.main_halt("a", "lock")  # its copy
    assert w.main_lock_off("a")


def test_a_lane_halt_the_main_connection_never_had_is_forgotten_at_its_marker() -> None:
    """Rule 1: past its marker, no main copy of it is to come; the next main stop is noted."""
    w = LastWord(token="t")
    w.lane_halt("a", "stop", 0.0)  # (its main copy dropped by a broker that fell behind)
    w.marker_back(w.marker(1).encode())
    w.main_halt("a", "stop")
    assert w.lane_halt("a", "stop", 1.1) is None


def test_a_new_main_connection_ends_every_hold_and_voids_the_markers_out() -> None:
    w = LastWord(token="t")
    w.lane_halt("a", "stop", 0.0)
    w.lane_halt("b", "stop", 0.0)
    assert sorted(w.main_gone()) == ["a", "b"]
    assert w.resend_due(100.0) is None  # nothing out
    n = w.lane_halt("a", "stop", 1.0)
    old = w.marker(2).encode()
    assert w.marker_back(old) == (2, []) and n == 3  # an old marker ends no newer hold


def test_a_marker_out_too_long_is_sent_again_with_a_back_off_and_never_given_up() -> None:
    w = LastWord(token="t")
    w.lane_halt("a", "stop", 0.0)
    assert w.resend_due(RESEND_S - 0.1) is None
    n = w.resend_due(RESEND_S + 0.1)
    assert n == 2 and w.resend_due(RESEND_S + 0.2) is None
    assert w.marker_back(w.marker(2).encode()) == (2, ["a"])
    w.lane_halt("a", "stop", 10.0)
    sent, t, waits = [], 10.0, []
    while t < 10.0 + HOUR_S:  # an hour of a broker that drops every marker
        t += 0.5
        n = w.resend_due(t)
        if n is not None:
            sent.append((t, n))
    waits = [b[0] - a[0] for a, b in zip(sent, sent[1:], strict=False)]
    assert waits[:3] == [2 * RESEND_S, 4 * RESEND_S, 8 * RESEND_S] and max(waits) == RESEND_MAX_S
    assert all(n > 0 for _t, n in sent) and w.holding  # never given up, still held
    assert w.marker_back(w.marker(sent[-1][1]).encode())[1] == ["a"]  # the last one ends it


def test_no_clock_ends_a_hold_while_the_main_connection_lives() -> None:
    """Rule 5: hours of a main connection that reads nothing: held; then each way a hold
    ends: the marker, the main connection's own copy, the main connection gone."""
    for end in ("marker", "copy", "gone"):
        w = LastWord(token="t")
        n = w.lane_halt("a", "stop", 0.0)
        for t in range(1, 5 * int(HOUR_S)):
            w.resend_due(float(t))  # the timer's work: it may send markers again, no more
        assert w.holding and w.long_holds(5 * HOUR_S) == {"a": 0.0}
        if end == "marker":
            assert w.marker_back(w.marker(n or 0).encode()) == (n, ["a"])
        elif end == "copy":  # rule 13: the copy sends a fresh marker at once; it ends the hold
            copy = w.main_halt("a", "stop")
            assert copy.echo and copy.marker is not None and w.holding
            assert w.marker_back(w.marker(copy.marker).encode()) == (copy.marker, ["a"])
        else:
            assert w.main_gone() == ["a"]  # (the caller releases with clearing)
        assert not w.holding and w.long_holds(5 * HOUR_S) == {}


def test_a_copy_ends_every_hold_up_to_its_own_and_no_later_one() -> None:
    """Rule 9: the copy of lane halt n says as much as marker n would; rule 13: the holds up
    to it no longer refuse moves (they wait under the hold), a later one still does."""
    w = LastWord(token="t")
    w.lane_halt("a", "stop", 0.0)  # 1
    w.lane_halt("b", "stop", 0.0)  # 2
    w.lane_halt("a", "lock", 0.0)  # 3: a is held until 3 now
    assert w.main_halt("a", "stop") == Copy(echo=True, upto=1, marker=4)
    assert w.held("a") and w.held("b")
    assert w.main_halt("b", "stop") == Copy(echo=True, upto=2, marker=5)
    assert w.held("a") and not w.held("b") and w.waits("b")
    assert w.holding and w.main_lock_off("a") is False  # rule 8: the ON waits for its copy
    assert w.main_halt("a", "lock") == Copy(echo=True, upto=3, marker=6)
    assert not w.held("a") and w.holding
    assert w.marker_back(w.marker(6).encode()) == (6, ["a", "b"])
    assert not w.holding and not w.markers_out  # the markers out are done with too


def test_a_long_hold_is_known_while_it_lasts() -> None:
    w = LastWord(token="t")
    w.lane_halt("a", "stop", 10.0)
    assert w.long_holds(10.0 + LONG_HOLD_S - 0.1) == {}
    assert w.long_holds(10.0 + LONG_HOLD_S) == {"a": 10.0}
    w.lane_halt("a", "stop", 12.0)  # the hold goes on: since its start
    assert w.long_holds(20.0) == {"a": 10.0}
    w.marker_back(w.marker(2).encode())
    assert w.long_holds(20.0) == {}


def test_with_the_markers_denied_a_lane_halt_holds_until_its_main_copy() -> None:
    """Rule 7: learnt from the broker; nothing goes out to wait for, the hold stays."""
    w = LastWord(token="t")
    held = w.lane_halt("a", "stop", 0.0)
    w.markers_denied()
    assert w.holding and not w.markers_out
    assert w.lane_halt("b", "lock", 1.0) == 2  # still a hold, no marker out
    assert not w.markers_out and w.resend_due(HOUR_S) is None
    assert w.holding and w.long_holds(HOUR_S) == {"a": 0.0, "b": 1.0}
    w.lane_connected()  # (without markers, a new lane connection is taken as in step)
    w.lane_subscribed(2.0)
    assert w.main_halt("a", "stop") == Copy(echo=True, upto=held or 0, released=("a",))
    assert w.main_halt("b", "lock").released == ("b",)
    assert not w.holding


def test_a_halt_published_while_the_lane_was_down_is_not_taken_for_a_newer_ones_copy() -> None:
    """Rule 9: the lane reconnected; the main connection, behind, still reads a stop the lane
    never had: it must not end the hold of the newer stop the lane read on its new connection."""
    w = LastWord(token="t")
    w.lane_connected()
    sync = w.lane_subscribed(0.0)
    assert sync == 1 and w.markers_out  # goes out on the main connection
    held = w.lane_halt("a", "stop", 0.1)  # on the new connection
    assert w.main_halt("a", "stop") == Copy()  # the stop the lane never had: nothing ends
    assert w.holding
    w.marker_back(w.marker(sync).encode())  # the main connection is past the lane's start
    assert w.holding
    copy = w.main_halt("a", "stop")
    assert copy.echo and copy.upto == held and not w.held("a")
    w.main_gone()  # a new main connection subscribes after the lane did: in step at once
    n = w.lane_halt("a", "stop", 1.0)
    copy = w.main_halt("a", "stop")
    assert copy.echo and copy.upto == n and not w.held("a")


def test_a_retained_stop_live_always_replayed_once_per_message() -> None:
    w = LastWord()
    assert w.retained_halt("r/stop", b"STOP", replayed=False)
    assert w.retained_halt("r/stop", b"STOP", replayed=False)  # pressed again (MQTT 5)
    assert w.retained_halt("r/stop", b"STOP", replayed=True)  # first seen replayed
    assert not w.retained_halt("r/stop", b"STOP", replayed=True)  # at the next reconnect
    assert w.retained_halt("r/stop", b"now", replayed=True)  # another message
    assert not w.retained_halt("r/stop", b"", replayed=True)  # deleted
    assert w.retained_halt("r/stop", b"now", replayed=True)


def test_a_halt_carried_out_live_under_311_is_not_carried_out_again_when_replayed() -> None:
    """Rule 6: under MQTT 3.1.1 a retained STOP published while the bridge runs arrives without
    its flag; the broker's replay of it after a restart is not a second stop (an attack pass:
    it stopped a rotor mid-turn to a later target)."""
    w = LastWord()
    w.live_halt("r/stop", b"STOP")
    assert not w.retained_halt("r/stop", b"STOP", replayed=True)  # the replay of what was obeyed
    assert w.retained_halt("r/stop", b"other", replayed=True)  # another message
    w.live_halt("r/stop", b"")  # an empty live stop remembers nothing
    assert not w.retained_halt("r/stop", b"other", replayed=True)


def test_markers_allowed_again_go_out_for_the_next_lane_halt() -> None:
    """Rule 7: judged on every connect: a probe back on a later connection turns them on."""
    w = LastWord(token="t")
    w.markers_denied()
    w.lane_halt("a", "stop", 0.0)
    assert not w.markers_out
    w.main_gone()  # the new connection
    assert w.markers_allowed(1.0) is None  # (no hold up, the lane in step: none now)
    n = w.lane_halt("a", "stop", 1.0)
    assert w.markers_out and w.marker_back(w.marker(n or 0).encode()) == (n, ["a"])


def test_no_echo_is_noted_while_the_lanes_subscription_is_not_acknowledged() -> None:
    """Rule 4, an attack pass: the main connection read a halt while the lane had connected
    but the broker had not taken its subscription; neither the lane's copy nor the lane
    marker came, the note stood, and the lane's next real stop was dropped as its echo (left
    to the main connection, behind whatever it was reading)."""
    w = LastWord(token="t")
    w.lane_connected()
    assert w.main_halt("a", "stop") == Copy()  # nothing noted, no lane marker
    sync = w.lane_subscribed(1.0)
    assert w.lane_halt("a", "stop", 2.0)  # carried out at once, with a hold
    assert w.main_halt("b", "stop") == Copy()  # its marker not back: maybe from before it
    w.marker_back(w.marker(sync or 0).encode())
    copy = w.main_halt("b", "stop")  # in step now: noted as before
    assert copy.lane_marker is not None and w.lane_halt("b", "stop", 3.0) is None


def test_another_interfaces_halt_fences_the_main_connections_older_moves_until_its_marker() -> None:
    """Rule 11: a stop or lock ON from the console, rotctld, a logger; what the main connection
    reads before the fence's marker came back was published before it. A stop fences moves
    alone; a lock ON fences a lock OFF too; a later fence for the rotator outlasts an earlier
    marker; a resent marker (rule 5) ends it; the connection dropping ends it."""
    w = LastWord(token="t")
    n = w.fence("a", lock=False, now=0.0)
    assert n == 1 and w.fenced("a") and not w.fenced("a", lock_off=True) and not w.fenced("b")
    assert w.markers_out and not w.holding  # (a fence holds nothing back in the mailbox)
    m = w.fence("a", lock=True, now=0.1)
    assert m == 2 and w.fenced("a", lock_off=True)
    assert w.marker_back(w.marker(1).encode()) == (1, [])
    assert w.fenced("a") and w.fenced("a", lock_off=True)  # the newer halt's marker is out
    assert w.marker_back(w.marker(2).encode()) == (2, [])
    assert not w.fenced("a") and not w.fenced("a", lock_off=True)
    w.fence("a", lock=True, now=HOUR_S)
    resent = w.resend_due(HOUR_S + RESEND_S)
    assert resent is not None and w.marker_back(w.marker(resent).encode())[0] == resent
    assert not w.fenced("a")
    w.fence("a", lock=True, now=2 * HOUR_S)
    w.main_gone()  # nothing older comes on the next connection
    assert not w.fenced("a", lock_off=True)


def test_no_fence_while_the_main_connection_cannot_read_its_markers() -> None:
    """Rule 11 with rule 7: a fence no marker could end would refuse every MQTT move for
    good; none is put, and one up when the markers are found denied ends."""
    w = LastWord(token="t")
    w.fence("a", lock=True, now=0.0)
    w.markers_denied()
    assert not w.fenced("a", lock_off=True)
    assert w.fence("a", lock=True, now=1.0) is None and not w.fenced("a")


def test_the_copy_of_a_lane_stop_read_after_another_interfaces_halt_ends_no_fence() -> None:
    """Rule 11 (a review): an MQTT STOP, a target, then the console's STOP, published in that
    order; the lane reads the MQTT STOP only after the console's was fenced, so its number is
    the newer. Its copy on the main connection says nothing of what was published before the
    console's STOP (the target, read next): it ended the fence and forgot its marker, and the
    target turned the rotor after the console's STOP. Only a marker ends a fence."""
    w = LastWord(token="t")
    fence = w.fence("r", False, 0.0)  # the console's STOP
    assert fence is not None
    assert w.lane_halt("r", "stop", 0.0) == fence + 1  # the older MQTT STOP, read late
    assert w.main_halt("r", "stop").echo  # its copy: the lane's hold refuses no more ...
    assert not w.held("r")
    assert w.fenced("r")  # ... the fence does: the target read next was published before
    resent = w.resend_due(RESEND_S)  # its marker is still waited for (sent again if lost)
    assert resent is not None
    w.marker_back(w.marker(resent).encode())
    assert not w.fenced("r") and not w.holding


def test_a_flood_of_fences_puts_a_few_markers_out_and_each_fence_waits_for_one_after_it() -> None:
    """Rule 11 (an attack pass): a marker for every stop of a flood on a logger port piled up
    behind the main connection. At most FENCE_MARKERS_OUT are out; a halt beyond them is fenced
    at once, its marker owed until one is back (a marker out then was published before the
    halt, so it ends no fence of it); the owed one ends it; a resend (rule 5) makes room, and
    the connection dropping forgets what was owed."""
    w = LastWord(token="t")
    out = [w.fence("a", lock=False, now=0.0) for _ in range(FENCE_MARKERS_OUT)]
    assert out == list(range(1, FENCE_MARKERS_OUT + 1))
    assert w.fence("b", lock=True, now=0.1) is None  # no room: owed
    assert w.fence("a", lock=False, now=0.1) is None
    assert w.fenced("b", lock_off=True) and w.fenced("a") and w.markers_out
    assert w.owed_fence(0.2) is None  # (still no room)
    w.marker_back(w.marker(FENCE_MARKERS_OUT).encode())  # every marker out is back ...
    assert w.fenced("a") and w.fenced("b", lock_off=True)  # ... none after these halts
    owed = w.owed_fence(0.3)
    assert owed == FENCE_MARKERS_OUT + 1 and w.owed_fence(0.3) is None  # one for both
    w.marker_back(w.marker(owed).encode())
    assert not w.fenced("a") and not w.fenced("b", lock_off=True) and not w.markers_out
    for _ in range(FENCE_MARKERS_OUT):  # a broker that drops them: rule 5's resend
        w.fence("a", lock=False, now=HOUR_S)
    assert w.fence("a", lock=False, now=HOUR_S) is None
    resent = w.resend_due(HOUR_S + RESEND_S)
    assert resent is not None and w.owed_fence(HOUR_S + RESEND_S) == resent + 1
    w.fence("a", lock=True, now=2 * HOUR_S)  # (room again: no owed while room)
    for _ in range(FENCE_MARKERS_OUT):
        w.fence("b", lock=False, now=2 * HOUR_S)
    w.main_gone()  # nothing older comes on the next connection: nothing owed
    assert not w.fenced("a", lock_off=True) and not w.fenced("b") and not w.markers_out
    assert w.owed_fence(3 * HOUR_S) is None
