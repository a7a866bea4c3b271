"""interfaces/mqtt/remote.py rule 8 on a kept halt sent again (review 28): it goes stamped with
when it was last asked (seen), by the reckoning of the moment it goes, never with when it goes
again; no move is lifted by it but its own source's. What ``_AGAIN`` (82772ff4) lifted every
move to the resend for must still hold: a move asked after the STOP, before or after it goes
again, is not stamped before it (the station would refuse it while its client got RPRT 0)."""

from __future__ import annotations

import pytest

from bridge.core.errors import Refused
from bridge.interfaces.mqtt.remote import AGAIN_SEEN_MAX_S
from tests.remote.test_attack5_floor_other_front_end import _floor_alone, _link, _sent
from tests.remote.test_late_commands import paho_message

BASE = 1_700_000_000.0
AFTER = ("rotor/stop", "rotor/lock")


def _beat(link: object, t: float, station: str | None = None) -> None:
    props = [("station", station)] if station is not None else []
    beat = paho_message("rotor/bridge/heartbeat", f"{t:.3f}".encode(), props)
    link._on_message(None, None, beat)  # type: ignore[attr-defined]  # noqa: SLF001


def _stops(fake: object) -> list[object]:
    return [props for topic, props in fake.published if topic == "rotor/stop"]  # type: ignore[attr-defined]


@pytest.mark.parametrize("station", [None, "new-run"])
def test_a_move_asked_after_a_kept_stop_goes_after_it_however_late_read(
    station: str | None,
) -> None:
    """The STOP seen at 9 s goes again at the beat at 12 s (from the same run of the station's
    bridge, or a new one: the reckoning learnt anew); the P another front end's reader saw at
    10 s (after the STOP), read after the beat, and the P seen at 13 s are not stamped before
    the STOP sent again; a P seen at 8 s is refused here (review 30), stamped before it."""
    clock, link, fake = _link()
    t0 = clock.t
    clock.t = t0 + 9.0
    link.station_clock.heard(BASE + clock.t)
    link.send("rotor/stop", "stop", "DL1ABC", 5, until_heard=True, seen_s=clock.t, reader="pst")
    clock.t = t0 + 12.0
    _beat(link, BASE + clock.t + 0.25, station)  # (the new run's clock a little ahead)
    again = _stops(fake)[-1]
    with pytest.raises(Refused):  # (review 30: seen before the STOP)
        link.send(
            "rotor/target", '{"azimuth":200}', "DL1ABC", 5, seen_s=t0 + 8.0, after=AFTER,
            reader="rotctld gpredict",
        )  # fmt: skip
    _floor_alone(link)
    for seen, before in ((8.0, True), (10.0, False)):
        link.send(
            "rotor/target", '{"azimuth":200}', "DL1ABC", 5, seen_s=t0 + seen, after=AFTER,
            reader="rotctld gpredict",
        )  # fmt: skip
        move = fake.published[-1][1]
        assert (_sent(move) < _sent(again)) is before, (seen, _sent(move), _sent(again))
    clock.t = t0 + 13.0
    link.send(
        "rotor/target", '{"azimuth":200}', "DL1ABC", 5, seen_s=clock.t, after=AFTER,
        reader="rotctld gpredict",
    )  # fmt: skip
    assert _sent(fake.published[-1][1]) >= _sent(again)


def test_a_stop_kept_while_the_link_was_down_counts_from_when_it_was_asked() -> None:
    """Asked while down at 9 s (unstamped then: no reckoning is kept over a drop), sent on
    reconnect and again at the first beat at 20 s: stamped 9 s by that beat's reckoning, its
    stamp's expiry lengthened by the 11 s it was kept (so the station takes it as sent then);
    a move seen after it is not refused as before it."""
    clock, link, fake = _link()
    t0 = clock.t
    link.station_clock.heard(BASE + t0)
    link.connected.clear()
    clock.t = t0 + 9.0
    with pytest.raises(Refused):
        link.send("rotor/stop", "stop", "DL1ABC", 5, seen_s=clock.t, reader="rotctld")
    link.station_clock.forget()  # (as _closed does)
    link._opened(None)  # noqa: SLF001
    clock.t = t0 + 20.0
    _beat(link, BASE + clock.t)
    again = _stops(fake)[-1]
    assert _sent(again) == BASE + t0 + 9.0
    stamp_expiry = dict(again.UserProperty)["expiry"]  # type: ignore[attr-defined]
    assert float(stamp_expiry) >= 5 + 11
    assert again.MessageExpiryInterval == 5  # type: ignore[attr-defined]  # (the broker's)
    link.send(
        "rotor/target", '{"azimuth":200}', "DL1ABC", 5, seen_s=t0 + 10.0, after=AFTER,
        reader="other",
    )  # fmt: skip
    assert _sent(fake.published[-1][1]) >= _sent(again)


def test_the_same_stop_pressed_again_while_kept_counts_from_the_last_press() -> None:
    """Kept once however often it is pressed (rule 6), but stamped with the last press: a move
    seen between the two presses is refused here (review 30), and stamped before the STOP
    sent again."""
    clock, link, fake = _link()
    t0 = clock.t
    link.station_clock.heard(BASE + t0)
    link.connected.clear()
    for seen in (9.0, 11.0):
        clock.t = t0 + seen
        with pytest.raises(Refused):
            link.send("rotor/stop", "stop", "DL1ABC", 5, seen_s=clock.t, reader="pst")
    link.station_clock.forget()
    link._opened(None)  # noqa: SLF001
    clock.t = t0 + 12.0
    _beat(link, BASE + clock.t)
    again = _stops(fake)[-1]
    assert _sent(again) == BASE + t0 + 11.0
    with pytest.raises(Refused):
        link.send(
            "rotor/target", '{"azimuth":200}', "DL1ABC", 5, seen_s=t0 + 10.0, after=AFTER,
            reader="gpredict",
        )  # fmt: skip
    _floor_alone(link)
    link.send(
        "rotor/target", '{"azimuth":200}', "DL1ABC", 5, seen_s=t0 + 10.0, after=AFTER,
        reader="gpredict",
    )  # fmt: skip
    assert _sent(fake.published[-1][1]) < _sent(again)


def test_a_stop_kept_longer_than_the_station_takes_a_stamp_is_stamped_when_sent_again() -> None:
    """Kept over AGAIN_SEEN_MAX_S, its seen time would be older than the station's
    HALT_STAMP_MAX_S takes (it would count from when it came, refusing the moves seen right
    after): stamped when sent again; a move seen before that is refused (the safe side)."""
    clock, link, fake = _link()
    t0 = clock.t
    link.station_clock.heard(BASE + t0)
    link.connected.clear()
    with pytest.raises(Refused):
        link.send("rotor/stop", "stop", "DL1ABC", 5, seen_s=t0, reader="pst")
    link.station_clock.forget()
    link._opened(None)  # noqa: SLF001
    clock.t = t0 + AGAIN_SEEN_MAX_S + 5.0
    _beat(link, BASE + clock.t)
    again = _stops(fake)[-1]
    assert _sent(again) == BASE + clock.t
    assert float(dict(again.UserProperty)["expiry"]) == 5  # type: ignore[attr-defined]
    clock.t += 0.01
    link.send(
        "rotor/target", '{"azimuth":200}', "DL1ABC", 5, seen_s=clock.t, after=AFTER,
        reader="gpredict",
    )  # fmt: skip
    assert _sent(fake.published[-1][1]) >= _sent(again)
