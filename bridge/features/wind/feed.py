"""The wind topics: each rotator's ``wind_topic`` read into wind readings for the engine (its
wind park, session/wind.py, decides). Its topics are the user's, named in the configuration.

Rules:
1. A reading is a bare number (``12.5``, as Home Assistant's statestream and most weather
   stations publish), in the rotator's ``wind_unit``; it reaches the rotator in km/h. A speed
   has no sign: ``-0`` (a station's rounding of a small negative offset) is 0 (attack 28:
   taken as it came, R/status and Home Assistant's Wind sensor showed -0.0 km/h).
2. A retained reading is taken: it is the last known wind, a state and not a command (a high
   one parks the rotor; a reading never moves it anywhere else). One the broker replays on
   (re)subscribing is handed on as replayed (session/wind.py rule 6: it never ends a storm):
   the topic is subscribed without retain-as-published (connection.py rule 1), so the retain
   flag says "replayed" under MQTT 5 and MQTT 3.1.1 alike.
3. A payload that is no reading (text, a negative or non-finite number, or one over
   WIND_MAX_KMH once in km/h: no wind ever measured came near; an attack pass sent ``1e308``
   in m/s, which became infinite km/h, parked the rotor and put ``Infinity`` in R/status,
   which is no JSON) is dropped and logged at most once per BAD_LOG_S per topic; the wind
   park's silence report (wind.py rule 4) tells the user when nothing readable comes at all.
   Over WIND_MAX_KMH is judged in each rotator's own unit, for that rotator alone (an attack
   pass: a topic read in km/h by one rotator and in m/s by another dropped a 300 km/h storm
   for both, 1,080 km/h in the other's unit, and the first never parked).
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable

from bridge.interfaces.mqtt.payloads import PayloadError, parse_number
from bridge.settings.wind import to_kmh

log = logging.getLogger(__name__)

BAD_LOG_S = 60.0
WIND_MAX_KMH = 1000.0  # rule 3: a sensor's fault above this (the highest gust measured: 408)

Handler = Callable[[str, bytes, bool], bool]


def wind_feed(
    entries: list[tuple[str, str, Callable[[float, bool], None]]],
    clock: Callable[[], float] = time.monotonic,
) -> tuple[list[str], Handler]:
    """(the topics to subscribe, the handler of their messages) for ``(topic, unit, to)``
    entries: ``to`` gets each reading in km/h, and whether the broker replayed it (rule 2)."""
    logged: dict[str, float] = {}

    def on_message(topic: str, payload: bytes, retain: bool) -> bool:
        mine = [(unit, to) for t, unit, to in entries if t == topic]
        if not mine:
            return False
        try:
            value = parse_number(payload, "wind speed")
            if value < 0 or not math.isfinite(value):
                raise PayloadError("wind speed must be 0 or more")
            value = abs(value)  # rule 1: -0 (not below 0) is 0, a speed has no sign
        except PayloadError as exc:
            dropped(topic, exc)
            return True
        for unit, to in mine:  # rule 3: each rotator's own unit decides
            speed = to_kmh(value, unit)  # rule 1
            if speed > WIND_MAX_KMH:
                why = f"{value:g} {unit} is over {WIND_MAX_KMH:g} km/h: a sensor's fault?"
                dropped(topic, PayloadError(why))
                continue
            to(speed, retain)  # rule 2
        return True

    def dropped(topic: str, exc: PayloadError) -> None:
        now = clock()
        if now - logged.get(topic, -math.inf) >= BAD_LOG_S:
            logged[topic] = now
            log.warning("wind topic %s: reading dropped: %s", topic, exc)

    return sorted({t for t, _, _ in entries}), on_message
