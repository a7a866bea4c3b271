"""Review 123: a GS-232B (or GS-232A, RC2800) or a SatEL at rest whose line then garbles
every byte (its line ends too) gets no unwatched stop in time: a hand at the panel turns it
from 150 past ``az_min_deg`` 100, a GS-232B to its end with no stop ever written,
a SatEL to about 17.

controller.py rule 9 (review 116's third fix, 40a3ae59): "a poll answered garbled past parsing at
rest counts as one of them [readings at rest that confirmed none], as a first reading's does";
FIRST_UNWATCHED_READINGS (8) in a row get the unwatched stop, and "answers torn at rest too, from
the third on" are asked at the moving rate. The promise: a hand turn at rest on a bad line is
stopped before a limit on every model. Measured: on a line that XORs every byte with 0x5A
(review 113's ``torn``), a GS-232B is polled about once a second, each exchange waiting out its
reply time, the first torn answer of a run not counted (link.py rule 11): rule 2 takes it
offline ('answers only garbled replies', 6 s) before the eighth (a GS-232A and an RC2800
the same), and nothing counts offline
(``_rest_phase`` wants it answering); the hand runs on to 5, no stop frame written. A SatEL is
polled every 2 s throughout (never the moving rate): the eighth comes 16.6 s into the hand's
turn, at 6 deg/s about 17, 83 degrees past the limit. An Easycomm II on the same line is
stopped 3.8 s in, at about 127 (the premise, the first test). The parent of review 116's fixes
wrote no stop on any model: the fix is incomplete, not a regression.

In virtual time: the emulated box at rest at 150 (``az_min_deg`` 100), confirmed on a clean
line; then every byte it sends reaches the host XORed with 0x5A, and a hand turns the rotor down
to 5 at the box's speed.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.engine.garblers import confirmed_at_rest, limited, lowest_az
from tests.engine.test_review113_every_byte_garbled_unwatched import torn
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
AZ_MIN_DEG = 100.0
CONFIRMED_S = 15.0  # the start's readings on a clean line (virtual time, not a deadline)
WATCH_S = 60.0  # 145 degrees at 6 deg/s, with room (virtual time)


def _hand_on_a_torn_line(rig: Rig, model: str) -> tuple[VirtualRotator, float, float]:
    v = confirmed_at_rest(rig, model, REST_DEG, AZ_MIN_DEG, CONFIRMED_S)
    v.to_host = torn
    t = v.now
    v.manual_rotate(5.0)  # (a hand at the panel, towards the limit)
    return v, t, lowest_az(v, t + WATCH_S, REST_DEG)


def test_the_premise_an_easycomm_on_the_same_line_is_stopped_before_the_limit(rig: Rig) -> None:
    _, _, lowest = _hand_on_a_torn_line(rig, "easycomm2")
    assert lowest >= AZ_MIN_DEG


@pytest.mark.xfail(
    strict=True,
    reason="review 123: a hand turn at rest on a line that garbles every byte runs past "
    "az_min_deg (GS-232A/B, RC2800: no stop, offline first; SatEL: stopped 16.6 s in, at 17)",
)
@pytest.mark.parametrize("model", ["gs232b", "gs232a", "rc2800-az", "satel"])
def test_a_hand_turn_at_rest_on_a_line_garbling_every_byte_is_stopped_before_the_limit(
    rig: Rig, model: str
) -> None:
    v, t, lowest = _hand_on_a_torn_line(rig, model)
    stops = [round(f.time_s - t, 1) for f in v.frames("stop", since=t)]
    said = [e.message for e in v.errors(since=t)]
    assert lowest >= AZ_MIN_DEG, (
        f"{model}: turned unstopped from {REST_DEG:g} down to {lowest:g}, past az_min_deg "
        f"{AZ_MIN_DEG:g}; stops written {stops} s into the turn; said: {said}"
    )


LOCK_S = 5.0  # the lock's ON taken and its stop out (virtual time)


@pytest.mark.xfail(
    strict=True,
    reason="review 123: with the lock ON, a hand turn on a GS-232B whose line garbles every "
    "byte runs past az_min_deg to 5: neither the lock's stop nor the unwatched one is written",
)
def test_a_locked_gs232b_on_a_line_garbling_every_byte_is_stopped_before_the_limit(
    rig: Rig,
) -> None:
    """The same with the lock ON: torn answers are no sign for the lock's stop (stops.py rule 7
    takes only readings that parse and are doubted), and the unwatched count never reaches eight
    before the offline: the rotor the operator locked turns from 150 to 5, no stop written."""
    v = limited(rig, "gs232b", REST_DEG, AZ_MIN_DEG)
    v.link_up()
    v.run_for(CONFIRMED_S)
    v.lock(True)
    v.run_for(LOCK_S)
    assert v.status.available and v.status.bearing_deg == REST_DEG  # (confirmed, clean line)
    v.to_host = torn
    t = v.now
    v.manual_rotate(5.0)  # (a hand at the panel of a locked rotor, towards the limit)
    lowest = lowest_az(v, t + WATCH_S, REST_DEG)
    stops = [round(f.time_s - t, 1) for f in v.frames("stop", since=t)]
    assert lowest >= AZ_MIN_DEG, (
        f"locked, turned unstopped from {REST_DEG:g} down to {lowest:g}, past az_min_deg "
        f"{AZ_MIN_DEG:g}; stops written {stops} s into the turn"
    )
