"""Review 95: the wall clock stepped back (NTP) further than the windows kept (8 windows: 16 min
for a satellite, 2 h 40 for the sun) while tracking: each window answered evicted the oldest
one kept, which was always the other window the step needed (the one at ``utc`` or the one
after it, asked for at every look), so the body's position was missing at every other step and
the asking never stopped: a sky answer ran a step that asked again, as fast as the sky worker
answered (the virtual bench looped at one instant without end)."""

from __future__ import annotations

from bridge.session.config import TrackConfig
from bridge.session.skytrack import SkyTrack
from bridge.sky import Body, Sky
from bridge.sky.worker import Answer, PositionsQuestion


def _answered(track: SkyTrack) -> int:
    asks, track.asks = track.asks, []
    for q in asks:
        assert isinstance(q, PositionsQuestion)
        track.answered(Answer(q, [(t / 1000.0 % 360.0, 30.0) for t in q.times]))
    return len(asks)


def test_after_the_clock_steps_back_the_windows_settle_and_the_asking_stops() -> None:
    track = SkyTrack(TrackConfig(Sky(50.0, 10.0)), Body.sun())
    t = 1_781_000_000.0
    for k in range(3 * 360):  # three hours of the sun, a look every 10 s
        if track.at(t + 10.0 * k) is None:
            _answered(track)
        _answered(track)
    back = t + 10.0 * k - 4 * 3600.0  # NTP steps the clock back four hours
    for _ in range(3):  # the windows it needs are asked for and come in
        track.at(back), track.at(back + 60.0)
        _answered(track)
    for _ in range(10):  # then every look has the position and asks for nothing more
        assert track.at(back) is not None and track.at(back + 60.0) is not None
        assert _answered(track) == 0
