"""DX cluster spots, as one feature (bridge/feature.py): the bridge logs in to a cluster node,
keeps the newest spots with their bearings, publishes them on ``B/spots`` and turns a rotator
to a spotted call (``R/target`` ``{"call": ...}``).

What it is made of:
- its table, ``[dxcluster]``: settings/dxcluster.py ``DxClusterSettings`` (the file's model
  includes it; the settings' layer sits below this package);
- its service: dxcluster/ (the spot and country-file parsers, the spots' book, the telnet
  client and its aim thread), made by interfaces/dxcluster/setup.py ``service`` when ``[dxcluster]
  enabled`` and imported only then; it publishes ``B/spots`` and takes the targets by call;
- the call form of ``R/target``: interfaces/mqtt/call_payload.py, parsed with the target's other
  forms (interfaces/mqtt/payloads.py ``parse_aim``) and handed to the service
  (interfaces/mqtt/service.py ``aim_calls_with``);
- here: ``B/spots``, Home Assistant's spot select (its options: interfaces/homeassistant/info.py
  ``spot_options``, the newest calls the service hands over), its declaration.
"""

from __future__ import annotations

from typing import Any

from bridge.feature import EntityRow, Feature, RotatorView
from bridge.settings.dxcluster import DxClusterSettings

NAME = "dxcluster"  # interfaces/homeassistant/info.py names it too: the spot select's options
SPOTS = "spots"  # B/spots: the newest spots with their bearings, retained
OPTIONS = "spot_options"  # RotatorInfo's: the newest calls; none without a station
# its select's place in discovery (bridge/feature.py rule 5): right after tracking's select, as
# the entity table had it (after the distance, the other features' rows, without tracking)
AFTER = "track"
# the spot select sends the call it shows to the target topic (interfaces/dxcluster/client.py turns
# to it)
CALL_TEMPLATE = '{"call": "{{ value }}"}'
# shown with none chosen, as the preset select (Home Assistant's dashboard sends nothing when
# the option it shows is picked again)
NO_OPTION = "{{ 'None' }}"


def _spot(r: RotatorView) -> dict[str, object]:
    options = getattr(r, OPTIONS)  # RotatorInfo's (needs: it has some)
    return {
        "command_topic": r.topics.target, "command_template": CALL_TEMPLATE,
        "options": list(options), "state_topic": r.topics.status,
        "value_template": NO_OPTION, "icon": "mdi:account-voice",
    }  # fmt: skip


def _on(settings: Any) -> bool:
    return bool(settings.dxcluster.enabled)


FEATURE = Feature(
    name=NAME,
    docs="docs/dxcluster.md",
    summary="keeps a DX cluster's newest spots with their bearings and turns to a spotted call",
    entities=(EntityRow("select", "spot", "Turn to spot", _spot, needs=OPTIONS, after=AFTER),),
    settings_table=("dxcluster", DxClusterSettings),
    base_topics=(SPOTS,),
    service="bridge.interfaces.dxcluster.setup:service",
    service_on=_on,
    check="bridge.interfaces.dxcluster.setup:check",  # check-config: the cty file, read as run
    console=("the spots on the map (interfaces/web/static/console.js, from B/spots' document)",),
)
