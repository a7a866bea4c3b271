"""Attack 30: a GS-232 450-degree model whose pot reads a degree past 450 is offline for good.

gs232.py rule 2: "Up to AZ_DRIFT_DEG past [the top of this model's scale] is a pot calibrated a
little short of its end, read as the end". On the 360-degree models it is: a box resting at its
360 end that says ``AZ=361`` reads as 360 and is turned back by the next target. On the
450-degree models (``gs232a-az-450``, ``gs232b-az-450``, ``gs232b-450``: a G-800DXA, G-1000DXA,
G-2800DXA at P45, whose overlap is real) the codec calls any azimuth past AZ_MAX_DEG (450)
"position out of range" (SPOILED) before it looks at the drift: a rotor parked at its 450 end
whose pot says 451 gives no reading at all. The rotator goes offline ("answers only garbled
replies ...: a noisy line?") and a target of 350 never turns it back: the operator has to go to
the controller.

In virtual time: the emulated box turned to its 450 end; from then on the line says its answers
a degree further (``AZ=450`` read as ``AZ=451``, ``+0450`` as ``+0451``: a pot a degree past).
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.engine.virtual import VirtualRotator

END_DEG = 450.0
BACK_DEG = 350.0  # raw: a hundred degrees back from the end, on the same wrap


def read_past_the_end(said: bytes, read: bytes) -> Callable[[bytes, float], bytes]:
    """Each answer line handed on whole at its CR, ``said`` in it read as ``read``."""
    line = bytearray()

    def rewrite(data: bytes, now: float) -> bytes:
        line.extend(data)
        out = b""
        while b"\r" in line:
            end = line.index(b"\r") + 1
            whole = bytes(line[:end])
            del line[:end]
            out += whole.replace(said, read)
        return out

    return rewrite


@pytest.mark.parametrize(
    ("model", "said", "read"),
    [
        ("gs232b-az-450", b"AZ=450", b"AZ=451"),
        ("gs232a-az-450", b"+0450", b"+0451"),
        ("gs232b-450", b"AZ=450", b"AZ=451"),
    ],
)
def test_a_450_degree_gs232_a_degree_past_its_end_is_still_turned_back(
    rig: Callable[..., VirtualRotator], model: str, said: bytes, read: bytes
) -> None:
    el = None if "-az" in model else 0.0
    v = rig(model, emulator={"start_az_deg": 440.0})
    v.run_for(5)
    v.target(END_DEG, el)
    v.run_until(lambda h: h.truth().az_deg == END_DEG and not h.truth().is_moving, 30, "at 450")
    v.run_for(5)  # at rest at its end
    v.to_host = read_past_the_end(said, read)  # the pot a degree past the end
    v.run_for(20)
    v.target(BACK_DEG, el)
    v.run_for(60)
    told = [e.message for e in v.errors()]
    assert v.truth().az_deg == BACK_DEG, told
    assert v.status.available, told
