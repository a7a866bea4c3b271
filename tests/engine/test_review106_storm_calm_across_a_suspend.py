"""Review 106 (Medium): a storm's calm hold (session/wind.py rule 2) is counted on the session's
clock, CLOCK_MONOTONIC, which stands still while the machine sleeps. Rule 2 starts the calm
again after a gap of ``wind_silent_min`` between readings ("a station that fell silent after
one calm reading says nothing of the wind since"), and review 104 moved a DCU-1's turn end to
the boot clock for this very reason; the wind's hold was left on the clock that stops.

What a user sees: a laptop at a portable station, parked for a storm, hears nine minutes of
calm readings and sleeps for two hours; woken, the first calm reading it hears (with the
broker's replay of the last one before it, as at every reconnect) ends the storm at once:
"the storm is over: motion allowed again", R/status's storm off, targets taken, though the
bridge heard nothing of the wind for two hours and the rule asks ten minutes of calm heard.
Awake through the same two hours with the station silent, the storm holds (the control
test). In virtual time: the sleep is the wall clock (and the boot clock) moving on while the
session's clock does not, told to the session as the worker tells it the wall clock."""

from __future__ import annotations

from pathlib import Path

from bridge.app import worker_config
from bridge.runtime.worker import Worker
from bridge.session.mailbox import Mailbox
from bridge.settings import RotatorSettings
from tests.engine.test_wind import WIND, wind, windy
from tests.engine.virtual import WALL_EPOCH_S, VirtualRotator
from tests.support.rig import FAST_BRIDGE
from tests.support.waiting import slow

SLEPT_S = 2 * 3600.0  # the machine sleeps two hours (wind_silent_min is 15)
MINUTE_S = 60.0  # the weather station publishes once a minute


def calm_for_nine_minutes(v: VirtualRotator) -> None:
    """Parked for a storm (75 km/h, park above 60), then calm readings (20 km/h, release
    below 40) once a minute for nine minutes: one minute short of ``wind_hold_min``."""
    wind(v, 75.0)
    v.run_until(lambda h: h.status.parked, 60, "parked for the storm")
    for _ in range(10):
        wind(v, 20.0)
        v.run_for(MINUTE_S)  # (the station's next reading: not a deadline)
    assert v.status.wind is not None and v.status.wind.storm


def heard_again(v: VirtualRotator) -> None:
    """The broker's replay at the reconnect, then the station's next calm reading."""
    v.mailbox.put_wind(20.0, replayed=True)
    v._take()
    wind(v, 20.0)
    v.run_for(1.0)  # (the status after it: not a deadline)


def test_awake_through_two_silent_hours_the_storm_holds_at_the_next_calm_reading() -> None:
    """The control: the gap rule of wind.py rule 2 as written, the bridge awake."""
    with windy() as v:
        calm_for_nine_minutes(v)
        v.run_for(SLEPT_S)  # (the station silent: not a deadline)
        heard_again(v)
        assert v.status.wind is not None and v.status.wind.storm


def test_a_storm_is_not_ended_by_the_first_calm_reading_after_a_suspend() -> None:
    with windy() as v:
        calm_for_nine_minutes(v)
        v.wall_epoch_s += SLEPT_S  # the machine sleeps: the wall and boot clocks move on,
        v.session.set_wall(v.now, v.wall())  # the session's (monotonic) does not
        v.run_for(MINUTE_S)  # (woken, the station's next minute: not a deadline)
        heard_again(v)
        assert v.status.wind is not None and v.status.wind.storm
        assert v.status.wind.refusal is not None


def test_a_suspend_with_the_port_out_is_a_gap_between_wind_readings(tmp_path: Path) -> None:
    """The same through the worker with the port out (an adapter that re-enumerates at the
    resume: the readings are handed over in its branch for a closed port, which told the
    session no wall clock, and the jump went unseen). Real pyserial on a missing path; the
    worker's ``now`` and wall clock from the test."""
    settings = RotatorSettings.model_validate(
        {"id": "tower", "model": "md01", "port": str(tmp_path / "gone"), **FAST_BRIDGE, **WIND}
    )
    box = Mailbox()
    clock = {"now": 100.0, "slept": 0.0}
    worker = Worker(
        worker_config(settings),
        box,
        lambda s: None,
        lambda e: None,
        wall=lambda: WALL_EPOCH_S + clock["slept"] + clock["now"],
    )

    def heard(kmh: float, *, replayed: bool = False) -> None:
        box.put_wind(kmh, replayed=replayed)
        worker.guarded(worker.serve, clock["now"], {box.fileno()})

    worker.guarded(worker.begin, clock["now"], lambda: None)
    try:
        heard(75.0)
        for _ in range(10):  # nine minutes of calm, a reading a minute
            clock["now"] += MINUTE_S
            heard(20.0)
        clock["slept"] += SLEPT_S  # the machine sleeps: the worker's (monotonic) now stands
        clock["now"] += MINUTE_S
        heard(20.0, replayed=True)
        heard(20.0)
        wind_now = worker.session.status.wind
        assert wind_now is not None and wind_now.storm
    finally:
        worker.guarded(worker.end, clock["now"])
        assert worker.wait_closed(slow(5))
        box.close()
