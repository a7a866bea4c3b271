"""Review 30 on interfaces/mqtt/remote.py rule 8 (f7386b2d): a kept halt sent again is stamped
with its seen time "by the reckoning of the moment it goes again (at a beat, that beat's)",
and rule 8 promises "a move seen before it stays before it". But at the first beat after a
drop (``_closed`` forgets the reckoning) or a new station process (``heard`` clears it) the
reckoning is that one beat's alone, short by its whole trip; a move of another front end seen
before the halt and read after a later beat with a shorter trip is stamped from a better
reckoning (heartbeat.py rule 3: the largest offset), by as much as the two trips differ, and
can land after the halt's stamp. The station compares the two stamps directly (service.py
rule 9) and turns the rotor after the STOP. The remote itself knows both seen times on one
clock (its own monotonic one) and could tell.

Sequence: the link down; PstRotator's STOP seen at t0 + 9, kept; Gpredict's ``P`` seen at
t0 + 8.9, unread (its thread asleep, the computer busy); the link back, the first beat at
t0 + 12 after a 300 ms trip (the link just recovered): the STOP goes again stamped t0 + 8.7
on the station's clock; the next beat at t0 + 14 after 10 ms; the P is read now: stamped
t0 + 8.89, after the STOP's t0 + 8.7.
"""

from __future__ import annotations

import pytest

from bridge.core.errors import Refused
from tests.remote.test_attack5_floor_other_front_end import _link, _sent
from tests.remote.test_late_commands import paho_message

BASE = 1_700_000_000.0  # the station's clock is BASE + the remote's, exactly
AFTER = ("rotor/stop", "rotor/lock")


def _beat(link: object, left_station: float) -> None:
    beat = paho_message("rotor/bridge/heartbeat", f"{left_station:.3f}".encode(), [])
    link._on_message(None, None, beat)  # type: ignore[attr-defined]  # noqa: SLF001


@pytest.mark.parametrize("kept", [True, False])
def test_a_move_seen_before_a_kept_stop_stays_before_it_when_the_reckoning_improves(
    kept: bool,
) -> None:
    """``kept``: the diff's path; else the same STOP sent live right after that first beat
    (the same hole, older than f7386b2d: any halt stamped from a reckoning a later beat
    betters)."""
    clock, link, fake = _link()
    t0 = clock.t
    link.station_clock.heard(BASE + t0)
    link.connected.clear()
    clock.t = t0 + 9.0
    if kept:
        with pytest.raises(Refused):
            link.send("rotor/stop", "stop", "DL1ABC", 5, seen_s=clock.t, reader="pst")
    link.station_clock.forget()  # (as _closed does)
    link._opened(None)  # noqa: SLF001
    clock.t = t0 + 12.0
    _beat(link, BASE + clock.t - 0.3)  # (left the station 300 ms ago)
    if not kept:
        link.send("rotor/stop", "stop", "DL1ABC", 5, seen_s=t0 + 9.0, reader="pst")
    again = [props for topic, props in fake.published if topic == "rotor/stop"][-1]
    assert _sent(again) < BASE + t0 + 9.0  # (the reckoning short by that trip)
    clock.t = t0 + 14.0
    _beat(link, BASE + clock.t - 0.01)  # (10 ms)
    fake.published.clear()
    try:
        link.send(
            "rotor/target", '{"azimuth":200}', "DL1ABC", 5, seen_s=t0 + 8.9, after=AFTER,
            reader="rotctld gpredict",
        )  # fmt: skip
    except Refused:
        return  # (refused at the remote: the safe side)
    ((topic, move),) = fake.published
    assert topic == "rotor/target"
    assert _sent(move) < _sent(again), (
        f"Gpredict's P seen 100 ms before PstRotator's STOP went out stamped "
        f"{_sent(move):.3f}, after the STOP's resend ({_sent(again):.3f}): the station takes "
        "it for after its last halt and turns the rotor"
    )
