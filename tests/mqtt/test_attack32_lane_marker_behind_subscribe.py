"""Attack 32's SUBACK window, in the last word's books (interfaces/mqtt/lastword.py rule 17): the
lane, back alone, publishes a marker of its own right behind its SUBSCRIBE; the main connection
reading that marker back puts the lane in step (rule 9) without waiting for the marker its own
uplink carries after the SUBACK. Pure: a clock passed in."""

from __future__ import annotations

from bridge.interfaces.mqtt.lastword import LastWord


def _back_alone(w: LastWord, kind: str) -> tuple[int, int]:
    """The lane of ``kind`` reconnects: its own marker behind its SUBSCRIBE (``q``), then its
    SUBACK's marker on the main connection (``m``), which does not come back (a busy uplink)."""
    w.lane_connected((kind,))
    q = w.lane_subscribing((kind,))
    m = w.lane_subscribed(0.0, (kind,))
    assert q is not None and m is not None
    return q, m


def test_a_stop_read_after_the_lanes_own_marker_is_its_copy_and_the_target_after_it_waits() -> None:
    w = LastWord(token="t")
    q, _m = _back_alone(w, "stop")
    w.marker_back(w.marker(q).encode())  # the lane's marker, read on the main connection
    n = w.lane_halt("a", "stop", 0.1)  # the operator's STOP, on the lane first
    assert n
    copy = w.main_halt("a", "stop", 0.1)  # its copy on the main connection
    assert copy.echo and copy.marker, copy
    assert not w.held("a") and w.waits("a"), "a target after the STOP's copy is refused"
    assert w.marker_back(w.marker(copy.marker).encode())[1] == ["a"]  # then it goes


def test_a_halt_read_before_the_lanes_own_marker_still_counts_for_nothing() -> None:
    """Rule 9 kept: read before either marker, the halt may be older than the SUBSCRIBE."""
    w = LastWord(token="t")
    q, _m = _back_alone(w, "stop")
    assert w.lane_halt("a", "stop", 0.1)
    assert w.main_halt("a", "stop", 0.1).echo is False  # maybe published before it: nothing
    assert w.held("a")
    w.marker_back(w.marker(q).encode())
    assert w.main_halt("a", "stop", 0.2).echo  # the next one, read after it, is the copy


def test_a_lock_on_the_main_connection_reads_first_after_the_lanes_marker_is_noted() -> None:
    """The lock lane's twin (rule 4): the main connection reads the ON before the lock lane;
    the note makes the lane's copy, read after the OFF that followed, the echo, not a second
    lock ON."""
    w = LastWord(token="t")
    q, _m = _back_alone(w, "lock")
    w.marker_back(w.marker(q).encode())
    copy = w.main_halt("a", "lock", 0.1)
    assert copy.lane_marker is not None, copy
    assert w.main_lock_off("a")  # the OFF after it is carried out
    assert w.lane_halt("a", "lock", 0.2) is None, "the lane's copy of the ON locked it again"


def test_only_the_lanes_own_marker_puts_it_in_step_not_a_later_number() -> None:
    """A marker numbered after the lane's own one (another interface's fence) may have gone out
    on the main connection before the broker took the lane's SUBSCRIBE: read back, it says
    nothing of the lane's subscription, though it ends the fence."""
    w = LastWord(token="t")
    w.lane_connected(("stop",))
    q = w.lane_subscribing(("stop",))
    f = w.fence("b", False, 0.0)  # the console's STOP: its marker, numbered after q
    assert q is not None and f is not None and f > q
    assert w.marker_back(w.marker(f).encode())[0] == f and not w.fenced("b")
    assert w.main_halt("a", "stop", 0.1).lane_marker is None  # no note: maybe before it
    assert w.lane_halt("a", "stop", 0.2)  # the lane's own STOP is carried out
    assert w.main_halt("a", "stop", 0.2).echo is False and w.held("a")


def test_the_marker_of_a_lane_connection_gone_since_puts_the_new_one_in_nothing() -> None:
    w = LastWord(token="t")
    q, _m = _back_alone(w, "stop")
    w.lane_connected(("stop",))  # dropped again before its marker came back
    w.marker_back(w.marker(q).encode())  # the old connection's marker, read late
    assert w.main_halt("a", "stop", 0.1).lane_marker is None  # the new one is not in step


def test_no_marker_behind_the_subscribe_while_the_main_connection_reads_none() -> None:
    w = LastWord(token="t")
    w.markers_denied()
    w.lane_connected(("stop",))
    assert w.lane_subscribing(("stop",)) is None
