"""Review 98: a composite's azimuth box that is an az/el GS-232 is offline for good when its own,
unused, elevation channel reads past base.py rule 10's slack.

axes.py rule 1: an az/el box driving a composite's azimuth has its elevation "never turned and
never read"; every target carries back the elevation the box last said, clamped "within the
box's own elevation range" (``AzimuthOfAzEl.encode_target``: an elevation outside it is
expected there). But the GS-232 codec judges that elevation first (gs232.py rule 2, its range
check now ``read_in_range`` with READ_SLACK_DEG): ``EL=181`` .. ``EL=183`` are read as 180, and
``EL=184`` on spoils the whole reply, the azimuth in it too. A G-5500's box whose elevation
input reads past its scale (nothing on it: the elevation is another box's) gives the bridge no
azimuth reading at all: the rotator goes offline and no target turns the azimuth, though the
azimuth the box says is fine (R/error: "answers only garbled replies: the wrong baud rate or
model, or a noisy line?", nothing of the elevation). The mirror of review 49 (the elevation
box's own azimuth, now judged by no scale). Found in the line review 98 rewrote; older than it.

The same in the Easycomm codec (its elevation past 180.5), and the RC2800's (past 180.5) and
the Combi-Track's (unit B past 90.5).

Fixed: AzimuthOfAzEl tells such a codec its elevation is never read (base.py ScalesElevation,
rule 10): that elevation is judged by no range (tests/protocols/test_review98_*, every codec).

In virtual time: the azimuth box a GS-232B (an Easycomm III, an RC2800, a Combi-Track)
emulator whose answers say its elevation as 190 (181.0, 181.0, 95.0).
"""

from __future__ import annotations

import re
from collections.abc import Callable

import pytest

from bridge.core.model import Target
from bridge.protocols.axes import Axis
from tests.engine.virtual_composite import VirtualComposite


def elevation_read_as(form: bytes, said: bytes) -> Callable[[bytes, float], bytes]:
    """Each answer line handed on whole at its end, its elevation (``form``, a pattern) said
    as ``said``."""
    line = bytearray()

    def rewrite(data: bytes, now: float) -> bytes:
        line.extend(data)
        end = max(line.rfind(b"\r"), line.rfind(b"\n")) + 1
        whole = bytes(line[:end])
        del line[:end]
        return re.sub(form, said, whole)

    return rewrite


# model, its elevation in its replies, the same past base.py rule 10's slack
CASES = [
    ("gs232b", rb"EL=\d{3}", b"EL=190"),  # a pot read in whole degrees: 3 past 180
    ("easycomm3", rb"EL-?\d+(?:\.\d*)?", b"EL181.0"),  # a sensor read in tenths: half a degree
    ("rc2800", rb"E P=\s*-?\d+(?:\.\d+)?", b"E P= 181.0"),  # tenths: half a degree
    ("prosistel-combi", rb"B,\?,\d{4}", b"B,?,0950"),  # tenths: half a degree past 90
]


@pytest.mark.parametrize(("model", "form", "said"), CASES)
def test_an_azimuth_box_own_elevation_past_its_scale_leaves_its_azimuth_read_and_turned(
    model: str, form: bytes, said: bytes
) -> None:
    with VirtualComposite(
        model,
        model,
        emulators={
            Axis.AZIMUTH: {"start_az_deg": 120.0, "start_el_deg": 0.0},
            Axis.ELEVATION: {"start_el_deg": 45.0},
        },
    ) as v:
        v.az.to_host = elevation_read_as(form, said)  # its elevation input: nothing on it
        v.run_for(20)
        told = [e.message for e in v.az.errors()]
        assert v.status.available, told
        v.aim(Target(130.0, 30.0))
        v.run_for(60)
        told = [e.message for e in v.az.errors()]
        assert v.az.truth().az_deg == 130.0, told
        assert (v.status.bearing_deg, v.status.elevation_deg) == (130.0, 30.0), told
