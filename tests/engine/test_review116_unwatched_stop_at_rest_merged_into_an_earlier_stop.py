"""Review 116: the unwatched stop at rest is merged into a STOP written before the hand began
turning: nothing goes on the wire, R/error says "it was stopped", and the hand's turn runs eight
idle polls more, past ``az_min_deg``.

controller.py rule 9 (review 103's follow-up, f23b2118): readings at rest that go on disagreeing
get the unwatched stop at each FIRST_UNWATCHED_READINGS (8) of them, "merged as stops.py rule 1
merges, the lock's stop a brake window before being that stop" (``self.stop(now, merge=True)``).
stops.py rule 1 merges a stop into one written within the brake window (a Rotor-EZ's 5 s) unless
"a reading since that stop showed the rotor turning": at rest on a line gone bad no reading is
ever taken, so none can show it. An operator's STOP to a rotor at rest (or any stop) followed
within the brake window by a hand at the panel: the eighth disagreeing reading comes 1.7 s into
the hand's turn, the unwatched stop is merged into the earlier STOP (which the hand came after),
"8 readings in a row at rest do not agree ... so it was stopped" is said, and no stop frame is
written; the next goes eight idle polls later, 8.5 s into the turn, at about 99: past
``az_min_deg`` 110. The same line without the earlier STOP is stopped 1.7 s in, at about 140.

In virtual time: the emulated Rotor-EZ at rest at 150 (``az_min_deg`` 110), confirmed on a clean
line; an operator's STOP; then every azimuth answer reaches the host off by +60 or -60 in turn (a
line gone bad, never back where it stood); half a second after the STOP, a hand turns the rotor
down to 5.

The same merge swallows the unwatched stop's own next one where the brake window is longer than
eight idle polls: an Easycomm configured with ``brake_delay_s`` 10 (a brake as a HAM-IV's, set
long), its line gone bad at rest, its first unwatched stop out, turned by hand a moment later:
the sixteenth disagreeing reading's stop (about 7 s in) is merged into the first, and the next
goes 14.6 s in, at about 62, past ``az_min_deg`` 100; the stops go 15 s apart, every other one
merged away (with no brake window they go 7 s apart). The second test.
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import ErrorKind
from tests.engine.garblers import every_answer_off, every_rotorez_answer_off, limited, lowest_az
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
AZ_MIN_DEG = 110.0
OFFSETS = [60.0, -60.0]
CONFIRMED_S = 15.0  # the start's readings on a clean line (virtual time, not a deadline)
STOP_OUT_S = 0.3  # the STOP written (virtual time)
HAND_AFTER_S = 0.2  # the hand comes this long after the line goes bad (virtual time)
WATCH_S = 60.0  # 145 degrees at the box's speed, with room (virtual time)
UNWATCHED = "readings in a row at rest do not agree"


def _turned_by_hand(rig: Rig, stop_first: bool) -> tuple[VirtualRotator, float, float]:
    v = limited(rig, "rotorez", REST_DEG, AZ_MIN_DEG)
    v.link_up()
    v.run_for(CONFIRMED_S)
    assert v.status.available and v.status.bearing_deg == REST_DEG  # (confirmed, clean line)
    if stop_first:
        v.stop()  # (an operator's STOP to a rotor at rest)
    v.run_for(STOP_OUT_S)
    v.to_host = every_rotorez_answer_off(OFFSETS)
    v.run_for(HAND_AFTER_S)
    t = v.now
    v.manual_rotate(5.0)  # (a hand at the panel, after the STOP, towards the limit)
    return v, t, lowest_az(v, t + WATCH_S, REST_DEG)


def test_without_an_earlier_stop_the_hand_is_stopped_before_the_limit(rig: Rig) -> None:
    """The premise: the same line and hand, no STOP before, is stopped well short of it."""
    _, _, lowest = _turned_by_hand(rig, stop_first=False)
    assert lowest >= AZ_MIN_DEG


def test_a_hand_after_a_stop_at_rest_gets_the_unwatched_stop_on_the_wire(rig: Rig) -> None:
    v, t, lowest = _turned_by_hand(rig, stop_first=True)
    said = [(round(at - t, 1), e.message) for at, e in v.events if at >= t]
    said = [(at, m) for at, m in said if UNWATCHED in m]
    stops = [round(f.time_s - t, 1) for f in v.frames("stop", since=t)]
    assert said  # (the unwatched stop was made, and said)
    assert all(e.kind == ErrorKind.STOP for at, e in v.events if at >= t and UNWATCHED in e.message)
    assert stops and stops[0] <= said[0][0], (
        f"said {said[0][0]} s into the hand's turn that the rotor was stopped; stops written "
        f"{stops} s in"
    )
    assert lowest >= AZ_MIN_DEG, (
        f"turned unstopped from {REST_DEG:g} down to {lowest:g}, past az_min_deg "
        f"{AZ_MIN_DEG:g}; stops written {stops} s into the turn"
    )


LONG_BRAKE_S = 10.0  # a brake window longer than eight idle polls (a setting, not a deadline)
FIRST_STOP_S = 60.0  # eight readings at the moving rate, with room (virtual time)
EASYCOMM_MIN_DEG = 100.0


def test_the_next_unwatched_stop_is_not_merged_into_the_first(rig: Rig) -> None:
    v = rig(
        "easycomm2",
        emulator={"start_az_deg": REST_DEG},
        settings={"az_min_deg": EASYCOMM_MIN_DEG, "brake_delay_s": LONG_BRAKE_S},
        connect=False,
    )
    v.link_up()
    v.run_for(CONFIRMED_S)
    assert v.status.available and v.status.bearing_deg == REST_DEG  # (confirmed, clean line)
    v.to_host = every_answer_off(OFFSETS)
    t0 = v.now
    v.run_until(lambda h: bool(h.frames("stop", since=t0)), FIRST_STOP_S, "the unwatched stop")
    v.run_for(HAND_AFTER_S)
    t = v.now
    v.manual_rotate(5.0)  # (a hand at the panel after the first unwatched stop)
    lowest = lowest_az(v, t + WATCH_S, REST_DEG)
    stops = [round(f.time_s - t, 1) for f in v.frames("stop", since=t)]
    assert lowest >= EASYCOMM_MIN_DEG, (
        f"turned unstopped from {REST_DEG:g} down to {lowest:g}, past az_min_deg "
        f"{EASYCOMM_MIN_DEG:g}; stops written {stops} s into the turn"
    )
