"""skytrack.py rule 3: when the pass in hand is over, the next one is searched for at once (attack
19: a pass tracked from its last minute ended into 40 s of 'no pass', the search waiting for
PASS_RETRY_S after the one made at the start); but an answer of none in sight, or one that
gives a pass already over, is searched for again only PASS_RETRY_S on: no search loop at one
instant. Pure: SkyTrack asked and answered by hand, the times the test's own."""

from __future__ import annotations

from bridge.session.config import TrackConfig
from bridge.session.skytrack import PASS_RETRY_S, SkyTrack
from bridge.sky import Body, Pass, Sky
from bridge.sky.worker import Answer, PassQuestion

T0 = 1_781_000_000.0


def _searches(track: SkyTrack, answer: Pass | None) -> list[float]:
    """The pass searches asked for, each answered ``answer``: the times searched from."""
    asks, track.asks = track.asks, []
    searched = []
    for q in asks:
        if isinstance(q, PassQuestion):
            searched.append(q.utc)
            track.answered(Answer(q, answer))
    return searched


def _pass(aos: float, los: float) -> Pass:
    return Pass(aos, los, (aos + los) / 2, 30.0, 100.0, 110.0)


def test_the_end_of_a_pass_searches_for_the_next_at_once() -> None:
    track = SkyTrack(TrackConfig(Sky(52.52, 13.29)), Body.sun())
    ending = _pass(T0 - 600.0, T0 + 20.0)  # tracking starts 20 s before its end
    assert track.searching(T0) and _searches(track, ending) == [T0]
    assert not track.searching(T0 + 20.0) and track.pass_now == ending
    nxt = _pass(T0 + 2600.0, T0 + 2900.0)
    assert track.searching(T0 + 21.0) and _searches(track, nxt) == [T0 + 21.0]  # at once
    assert not track.searching(T0 + 21.0) and track.pass_now == nxt and track.after_pass


def test_after_a_pass_none_in_sight_is_searched_for_again_only_after_the_retry_time() -> None:
    track = SkyTrack(TrackConfig(Sky(52.52, 13.29)), Body.sun())
    assert track.searching(T0) and _searches(track, _pass(T0 - 600.0, T0 + 20.0)) == [T0]
    assert track.searching(T0 + 21.0) and _searches(track, None) == [T0 + 21.0]
    assert not track.searching(T0 + 21.0) and track.pass_now is None
    assert not track.searching(T0 + 20.0 + PASS_RETRY_S) and _searches(track, None) == []
    assert track.searching(T0 + 21.0 + PASS_RETRY_S)
    assert _searches(track, None) == [T0 + 21.0 + PASS_RETRY_S]


def test_a_search_that_gives_a_pass_already_over_is_not_asked_again_at_once() -> None:
    track = SkyTrack(TrackConfig(Sky(52.52, 13.29)), Body.sun())
    over = _pass(T0 - 600.0, T0 - 10.0)  # (a sky worker's slip: it ended before the search)
    assert track.searching(T0) and _searches(track, over) == [T0]
    for t in (T0, T0 + 1.0, T0 + PASS_RETRY_S - 1.0):
        assert not track.searching(t) and _searches(track, over) == [], t
        assert track.pass_now is None
    assert track.searching(T0 + PASS_RETRY_S) and _searches(track, None) == [T0 + PASS_RETRY_S]
