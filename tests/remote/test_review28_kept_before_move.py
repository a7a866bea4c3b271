"""Review 28 on interfaces/mqtt/remote.py rules 6 and 8: a move asked after a halt kept for the
station's return (``until_heard``: the station's bridge flapped on its broker, and takes moves
before its first heartbeat comes: tests/remote/test_stalled_link.py) sends the halt first
(``_send_unheard_before``), stamped with the reckoning *then*; but the move's own stamp was
made before that, from its seen time (the look that read it, a few milliseconds earlier),
and is not lifted to the halt that now goes just ahead of it (the floor was read before the
halt was sent again). The station compares the two stamps (service.py rule 9): the move is
"sent before the last STOP or lock ON" and refused, while its client got ``RPRT 0`` and
rule 6 says it goes after the STOP.
"""

from __future__ import annotations

from tests.remote.test_attack5_floor_other_front_end import _link, _sent

BASE = 1_700_000_000.0
AFTER = ("rotor/stop", "rotor/lock")


def test_a_move_sent_right_after_a_kept_stop_is_not_stamped_before_it() -> None:
    clock, link, fake = _link()
    t0 = clock.t
    link.station_clock.heard(BASE + t0)
    # the operator's S while the station's bridge is not heard: sent, kept for its return
    link.send("rotor/stop", "stop", "DL1ABC", 5, until_heard=True, seen_s=t0, reader="rotctld")
    # the station's bridge back on its broker (no heartbeat yet); 2 s after the S, the same
    # client's P, seen at its look and handed to the link 5 ms later
    clock.t = t0 + 2.005
    link.send(
        "rotor/target",
        '{"azimuth":100}',
        "DL1ABC",
        5,
        lambda: None,  # (its check: a move, rule 9)
        seen_s=t0 + 2.0,
        after=AFTER,
        reader="rotctld",
    )
    (_, first), (again_topic, again), (move_topic, move) = fake.published
    assert again_topic == "rotor/stop" and move_topic == "rotor/target"  # (rule 6's order)
    assert _sent(move) >= _sent(again), (
        f"the P went out right after the STOP sent again ({_sent(again):.3f}), stamped "
        f"{_sent(move):.3f}: the station refuses it as sent before its last STOP"
    )
