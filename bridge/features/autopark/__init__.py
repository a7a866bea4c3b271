"""Auto-park, as one feature (bridge/feature.py): a rotator parks by itself after a quiet
spell (``park_after_idle_s``; a windy remote site).

What it is made of:
- its key: ``park_after_idle_s`` in ``[[rotators]]`` (settings/pointing.py, checked there
  with the park position it needs, so it stays among the pointing keys);
- its session part: session/autopark.py ``AutoPark`` (the session owns the order of its parts);
- what users see of it: a park like any, its source ``auto-park`` in ``R/status`` and the
  audit (the core's), a refused park on ``R/error``; no topic, block or entity of its own;
- here: its declaration.
"""

from __future__ import annotations

from pydantic import BaseModel

from bridge.feature import Feature
from bridge.settings.pointing import PointingFields

NAME = "autopark"


def _configured(r: BaseModel) -> bool:
    return isinstance(r, PointingFields) and r.park_after_idle_s > 0


FEATURE = Feature(
    name=NAME,
    docs="docs/pointing.md#presets-park-and-nudge",
    summary="parks the rotator by itself after a quiet spell",
    configured=_configured,
    part="bridge.session.autopark:AutoPark",
)
