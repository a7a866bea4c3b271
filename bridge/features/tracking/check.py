"""check-config's judgement of ``[tracking] tle_file`` (bridge/feature.py ``check``): the file
read by the start's own reader, sky/catalog.py ``TleCatalog`` (its rule 6), and what that
reading warns of said as check-config's warnings. A review: the file was judged by ``isfile``
alone, so an error page saved as the TLE file was "(found)" with no warning while every
satellite was then "no satellite" at run, and a pipe the start does not read "did not exist"."""

from __future__ import annotations

import os
from typing import Any

from bridge.core.text import shown_path
from bridge.sky.catalog import TleCatalog


def check(settings: Any) -> list[str]:
    """The warnings of the TLE file of ``settings`` (the file's Settings), none without one."""
    path = settings.tracking.tle_file
    if path is None:
        return []
    if not os.path.lexists(path):
        return [
            f"tracking.tle_file: {shown_path(path)} does not exist now; satellites can be "
            "tracked by name once it does (it is read when it changes)"
        ]
    count, said = TleCatalog(path, logged=False).warnings()
    found = [f"tracking.tle_file: {line.removeprefix('tle_file ')}" for line in said]
    if count == 0 and not found:  # (read, and empty)
        found.append(f"tracking.tle_file: {shown_path(path)} holds no satellite")
    elif count == 0:
        found[0] += "; it holds no satellite"
    return found
