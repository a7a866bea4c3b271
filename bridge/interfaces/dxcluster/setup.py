"""The DX cluster's service, made from ``[dxcluster]`` (features/dxcluster: its declaration
points here; the app imports this module only when ``[dxcluster] enabled``): the cty file read
once, at start-up (settings/dxcluster.py rule 2: a ConfigError names the file), the spots'
book, the client publishing ``B/spots`` and taking the MQTT service's targets by call. What
the cty file's reader refused (cty.py rule 5) is logged here, once, at start-up. The start and
check-config judge the cty file by one function, ``read_cty`` (``check`` is check-config's,
named by the feature's declaration): an attack pass found check-config saying "config OK" of a
file with no entity in it (an error page a failed download saved), which the start refused."""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from typing import Any

from bridge.core.text import shown_path
from bridge.feature import AppView
from bridge.interfaces.dxcluster.book import Book
from bridge.interfaces.dxcluster.client import DxCluster
from bridge.interfaces.dxcluster.cty import Cty, CtyError, load
from bridge.settings import ConfigError
from bridge.settings.dxcluster import DxClusterSettings

log = logging.getLogger(__name__)


def service(view: AppView) -> DxCluster:
    """The client of ``view``'s ``[dxcluster]``, its spots on ``B/spots`` (and the console's
    map), the calls of ``R/target`` turned by it; ConfigError if the cty file cannot be read
    or holds nothing (``read_cty``)."""
    (spots,) = view.publishers  # B/spots, its one topic (features/dxcluster)
    settings = view.settings.dxcluster
    cty = read_cty(settings)
    cluster = dxcluster(settings, view.station, spots, wall=view.wall, cty=cty)
    view.mqtt.aim_calls_with(cluster.aim)
    return cluster


def check(settings: Any) -> list[str]:
    """ConfigError if the start would stop on ``[dxcluster]`` of ``settings`` (the file's
    Settings, its service on), else what it would warn of, the cty file's refusals (cty.py
    rule 5; a review: check-config dropped them and said "config OK" of the very line the
    start warns of): check-config asks this (bridge/feature.py ``check``)."""
    dx = settings.dxcluster
    shown = shown_path(str(dx.cty_file))
    return [f"dxcluster.cty_file: {shown} {why}" for why in read_cty(dx).refused]


def read_cty(settings: DxClusterSettings) -> Cty:
    """The cty file as the start reads it; ConfigError naming it if it cannot be read or holds
    no entity (cty.py rule 4): one judgement for the start and check-config."""
    assert settings.cty_file is not None  # enabled: validated
    try:
        return load(settings.cty_file)
    except CtyError as exc:
        raise ConfigError(f"dxcluster.{exc}") from None  # (cty.py's words start "cty_file")


def dxcluster(
    settings: DxClusterSettings,
    station: tuple[float, float] | None,
    publish: Callable[[str], None],
    *,
    wall: Callable[[], float] = time.time,
    cty: Cty | None = None,
) -> DxCluster:
    """The client, with ``cty`` (read from the settings' cty file if not given: CtyError if it
    cannot be read or holds nothing)."""
    assert settings.host is not None and settings.login is not None  # enabled: validated
    assert settings.cty_file is not None
    if cty is None:
        cty = load(settings.cty_file)
    for why in cty.refused:  # cty.py rule 5: said once
        log.warning("DX cluster: cty_file %s %s", shown_path(str(settings.cty_file)), why)
    book = Book(
        cty,
        station,
        max_spots=settings.max_spots,
        max_age_s=settings.max_age_min * 60.0,
        bands=tuple(settings.bands),
        wall=wall,
    )
    return DxCluster(settings.host, settings.port, settings.login, book, publish)
