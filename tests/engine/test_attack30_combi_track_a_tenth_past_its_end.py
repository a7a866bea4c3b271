"""Attack 30: a Prosistel Combi-Track whose encoder reads a tenth past an end of its range is
offline for good, and one jittering there is told as junk every 30 s.

The Combi-Track says its positions in tenths (prosistel.py rule 6), and its spec allows a still
rotor's readings to wander ``noise_deg`` = 0.2 (an encoder read in tenths). At the ends of its
range, azimuth 360.0 (north, where a wrapping scale's travel ends: a target of 360 goes there)
and elevation 90.0, such a wander is past the range, and prosistel.py rule 1 spoils it ("values
beyond the unit's range ... are spoiled"), with no slack (gs232.py rule 2 reads up to 3 degrees
past a GS-232's 360 as 360; easycomm.py rule 2 half a degree either side of 0 and 360):

- an encoder that settles a tenth past the end (``A,?,3601`` at north, ``B,?,0901`` at the
  zenith) gives no reading at all: the rotator goes offline ("answers only garbled replies
  ...: a noisy line?") and the next target never turns it back; the operator has to go to
  the box;
- one that wanders a tenth either side of the end has every other such reply told on R/error,
  "controller sent 12 bytes that are no valid reply", again and again while the rotor rests.

In virtual time: the emulated box turned to the end; from then on the line says that unit's
answers as the encoder past the end would (``3600`` read as ``3601``, or in turn 3601, 3600,
3599, 3600).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable

import pytest

from tests.engine.test_attack30_gs232_450_a_degree_past_its_end import read_past_the_end
from tests.engine.virtual import VirtualRotator

CASES = [
    # unit, what it says at the end, the target that takes it there, the one to turn it back
    (b"A", b"3600", (360.0, 10.0), (300.0, 10.0)),
    (b"B", b"0900", (300.0, 90.0), (300.0, 45.0)),
]
REST_S = 300  # five minutes at rest, ten junk report intervals


def read_as(unit: bytes, said: bytes, *read: bytes) -> Callable[[bytes, float], bytes]:
    """Each answer line handed on whole at its CR; ``unit``'s position ``said`` read as each of
    ``read`` in turn."""
    line = bytearray()
    values = itertools.cycle(read)
    key = b"\x02" + unit + b",?," + said + b","

    def rewrite(data: bytes, now: float) -> bytes:
        line.extend(data)
        out = b""
        while b"\r" in line:
            end = line.index(b"\r") + 1
            whole = bytes(line[:end])
            del line[:end]
            if key in whole:
                whole = whole.replace(key, b"\x02" + unit + b",?," + next(values) + b",")
            out += whole
        return out

    return rewrite


def at_the_end(rig: Callable[..., VirtualRotator], target: tuple[float, float]) -> VirtualRotator:
    v = rig("prosistel-combi", emulator={"start_az_deg": 300.0, "start_el_deg": 80.0})
    v.run_for(5)
    v.target(*target)
    v.run_until(
        lambda h: (h.truth().az_deg, h.truth().el_deg) == target and not h.truth().is_moving,
        30,
        "at the end",
    )
    v.run_for(5)  # at rest there
    return v


@pytest.mark.parametrize(("unit", "said", "target", "back"), CASES)
def test_a_combi_track_a_tenth_past_its_end_is_still_turned_back(
    rig: Callable[..., VirtualRotator],
    unit: bytes,
    said: bytes,
    target: tuple[float, float],
    back: tuple[float, float],
) -> None:
    v = at_the_end(rig, target)
    past = b"%04d" % (int(said) + 1)
    v.to_host = read_as(unit, said, past)  # the encoder a tenth past the end
    v.run_for(20)
    v.target(*back)
    v.run_for(60)
    told = [e.message for e in v.errors()]
    assert (v.truth().az_deg, v.truth().el_deg) == back, told
    assert v.status.available, told


@pytest.mark.parametrize(("unit", "said", "target", "back"), CASES)
def test_a_combi_track_wandering_a_tenth_at_its_end_is_not_told_as_junk(
    rig: Callable[..., VirtualRotator],
    unit: bytes,
    said: bytes,
    target: tuple[float, float],
    back: tuple[float, float],
) -> None:
    v = at_the_end(rig, target)
    t = v.now
    wander = (int(said) + 1, int(said), int(said) - 1, int(said))
    v.to_host = read_as(unit, said, *(b"%04d" % n for n in wander))
    v.run_for(REST_S)
    assert v.status.available
    assert not [e.message for e in v.errors(since=t)]


# The same on a D, in whole degrees (its spec's noise_deg 1.0): an azimuth box at its 360 end
# whose pot says ``A,?,361``, and a D turning an elevation of its own (prosistel-el) at its 90
# end saying ``E,?,091``: offline for good, never turned back.
D_CASES = [
    ("prosistel", {"start_az_deg": 330.0}, b"\x02A,?,360,", b"\x02A,?,361,", 360.0, 300.0),
    ("prosistel-el", {"start_el_deg": 80.0}, b"\x02E,?,090,", b"\x02E,?,091,", 90.0, 45.0),
]


@pytest.mark.parametrize(("model", "emulator", "said", "read", "end", "back"), D_CASES)
def test_a_prosistel_d_a_degree_past_its_end_is_still_turned_back(
    rig: Callable[..., VirtualRotator],
    model: str,
    emulator: dict[str, float],
    said: bytes,
    read: bytes,
    end: float,
    back: float,
) -> None:
    v = rig(model, emulator=emulator)
    v.run_for(5)
    v.target(end)
    v.run_until(lambda h: h.status.raw_bearing_deg == end and not h.truth().is_moving, 30, "end")
    v.run_for(5)  # at rest there
    v.to_host = read_past_the_end(said, read)  # the pot a degree past the end
    v.run_for(20)
    v.target(back)
    v.run_for(60)
    told = [e.message for e in v.errors()]
    assert v.status.available and v.status.raw_bearing_deg == back, told
