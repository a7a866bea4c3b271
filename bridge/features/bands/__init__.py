"""The band map, as one feature (bridge/feature.py): which rotator's antenna is for which band
(``bands = ["20m", "15m"]`` in ``[[rotators]]``), so that a message naming a band turns the
antenna on the radio's band.

What it is made of:
- its key: settings/bands.py ``BandFields`` (the rotator's table includes it; no two rotators
  share a band: settings/), the bands by name: core/bands.py;
- its readers: an N1MM rotor message to a shared name or ``*`` (interfaces/loggers/commands.py rule
  5) and following WSJT-X (session/follow.py rule 9), each with the rotator's ``bands`` handed
  over by the app; no topic, block, entity or part of its own;
- here: its declaration (its section in docs/configuration.md comes from it).
"""

from __future__ import annotations

from pydantic import BaseModel

from bridge.feature import Feature
from bridge.settings.bands import BandFields

NAME = "bands"


def _configured(r: BaseModel) -> bool:
    return isinstance(r, BandFields) and bool(r.bands)


FEATURE = Feature(
    name=NAME,
    docs="docs/loggers.md#one-antenna-per-band",
    summary="turns the antenna that is on the radio's band, for loggers and WSJT-X",
    rotator_settings=BandFields,
    settings_section=(
        "Bands (per rotator)",
        "The bands the rotator's antenna is for: an N1MM rotor message and following WSJT-X "
        "turn the antenna on the radio's band (docs/loggers.md, One antenna per band).",
    ),
    configured=_configured,
)
