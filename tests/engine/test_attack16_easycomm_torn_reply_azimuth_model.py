"""Attack 16: an Easycomm azimuth model takes a reply torn by a stray line end for a clean one.

A rotor at rest at 150 answers ``AZ150.0 EL0.0`` LF. A line end the line adds after ``AZ15``
(a flipped or inserted byte) makes two lines: ``AZ15`` and ``0.0 EL0.0``. The second, junk in
front of an elevation, is line noise (easycomm.py rule 3: "a line with junk in front of the
reply, or junk anywhere in the exchange, makes its reading UNTRUSTED"), and it spoils the
reading held in the same exchange (link.py rule 9). On the az/el model it does. On an azimuth
model the codec calls it "an elevation from an azimuth model", harmless chatter, before it
looks at the junk in front: the torn ``AZ15`` stands as that exchange's reading. The doubt of
a reading at rest (controller.py rule 9) then counts it as the first of two: a re-poll answer
that loses a byte alike (``AZ15.0``) agrees with it, and the bridge shows the rotor at 15,
MOVING, stops it and says it turned without a command, though it never left 150. On the az/el
model the same two faults are a torn exchange and one doubted reading, never shown. At
start-up one torn reply is enough: the connection's first reading is not doubted, the rotor is
shown at 15 for a second, and a nudge of +10 then turns it from 150 down to 25.

In virtual time, the emulated box at 150; the next two answers read as given."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from bridge.core.model import Nudge, Origin, Source
from bridge.runtime.rotator import Rotator
from bridge.runtime.state_store import StateStore
from tests.engine.virtual import VirtualRotator

REST_DEG = 150.0
# the first answer torn by a line end after "AZ15"; the re-poll's with a byte lost
TORN = b"AZ15\n0.0 EL0.0\n"
SHORT = b"AZ15.0 EL0.0\n"
SHOWN_WITHIN_DEG = 1.0  # a still rotor's readings, in tenths, jitter by less
WHO = Origin(Source.MQTT, "DL1ABC")


def answers_read_as(v: VirtualRotator, *replies: bytes) -> list[bytes]:
    """The next answers (each from its first byte ``A`` through its LF; the box's output is
    paced a byte at a time) reach the host as ``replies``, one each; the list returned gets
    each one as it goes."""
    done: list[bytes] = []
    swapping = [False]

    def swap(data: bytes, now: float) -> bytes:
        if swapping[0]:
            swapping[0] = data != b"\n"
            return b""
        if data == b"A" and len(done) < len(replies):
            done.append(replies[len(done)])
            swapping[0] = True
            return done[-1]
        return data

    v.to_host = swap
    return done


@pytest.mark.parametrize(
    "model",
    [
        "easycomm2",
        "easycomm2-az",
        "easycomm3-az",
    ],
)
def test_a_reply_torn_by_a_line_end_is_no_reading_on_an_azimuth_model(
    rig: Callable[..., VirtualRotator], model: str
) -> None:
    v = rig(model, emulator={"start_az_deg": REST_DEG})
    v.run_until(lambda h: h.status.bearing_deg == REST_DEG, 10, "at rest at 150")
    v.run_for(3)  # settled at rest
    t = v.now
    swapped = answers_read_as(v, TORN, SHORT)
    v.run_until(lambda h: len(swapped) == 2, 5, "both answers read as given")
    v.run_for(5)
    shown = [s.bearing_deg for s in v.published(since=t) if s.bearing_deg is not None]
    stops = [f.data for f in v.frames("stop", since=t)]
    assert v.truth().az_deg == REST_DEG  # (the box never turned)
    assert all(abs(b - REST_DEG) <= SHOWN_WITHIN_DEG for b in shown), (
        f"a rotor standing at {REST_DEG:g} was shown at {shown} after a torn reply"
    )
    assert not stops, f"a rotor at rest was stopped for a torn reply: {stops}"
    assert not [e.message for e in v.errors("stop", since=t)]


# One torn reply is enough at start-up: the connection's first reading is not doubted
# (controller.py rule 9), so the torn ``AZ15`` is the bearing shown until the next idle poll, a
# second later, and a nudge judged from it in that time turns the rotor the wrong way, the
# whole way down to 25 for a nudge of +10 (the az/el model drops the torn exchange, asks again,
# and the nudge goes to 160).
NUDGE_DEG = 10.0
WATCH_S = 40  # the turn at 6 degrees a second, with room


@pytest.mark.parametrize(
    "model",
    [
        "easycomm2",
        "easycomm2-az",
    ],
)
def test_a_nudge_after_a_torn_first_reply_turns_the_rotor_by_the_nudge(
    tmp_path: Path, model: str
) -> None:
    v = VirtualRotator(model, emulator={"start_az_deg": REST_DEG}, connect=False)
    answers_read_as(v, TORN)
    v.link_up()
    v.run_until(lambda h: h.status.available, 5, "the controller answers")
    rot = Rotator(v.cfg, StateStore(tmp_path / "state.json"), lambda s: None, lambda e: None)
    v.mailbox.close()  # the judge's mailbox, as test_halt_epoch's Bench takes it
    v.mailbox = rot._mailbox
    rot._worker.session = v.session
    try:
        shown = rot.status.bearing_deg
        rot.submit(Nudge(NUDGE_DEG, source=Source.MQTT, origin=WHO), "nudge +10")
        v._take()
        lowest = REST_DEG
        for _ in range(WATCH_S):
            v.run_for(1.0)
            lowest = min(lowest, v.truth().az_deg)
        assert lowest >= REST_DEG - SHOWN_WITHIN_DEG, (
            f"a nudge of +{NUDGE_DEG:g} at {REST_DEG:g} (shown {shown}) turned the rotor down "
            f"to {lowest:g}: {[f.data for f in v.frames('move')]}"
        )
        assert v.truth().az_deg == pytest.approx(REST_DEG + NUDGE_DEG, abs=SHOWN_WITHIN_DEG)
    finally:
        rot.operators.stop()
        v.close()
