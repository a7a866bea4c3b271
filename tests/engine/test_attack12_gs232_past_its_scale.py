"""Attack 12: a GS-232 set up as a 360-degree model whose box answers past 360 (a 450-degree
rotor's box left at P45, the G-800DXA, G-1000DXA, G-2800DXA: ``+0400`` / ``AZ=400``). The codec
reads every GS-232 reply up to 450 (gs232.py rule 2), whatever the model's scale, so a reading
of 400 on a model whose azimuth is 0..360 (its limits too) is taken silently: the status shows
bearing 40 at rest, nothing on R/error, and the next target of 50 goes out as ``M050``: the rotor
runs 350 degrees the long way round, back through its whole travel, for a turn the operator saw
as 10 degrees. A reply past the model's scale is the box set up as another model, as a
Prosistel of the other family's width is (prosistel.py rule 6): said, never taken as a bearing
the judge counts from. In virtual time, the box a GS-232B emulator in its 450-degree setting."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge import emulators
from bridge.core.model import Target
from tests.engine.virtual import VirtualRotator

FAST = {"az_speed_deg_s": 6.0}


@pytest.mark.parametrize(
    ("model", "box"), [("gs232b-az", "gs232b-az-450"), ("gs232a", "gs232a-450")]
)
def test_a_reading_past_the_models_scale_is_said_and_never_turns_the_rotor_the_long_way(
    rig: Callable[..., VirtualRotator], model: str, box: str
) -> None:
    v = rig(model, connect=False)
    v.device = emulators.create(box, now=v.now, start_az_deg=400.0, **FAST)
    v.link_up()
    v.run_for(10)
    said = v.errors()  # the box answers past the scale of the model it is set up as
    t = v.now
    v.aim(Target(50.0, 0.0 if v.cfg.spec.has_elevation else None))
    lowest = v.truth().az_deg
    for _ in range(90):  # the long way round takes about a minute at 6 degrees a second
        v.run_for(1.0)
        lowest = min(lowest, v.truth().az_deg)
    assert said, "a reading of 400 from a 0..360 model was taken without a word"
    words = [r.message for r in said]
    assert any(f'model = "{box}"' in w and "P36" in w for w in words), words
    assert lowest >= 360.0, (
        f"the rotor at 400 ran down to {lowest:g} after a target of 50: "
        f"{[w for w in v.sent(since=t) if w[:1] in (b'M', b'W')]} (350 degrees the long way round)"
    )
