"""The mailbox's rule 9 (session/mailbox.py): follow commands are commands like a track command;
what WSJT-X says and the wind are inputs, never dropped, the newest (the highest wind) kept."""

from __future__ import annotations

from bridge.core.model import Stop, Target
from bridge.session.follow import Follow, Heard
from bridge.session.mailbox import HEARD_KEPT, Mailbox
from bridge.session.tracking import Track


def test_follow_on_replaces_a_target_or_track_before_it_and_a_later_one_wins() -> None:
    box = Mailbox()
    try:
        box.put(Target(100.0))
        box.put_track(Track(None))
        box.put_follow(Follow(True))
        batch = box.take()
        assert batch.follow == Follow(True) and batch.target is None and batch.track is None
        box.put_follow(Follow(True))
        box.put(Target(50.0))  # later: kept, and the session lets it end following
        box.put_track(Track(None))  # later still: the follow command is dropped
        batch = box.take()
        assert batch.follow is None and batch.track is not None
        box.put(Target(50.0))
        box.put_follow(Follow(False))  # off ends nothing else
        batch = box.take()
        assert batch.target == Target(50.0) and batch.follow == Follow(False)
    finally:
        box.close()


def test_a_stop_or_lock_drops_a_follow_command_but_never_an_input() -> None:
    box = Mailbox()
    try:
        box.put_follow(Follow(True))
        box.put_heard(Heard("JA1ABC", "PM95", False))
        box.put_wind(70.0)
        box.put(Stop())
        batch = box.take()
        assert batch.follow is None and batch.stop is not None
        assert batch.heard == (Heard("JA1ABC", "PM95", False),)
        assert batch.wind_halted == 70.0 and batch.wind is None  # (kept, before the stop)
        box.put_follow(Follow(True))
        box.put_lock(True)
        assert box.take().follow is None
    finally:
        box.close()


def test_the_newest_status_and_the_highest_wind_of_a_batch_are_kept() -> None:
    box = Mailbox()
    try:
        box.put_heard(Heard("A", "FN31", True))
        box.put_heard(Heard("A", "FN31", False))
        for kmh in (20.0, 95.0, 30.0):
            box.put_wind(kmh)
        batch = box.take()
        assert batch.heard == (Heard("A", "FN31", False),) and batch.wind == 95.0  # no gust lost
        assert bool(batch) and not box.take()
    finally:
        box.close()


def test_each_programs_newest_status_is_kept_in_the_order_put_and_a_flood_of_names_is_bounded() -> (
    None
):
    """Rule 9: a second program's status does not replace the followed one's (its
    "transmitting" would be lost); a flood of forged program names keeps HEARD_KEPT."""
    box = Mailbox()
    try:
        box.put_heard(Heard("JA1ABC", "PM95", False, "WSJT-X - 20m"))
        box.put_heard(Heard("JA1ABC", "PM95", True, "WSJT-X - 20m"))
        box.put_heard(Heard("W1AW", "FN31", False, "WSJT-X - 6m"))
        assert box.take().heard == (
            Heard("JA1ABC", "PM95", True, "WSJT-X - 20m"),
            Heard("W1AW", "FN31", False, "WSJT-X - 6m"),
        )
        for i in range(1000):
            box.put_heard(Heard("W1AW", "FN31", False, f"forged {i}"))
        heard = box.take().heard
        assert len(heard) == HEARD_KEPT and heard[-1].instance == "forged 999"
    finally:
        box.close()
