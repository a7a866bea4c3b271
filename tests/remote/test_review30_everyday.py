"""interfaces/mqtt/remote.py rule 8 (review 30): a move seen before a halt the remote sent or
kept is refused here, from any source. What must keep working: the bytes of one read
(``P 300``, ``S``, ``P 200``: seen at one time) end at 200; ``S`` then a later ``P``; another
front end's move seen after a STOP; Gpredict tracking on after a STOP; the console's moves
(stamped when sent, not checked)."""

from __future__ import annotations

import pytest

from bridge.core.errors import RefusalCode, Refused
from tests.remote.test_attack5_floor_other_front_end import _link, _sent

BASE = 1_700_000_000.0
AFTER = ("rotor/stop", "rotor/lock")


def _move(link: object, azimuth: int, seen_s: float | None, reader: str | None) -> None:
    link.send(  # type: ignore[attr-defined]
        "rotor/target", f'{{"azimuth":{azimuth}}}', "DL1ABC", 5, seen_s=seen_s, after=AFTER,
        reader=reader,
    )  # fmt: skip


def _stop(link: object, seen_s: float | None, reader: str | None) -> None:
    link.send("rotor/stop", "stop", "DL1ABC", 5, seen_s=seen_s, reader=reader)  # type: ignore[attr-defined]


def test_one_read_p_s_p_ends_at_the_last_target_after_the_stop() -> None:
    clock, link, fake = _link()
    clock.t += 10.0
    link.station_clock.heard(BASE + clock.t)
    seen = clock.t - 0.5
    _move(link, 300, seen, "rotctld 1")
    _stop(link, seen, "rotctld 1")
    _move(link, 200, seen, "rotctld 1")
    topics = [topic for topic, _props in fake.published]
    assert topics == ["rotor/target", "rotor/stop", "rotor/target"]
    assert fake.published[-1][0] == "rotor/target"
    assert _sent(fake.published[2][1]) >= _sent(fake.published[1][1])


def test_s_then_a_later_p_goes_and_is_stamped_after_the_s() -> None:
    clock, link, fake = _link()
    clock.t += 10.0
    link.station_clock.heard(BASE + clock.t)
    _stop(link, clock.t, "rotctld 1")
    clock.t += 0.2
    _move(link, 200, clock.t, "rotctld 1")
    (_, stop), (_, move) = fake.published
    assert _sent(move) > _sent(stop)


def test_gpredict_tracks_on_after_a_stop_from_another_front_end() -> None:
    """Gpredict's ``P`` every second; PstRotator's STOP at 12.5 s: the ``P`` seen at 12 s and
    read late is refused here; those seen after the STOP go, stamped after it."""
    clock, link, fake = _link()
    t0 = clock.t
    clock.t = t0 + 10.0
    link.station_clock.heard(BASE + clock.t)
    _move(link, 100, t0 + 10.0, "rotctld gpredict")
    clock.t = t0 + 12.6
    _stop(link, t0 + 12.5, "pst")
    with pytest.raises(Refused) as refused:
        _move(link, 101, t0 + 12.0, "rotctld gpredict")
    assert refused.value.code is RefusalCode.STALE
    assert "seen before a STOP" in refused.value.message
    stop = fake.published[-1][1]
    for n in range(3):
        clock.t = t0 + 13.0 + n
        _move(link, 102 + n, clock.t, "rotctld gpredict")
        assert fake.published[-1][0] == "rotor/target"
        assert _sent(fake.published[-1][1]) > _sent(stop)


def test_a_move_seen_when_another_sources_stop_came_is_not_refused() -> None:
    """Another source's STOP with an exact arrival (a kernel's datagram stamp: its seen and
    read times one): a move seen at that moment is not refused (the station's stamps judge
    them). Without one, the STOP came at some time up to its read: a move seen at its seen
    time may have come before it, refused (the cross-reader case:
    tests/remote/test_cross_reader_halt.py); one seen at its read time is not."""
    clock, link, fake = _link()
    clock.t += 10.0
    link.station_clock.heard(BASE + clock.t)
    link.send(
        "rotor/stop", "stop", "DL1ABC", 5, seen_s=clock.t - 1.0, reader="pst", read_s=clock.t - 1.0
    )
    _move(link, 200, clock.t - 1.0, "rotctld gpredict")
    assert fake.published[-1][0] == "rotor/target"
    _stop(link, clock.t - 0.5, "pst")  # (no stamp: read now)
    with pytest.raises(Refused):
        _move(link, 201, clock.t - 0.5, "rotctld gpredict")
    _move(link, 202, clock.t, "rotctld gpredict")
    assert fake.published[-1][0] == "rotor/target"


def test_the_consoles_moves_are_not_checked_and_its_stop_refuses_moves_seen_before_it() -> None:
    clock, link, fake = _link()
    t0 = clock.t
    clock.t = t0 + 10.0
    link.station_clock.heard(BASE + clock.t)
    _stop(link, None, None)  # the console's STOP: seen when sent, at 10 s
    clock.t = t0 + 10.5
    _move(link, 200, None, None)  # the console's move: stamped when sent
    assert fake.published[-1][0] == "rotor/target"
    with pytest.raises(Refused):  # a rotctld P seen at 9.9 s, read after the console's STOP
        _move(link, 201, t0 + 9.9, "rotctld 1")
    _move(link, 202, t0 + 10.2, "rotctld 1")  # (seen after it: goes)
    assert fake.published[-1][0] == "rotor/target"


def test_a_halt_seen_earlier_read_later_does_not_lower_the_bar() -> None:
    """Two sources' STOPs read out of order (the later-seen first): the bar is the latest
    seen time of either."""
    clock, link, _fake = _link()
    t0 = clock.t
    clock.t = t0 + 10.0
    link.station_clock.heard(BASE + clock.t)
    _stop(link, t0 + 9.0, "pst")
    _stop(link, t0 + 8.0, "rotctld 1")
    with pytest.raises(Refused):
        _move(link, 200, t0 + 8.5, "rotctld gpredict")
