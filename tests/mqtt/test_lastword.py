"""The last word's bookkeeping (mqtt/lastword.py), pure: a clock passed in."""

from __future__ import annotations

from bridge.mqtt.lastword import GIVE_UP, RESEND_S, LastWord


def test_a_lane_halt_holds_until_its_marker_and_a_later_marker_ends_every_hold_before_it() -> None:
    w = LastWord(token="t")
    n1 = w.lane_halt("a", "stop", 0.0)
    n2 = w.lane_halt("b", "lock", 0.1)
    assert (n1, n2) == (1, 2) and w.holding
    assert w.marker(2) == "t 2"
    assert w.marker_back(b"t 1") == (1, ["a"])
    assert w.marker_back(b"other 2") == (0, [])  # not this process's
    assert w.marker_back(b"t x") == (0, [])
    assert w.marker_back(b"t 5") == (5, ["b"])
    assert not w.holding


def test_the_main_connections_copy_accounts_for_the_lanes_and_a_main_first_halt_eats_its_echo() -> (
    None
):
    w = LastWord(token="t")
    assert w.lane_halt("a", "stop", 0.0) == 1
    assert w.main_halt("a", "stop") is None  # the copy of the lane's: no note
    assert w.main_halt("a", "stop") == 1  # read first on the main connection: lane marker 1
    assert w.lane_halt("a", "stop", 0.3) is None  # its echo on the lane
    assert w.lane_halt("a", "stop", 0.4) == 2  # a new stop: carried out at once
    assert w.main_halt("a", "lock") == 2
    assert w.lane_halt("a", "stop", 1.1) == 3  # notes are per kind
    assert w.lane_halt("b", "lock", 1.2) == 4  # and per rotator


def test_notes_end_with_their_lane_marker_and_when_the_lane_reconnects() -> None:
    """Rule 4: a note never costs a later stop more than the lane's own round trip."""
    w = LastWord(token="t")
    w.main_halt("a", "stop")  # the lane missed this one (it was down)
    w.lane_connected()
    assert w.lane_halt("a", "stop", 0.5) == 1
    n = w.main_halt("a", "stop")  # read late from the main connection's backlog
    w.lane_marker_back(w.marker(n or 0).encode())  # the lane has no copy of it
    assert w.lane_halt("a", "stop", 0.6) == 2  # a new stop, not taken for an echo
    w.lane_marker_back(b"other 99")  # not ours: nothing
    w.echoes = False  # the lane cannot read its markers: nothing noted
    assert w.main_halt("a", "stop") is None
    assert w.lane_halt("a", "stop", 0.7) == 3


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
    w.marker_back(b"t 1")
    w.main_halt("a", "stop")
    assert w.lane_halt("a", "stop", 1.1) is None


def test_a_new_main_connection_ends_every_hold_and_voids_the_markers_out() -> None:
    w = LastWord(token="t")
    w.lane_halt("a", "stop", 0.0)
    w.lane_halt("b", "stop", 0.0)
    assert sorted(w.main_gone()) == ["a", "b"]
    assert w.resend_due(100.0) is None  # nothing out
    n = w.lane_halt("a", "stop", 1.0)
    assert w.marker_back(b"t 2") == (2, []) and n == 3  # an old marker ends no newer hold


def test_a_marker_out_too_long_is_replaced_by_a_new_one_and_then_given_up() -> None:
    w = LastWord(token="t")
    w.lane_halt("a", "stop", 0.0)
    assert w.resend_due(RESEND_S - 0.1) is None
    n = w.resend_due(RESEND_S + 0.1)
    assert n == 2 and w.resend_due(RESEND_S + 0.2) is None
    assert w.marker_back(b"t 2") == (2, ["a"])
    w.lane_halt("a", "stop", 10.0)
    resent = [w.resend_due(10.0 + RESEND_S * (i + 1) + 0.1) for i in range(GIVE_UP + 1)]
    assert resent[-1] == -1 and all(n and n > 0 for n in resent[:-1])  # (the caller gives up)
    assert w.lane_halt("a", "stop", 0.0, hold=False) == 0  # rule 7: no hold


def test_a_retained_stop_live_always_replayed_once_per_message() -> None:
    w = LastWord()
    assert w.retained_halt("r/stop", b"STOP", replayed=False)
    assert w.retained_halt("r/stop", b"STOP", replayed=False)  # pressed again (MQTT 5)
    assert w.retained_halt("r/stop", b"STOP", replayed=True)  # first seen replayed
    assert not w.retained_halt("r/stop", b"STOP", replayed=True)  # at the next reconnect
    assert w.retained_halt("r/stop", b"now", replayed=True)  # another message
    assert not w.retained_halt("r/stop", b"", replayed=True)  # deleted
    assert w.retained_halt("r/stop", b"now", replayed=True)
