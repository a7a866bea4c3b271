"""A Maidenhead encoder for tests: the locator of the area holding a point. The bridge only reads
locators (bridge/core/geo.py parse_locator); tests use this to check that reading from the other
side (a point's locator read back is the square around it) and to name a place's locator.

Written from the definition (IARU; bridge/core/geo.py's header): pairs of longitude then latitude,
field A..R (20 x 10 deg), square 0..9, subsquare A..X, extended square 0..9; counted east from
180 W (180 E counts as 180 W) and north from 90 S (the North Pole belongs to the top row).
"""

from __future__ import annotations

import math

# per pair: its alphabet and its size in the finest cells (1/120 deg lon by 1/240 deg lat)
_LEVELS = (("ABCDEFGHIJKLMNOPQR", 2400), ("0123456789", 240), ("ABCDEFGHIJKLMNOPQRSTUVWX", 10))
_LEVELS += (("0123456789", 1),)
_CELLS = 43200  # finest cells around the world, and from pole to pole


def to_locator(lat: float, lon: float, chars: int = 6) -> str:
    """The locator (upper case) of the area holding (lat, lon)."""
    for value, name, limit in ((lat, "latitude", 90.0), (lon, "longitude", 180.0)):
        if not math.isfinite(value) or not -limit <= value <= limit:
            raise ValueError(f"{name} must be a number from {-limit:g} to {limit:g}, got {value!r}")
    if chars not in (2, 4, 6, 8):
        raise ValueError(f"a locator has 2, 4, 6 or 8 characters, not {chars}")
    x = math.floor((lon + 180.0) * 120) % _CELLS
    y = min(math.floor((lat + 90.0) * 240), _CELLS - 1)
    out: list[str] = []
    for alphabet, size in _LEVELS[: chars // 2]:
        out.append(alphabet[x // size % len(alphabet)])
        out.append(alphabet[y // size % len(alphabet)])
    return "".join(out)
