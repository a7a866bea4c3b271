"""The DX cluster client made from ``[dxcluster]`` (app.py's part, kept here so the
composition root stays short): the cty file read once, at start-up (settings_dxcluster.py
rule 2: CtyError names the file), the spots' book, the client."""

from __future__ import annotations

import time
from collections.abc import Callable

from bridge.dxcluster.book import Book
from bridge.dxcluster.client import DxCluster
from bridge.dxcluster.cty import load
from bridge.settings_dxcluster import DxClusterSettings


def dxcluster(
    settings: DxClusterSettings,
    station: tuple[float, float] | None,
    publish: Callable[[str], None],
    *,
    wall: Callable[[], float] = time.time,
) -> DxCluster:
    """CtyError if the cty file cannot be read or holds nothing."""
    assert settings.host is not None and settings.login is not None  # enabled: validated
    assert settings.cty_file is not None
    book = Book(
        load(settings.cty_file),
        station,
        max_spots=settings.max_spots,
        max_age_s=settings.max_age_min * 60.0,
        bands=tuple(settings.bands),
        wall=wall,
    )
    return DxCluster(settings.host, settings.port, settings.login, book, publish)
