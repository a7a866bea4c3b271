"""Review 28 on interfaces/mqtt/remote.py rule 8 (82772ff4, the floor per reader): a move is
lifted to the stamp of its own reader's last halt, "or that went out again (a kept halt,
stamped when sent again)". A halt that goes again (``_publish_unawaited``) is noted under
``_AGAIN``, which every reader's move is lifted to: so the moment another front end's STOP
goes again, a move seen before that STOP (and before a STOP from Home Assistant at the
station) is lifted to the resend's stamp, after both, and the station turns the rotor.

Sequence (the remote on Windows: no FIONREAD, so the halt watchers' look does not count the
P's bytes, tcplines.py rule 9; or a logger port without kernel stamps): Gpredict's ``P 200 0``
reaches the remote's rotctld port at t=8 s and waits unread (its thread asleep over its
budget, the computer busy); at the station Home Assistant's STOP at 8.5 s; at 9 s the operator
presses STOP in PstRotator, which goes out while the station's bridge is not heard (or while
the link is down) and is kept to go again at the next live heartbeat (rule 6), at 12 s; then
the rotctld thread reads the P. Its seen time is 8 s; the attack-5 fix keeps it from being
lifted to PstRotator's STOP at 9 s, but the same STOP sent again at 12 s lifts it to 12 s. The
station's last halt is that resend (12 s): the P, stamped 12 s, is not before it, and turns
the rotor after two STOPs that both came after it was sent.
"""

from __future__ import annotations

import pytest

from bridge.core.errors import Refused
from tests.remote.test_attack5_floor_other_front_end import _floor_alone, _link, _sent
from tests.remote.test_late_commands import paho_message

BASE = 1_700_000_000.0
AFTER = ("rotor/stop", "rotor/lock")


@pytest.mark.parametrize("kept", ["station-unheard", "link-down"])
def test_a_move_seen_before_another_front_ends_stop_is_not_lifted_by_its_sending_again(
    kept: str,
) -> None:
    clock, link, fake = _link()
    t0 = clock.t
    clock.t = t0 + 9.0
    link.station_clock.heard(BASE + clock.t)
    if kept == "station-unheard":  # remote/rotator.py rule 3: sent now, and again when heard
        link.send(
            "rotor/stop", "stop", "DL1ABC", 5, until_heard=True, seen_s=t0 + 9.0, reader="pst"
        )
    else:  # rule 6: the link down (or being reset): kept, sent first on reconnect
        link.connected.clear()
        with pytest.raises(Refused):
            link.send("rotor/stop", "stop", "DL1ABC", 5, seen_s=t0 + 9.0, reader="pst")
        link.station_clock.forget()  # (as _closed does)
        link._opened(None)  # noqa: SLF001  # (reconnected: the kept STOP goes first)
    first_stop = BASE + t0 + 9.0  # the STOP's own time (its stamp, where it had one)
    clock.t = t0 + 12.0
    beat = paho_message("rotor/bridge/heartbeat", f"{BASE + clock.t:.3f}".encode(), [])
    link._on_message(None, None, beat)  # noqa: SLF001  # the station heard: the STOP again
    again = [props for topic, props in fake.published if topic == "rotor/stop"][-1]
    assert _sent(again) == first_stop  # (the resend keeps its first seen time: rule 8)
    fake.published.clear()

    # Gpredict's P, seen at t0 + 8 on another reader (before PstRotator's STOP, before a Home
    # Assistant STOP at t0 + 8.5 at the station), read only now
    def p_200() -> None:
        link.send(
            "rotor/target",
            '{"azimuth":200}',
            "DL1ABC",
            5,
            seen_s=t0 + 8.0,
            after=AFTER,
            reader="rotctld gpredict",
        )

    with pytest.raises(Refused):  # (review 30: refused here, seen before the STOP)
        p_200()
    assert not fake.published
    _floor_alone(link)
    p_200()
    ((topic, props),) = fake.published
    assert topic == "rotor/target"
    assert _sent(props) < first_stop, (
        f"the P seen at {BASE + t0 + 8.0:.3f}, before another front end's STOP "
        f"({first_stop:.3f}) and a Home Assistant STOP at {BASE + t0 + 8.5:.3f}, went out "
        f"stamped {_sent(props):.3f}, the STOP's resend: the station takes it for not older "
        "than its last halt and turns the rotor after both STOPs"
    )
