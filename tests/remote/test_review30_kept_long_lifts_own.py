"""Review 30 on interfaces/mqtt/remote.py rule 8 (f7386b2d): a halt kept over AGAIN_SEEN_MAX_S
is stamped when it goes again (T), and ``_publish_unawaited`` notes *that* stamp for its own
source (``_note_halt(topic, props, reader)``). That reader's moves are then lifted to T, the
halt's send time, not its seen time: rule 8's own words ("a move is lifted at most to its own
source's last halt's seen time, never to that halt's send time (a review: ``S`` then ``P``
read late behind a STOP from Home Assistant, the ``P`` lifted to the ``S``'s send time,
turned the rotor)").

Sequence: rotctld's ``S`` at t0 while the link is down (kept: RPRT -6); the same client's ``P``
reaches the remote at t0 + 30.5 and waits unread (the computer busy); at the station Home
Assistant's STOP at t0 + 30.8; the link is back and the first beat comes at t0 + 31, the
kept S goes again stamped t0 + 31 (kept over 30 s), noted for rotctld; the thread reads the P
now: lifted to t0 + 31, after Home Assistant's STOP, and the station turns the rotor. Stamped
at its seen time it would be refused (the safe side the rule promises for a halt kept so
long: "a move seen before that is refused").
"""

from __future__ import annotations

import pytest

from bridge.core.errors import Refused
from bridge.interfaces.mqtt.remote import AGAIN_SEEN_MAX_S
from tests.remote.test_attack5_floor_other_front_end import _link, _sent
from tests.remote.test_late_commands import paho_message

BASE = 1_700_000_000.0
AFTER = ("rotor/stop", "rotor/lock")


def test_a_stop_kept_long_does_not_lift_its_readers_move_to_when_it_goes_again() -> None:
    clock, link, fake = _link()
    t0 = clock.t
    link.station_clock.heard(BASE + t0)
    link.connected.clear()
    with pytest.raises(Refused):
        link.send("rotor/stop", "stop", "DL1ABC", 5, seen_s=t0, reader="rotctld")
    link.station_clock.forget()  # (as _closed does)
    link._opened(None)  # noqa: SLF001  # (reconnected: the kept S goes first, unstamped)
    clock.t = t0 + AGAIN_SEEN_MAX_S + 1.0
    beat = paho_message("rotor/bridge/heartbeat", f"{BASE + clock.t:.3f}".encode(), [])
    link._on_message(None, None, beat)  # noqa: SLF001  # the station heard: the S again
    again = [props for topic, props in fake.published if topic == "rotor/stop"][-1]
    assert _sent(again) == BASE + clock.t  # (kept over 30 s: stamped when sent again)
    clock.t += 0.1
    seen = t0 + AGAIN_SEEN_MAX_S + 0.5  # the same client's P, before Home Assistant's STOP
    home_assistant_stop = BASE + t0 + AGAIN_SEEN_MAX_S + 0.8
    link.send(
        "rotor/target", '{"azimuth":200}', "DL1ABC", 5, seen_s=seen, after=AFTER,
        reader="rotctld",
    )  # fmt: skip
    topic, move = fake.published[-1]
    assert topic == "rotor/target"
    assert _sent(move) < home_assistant_stop, (
        f"the P seen at {BASE + seen:.3f}, before a Home Assistant STOP at "
        f"{home_assistant_stop:.3f}, went out stamped {_sent(move):.3f}, the kept S's resend "
        "time: the station takes it for after its last halt and turns the rotor"
    )
