"""Review 109 (Medium): f8d20d21 made a gap on the wall clock between two wind readings a gap
(session/wind.py rule 2: a suspend stops the session's monotonic clock, not the wall clock),
and made the worker tell its session the wall clock at every serve, the port out too. A
rotator of two boxes (runtime/composite.py) hands its mailbox's batch, the wind readings in
it, to both boxes' sessions before either box is served in that round, and only a box's
serve tells its session the wall clock: the first reading after a suspend is judged with the
wall clock from before the sleep, and the gap is not seen.

What a user sees: an azimuth/elevation pair (two controllers, two ports) at a portable
station, parked for a storm, hears nine minutes of calm and the laptop sleeps two hours; the
adapters re-enumerate at the resume (both ports out), and the first calm reading handed over
before a box's next try at its port ends the storm at once: "the storm is over: motion
allowed again", with ten minutes of calm never heard. The same with one controller holds the
storm (review 106's test through the worker). Real pyserial on missing paths; the worker's
``now`` and wall clock from the test, as review 106's test through the worker has them."""

from __future__ import annotations

from pathlib import Path

from bridge import app
from bridge.runtime.composite import CompositeWorker
from bridge.session.mailbox import Mailbox
from bridge.settings import RotatorSettings
from tests.engine.test_wind import WIND
from tests.engine.virtual import WALL_EPOCH_S
from tests.support.waiting import slow

SLEPT_S = 2 * 3600.0  # the machine sleeps two hours (wind_silent_min is 15)
MINUTE_S = 60.0  # the weather station publishes once a minute


def test_a_suspend_is_a_gap_between_wind_readings_on_a_rotator_of_two_boxes(
    tmp_path: Path,
) -> None:
    settings = RotatorSettings.model_validate(
        {
            "id": "tower",
            "azimuth": {"model": "rotorez", "port": str(tmp_path / "gone-az")},
            "elevation": {"model": "gs232b", "port": str(tmp_path / "gone-el")},
            **WIND,
        }
    )
    axes = app.axis_configs(settings)
    assert axes is not None
    box = Mailbox()
    clock = {"now": 100.0, "slept": 0.0}
    worker = CompositeWorker(
        app.worker_config(settings),
        axes,
        box,
        lambda s: None,
        lambda e: None,
        wall=lambda: WALL_EPOCH_S + clock["slept"] + clock["now"],
    )

    def served() -> None:
        worker.guarded(worker.serve, clock["now"], {box.fileno()})

    worker.guarded(worker.begin, clock["now"], lambda: None)
    try:
        served()  # (each box served once: its first try at its port)
        clock["now"] += MINUTE_S
        box.put_wind(75.0)  # the storm
        served()
        for _ in range(10):  # nine minutes of calm, a reading a minute
            clock["now"] += MINUTE_S
            box.put_wind(20.0)
            served()
        wind_then = worker.status.wind
        assert wind_then is not None and wind_then.storm
        clock["slept"] += SLEPT_S  # the machine sleeps: the (monotonic) now stands
        clock["now"] += MINUTE_S
        box.put_wind(20.0, replayed=True)  # the broker's replay at the reconnect ...
        box.put_wind(20.0)  # ... and the station's next reading, taken together
        served()
        wind_now = worker.status.wind
        assert wind_now is not None and wind_now.storm, wind_now
    finally:
        worker.guarded(worker.end, clock["now"])
        assert worker.wait_closed(slow(5))
        box.close()
