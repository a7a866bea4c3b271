"""Attack 14: the storm's park, waiting under the hold of a stop lane's STOP (session.py rule
13) when the storm began, is dropped for good when that hold ends with clearing (the main MQTT
connection dropped before its marker came back: interfaces/mqtt/lastword.py rule 5).

The clearing is right to drop what an operator sent (its place in line is lost, and the
operator can send it again), but the storm's park is the bridge's own move and nobody can send
it again: the storm refuses every motion command (session/wind.py rule 1). wind.py owes the
park again only for an offline (rule 7); here nothing owes it. The STOP came before the storm,
so it halted no park (the status says ``halted: false``); yet the rotor stays where it was for
the whole storm, later live readings above the park level do not park it either, R/error says
"target dropped ... send it again" (which the storm refuses), and R/status and Home
Assistant's "Parked for the storm" say it is parked for the storm while it faces the wind.

In virtual time, a Rotor-EZ at 90 with its storm park at 180; the two MQTT connections stood
in for by what they put in the mailbox, as tests/engine/test_session_last_word.py does."""

from __future__ import annotations

from bridge.core.model import MotionState, Source, Stop
from tests.engine.virtual import VirtualRotator

WIND = {"wind_topic": "weather/wind", "wind_park_above": 60, "park_az_deg": 180}
MARKER = 1
PARK_TIME_S = 120.0  # virtual: a Rotor-EZ turns 90 degrees in well under this


def at_rest_at(v: VirtualRotator, az: float) -> bool:
    return abs(v.truth().az_deg - az) < 2.0 and v.state is MotionState.IDLE


def test_a_storm_park_waiting_under_a_hold_that_clears_is_sent_after_all() -> None:
    with VirtualRotator("rotorez", settings=WIND) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.target(90.0)
        v.run_until(lambda h: at_rest_at(h, 90.0), 120, "at rest at 90")
        v.mailbox.put(Stop(Source.MQTT), hold=MARKER)  # the operator's STOP, on the lane
        v._take()
        v.mailbox.put_wind(90.0)  # then the storm's first reading: its park waits for the hold
        v._take()
        v.mailbox.put_release(0, clear=True)  # the main connection dropped: the hold clears
        v._take()
        v.mailbox.put_wind(95.0)  # the storm goes on, read on the new connection
        v._take()
        v.run_for(PARK_TIME_S)
        wind = v.status.wind
        assert wind is not None and wind.storm and not wind.halted  # no STOP in the storm
        assert at_rest_at(v, 180.0), (
            f"rotor at {v.truth().az_deg:.0f}, not at the storm park, while R/status says: "
            f"{wind.refusal}"
        )


def test_a_storm_park_waiting_under_an_express_hold_lost_is_sent_after_all() -> None:
    with VirtualRotator("rotorez", settings=WIND) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.target(90.0)
        v.run_until(lambda h: at_rest_at(h, 90.0), 120, "at rest at 90")
        v.mailbox.put_express_hold(MARKER)  # the operator's STOP, by the stop express
        v.mailbox.put(Stop(Source.MQTT))
        v._take()
        v.mailbox.put_wind(90.0)  # the storm's first reading: its park waits for the hold
        v._take()
        v.mailbox.put_express_release(MARKER, lost=True)  # the express ended before its word
        v._take()
        v.mailbox.put_wind(95.0)
        v._take()
        v.run_for(PARK_TIME_S)
        wind = v.status.wind
        assert wind is not None and wind.storm and not wind.halted
        assert at_rest_at(v, 180.0), (
            f"rotor at {v.truth().az_deg:.0f}, not at the storm park, while R/status says: "
            f"{wind.refusal}"
        )
