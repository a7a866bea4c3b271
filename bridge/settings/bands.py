"""The bands a rotator's antenna is for, in ``[[rotators]]``: ``bands = ["20m", "15m"]``
(core/bands.py names them). The loggers' N1MM messages and WSJT-X following use them to turn the
antenna that is on the radio's band (interfaces/loggers/commands.py rule 5, session/follow.py rule
9).

Rules:
1. Each name is a band of core/bands.py's table, in any case (``20M``); stored as the table writes
   it. An unknown one is a configuration error naming the key and the nearest bands (a "did you
   mean"); a band given twice is one too (a typo for another band, most likely).
2. Empty (the default): the rotator is for no band in particular; nothing is chosen for it by
   band, and it is turned by name as before.
3. No two rotators share a band (settings/): a message for a band must name one antenna.
   Antennas turned together on one band are one group, not two rotators with one band.
4. Every key carries its meaning (``description``) for docs/configuration.md.
"""

from __future__ import annotations

from pydantic import Field, field_validator

from bridge.core.bands import UnknownBand, canonical
from bridge.settings.base import Strict


class BandFields(Strict):
    """The band part of ``[[rotators]]``."""

    bands: list[str] = Field(
        default_factory=list,
        description="the bands this rotator's antenna is for, as loggers write them "
        '("160m" ... "10m", "6m", "2m", "70cm", "23cm"...): an N1MM rotor message sent to a '
        "rotor name several rotators share (or to *) turns the one whose bands hold the "
        "message's band, and following WSJT-X turns it only while WSJT-X's dial is on one of "
        "them; no two rotators share a band",
        examples=[["20m", "15m", "10m"]],
        json_schema_extra={
            "unset": "no band: turned by its N1MM name alone; follows on every band"
        },
    )

    @field_validator("bands")
    @classmethod
    def _known(cls, names: list[str]) -> list[str]:
        """Rule 1."""
        out: list[str] = []
        for name in names:
            try:
                band = canonical(name)
            except UnknownBand as exc:
                raise ValueError(str(exc)) from None
            if band in out:
                raise ValueError(f"{band!r} is given twice")
            out.append(band)
        return out
