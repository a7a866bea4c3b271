"""The feature registry (bridge/feature.py; docs/architecture.md "The feature registry"): every
feature, one package each, in the order the topic table, the MQTT service, ``R/status``, Home
Assistant's entity table and the app take them (bridge/feature.py rule 2).

Stop, lock and the last word are not here: they come first, hard-wired (bridge/feature.py
rule 1). A new feature is a package beside these and one line below.
"""

from __future__ import annotations

from bridge.feature import Feature
from bridge.features import autopark, bands, control, dxcluster, follow, health, tracking, wind

FEATURES: tuple[Feature, ...] = (
    tracking.FEATURE,
    follow.FEATURE,
    wind.FEATURE,
    health.FEATURE,
    control.FEATURE,
    dxcluster.FEATURE,
    autopark.FEATURE,
    bands.FEATURE,
)
