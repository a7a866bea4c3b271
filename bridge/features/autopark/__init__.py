"""Auto-park, as one feature (bridge/feature.py): a rotator parks by itself after a quiet
spell (``park_after_idle_s``; a windy remote site).

What it is made of:
- its key: ``park_after_idle_s`` in ``[[rotators]]`` (settings/pointing.py, checked there
  with the park position it needs, so it stays among the pointing keys);
- its session part: session/autopark.py ``AutoPark``, run by the session's step as ``PART``
  here says (after the wind's, in the registry's order: it waits while the wind parks);
- what users see of it: a park like any, its source ``auto-park`` in ``R/status`` and the
  audit (the core's), a refused park on ``R/error``; no topic, block or entity of its own;
- here: its declaration.
"""

from __future__ import annotations

from pydantic import BaseModel

from bridge.feature import Feature
from bridge.session.autopark import AutoPark
from bridge.session.parts import Part, Wake
from bridge.session.session import RotatorSession
from bridge.settings.pointing import PointingFields

NAME = "autopark"


def _configured(r: BaseModel) -> bool:
    return isinstance(r, PointingFields) and r.park_after_idle_s > 0


def _reset(s: RotatorSession, now: float) -> None:
    s.autopark = AutoPark(s.cfg)
    s.autopark.activity(now)


# its session part (parts.py rule 4)
PART: Part[RotatorSession] = Part(
    "auto-park",
    Wake.STEP,  # a turning rotor's every step starts its quiet spell again
    True,
    lambda s: s.autopark.on,
    # (in a storm the wind's park is the park: auto-park waits, its wake-up still asked for)
    lambda s, scene: None if s.wind.storm else s.autopark.step(scene),
    _reset,
    lambda s, now: s.autopark.wakeup(now),
)

FEATURE = Feature(
    name=NAME,
    docs="docs/pointing.md#presets-park-and-nudge",
    summary="parks the rotator by itself after a quiet spell",
    configured=_configured,
    part=PART,
)
