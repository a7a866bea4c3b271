"""Review 70 (d2585368): a rotator whose bearing is an elevation (a Prosistel D on an elevation
rotor configured on its own, ``prosistel-el``, ``prosistel-el-a``) refuses every place now
(runtime/rotator.py ``_toward``, session/feature_commands.py rule 6: a locator, a long path,
a DX cluster's call), and Home Assistant was told so for tracking and following
(``track_options``, ``can_follow``: their select and switch are gone). But with ``[station]``
its device still offers the Locator text, the Long path button and the Distance sensor, and
with ``[dxcluster]`` the Spot select: controls whose every use is refused on R/error, and a
distance that never fills. The user sees a locator box on the dish's card that never moves it.
"""

from __future__ import annotations

import json

import pytest

from bridge.interfaces.homeassistant import Identity, RotatorInfo, all_configs
from bridge.interfaces.mqtt.topics import Topics
from bridge.settings import RotatorSettings


def _entities(model: str) -> set[str]:
    """The object ids of the entities discovery offers for one rotator of ``model``, with a
    station and the DX cluster on (as app.py builds its RotatorInfo)."""
    cfg = RotatorSettings(id="dish", model=model, port="/dev/ttyUSB0")
    topics = Topics("rotor", {"dish": "rotor"})
    info = RotatorInfo.of(
        "dish", "Dish", cfg.spec, topics.rotator("dish"), cfg.pointing,
        has_station=True, nudge_step_deg=cfg.nudge_step_deg,
        features=frozenset({"dxcluster"}),
    )  # fmt: skip
    msgs = all_configs("homeassistant", Identity("rotor"), topics, [info])
    assert all(json.loads(p) for p in msgs.values())
    return {t.split("/")[3] for t in msgs}


def test_an_azimuth_rotor_with_a_station_offers_places() -> None:
    """The same call offers them for an azimuth rotor: the test's set-up is sound."""
    assert {"locator", "long_path", "distance", "spot"} <= _entities("prosistel")


@pytest.mark.parametrize("model", ["prosistel-el", "prosistel-el-a"])
def test_an_elevation_rotor_on_its_own_is_offered_no_place_it_refuses(model: str) -> None:
    ids = _entities(model)
    assert "track" not in ids and "follow" not in ids  # (what d2585368 hid)
    offered = ids & {"locator", "long_path", "distance", "spot"}
    assert not offered, offered  # observed: all four
