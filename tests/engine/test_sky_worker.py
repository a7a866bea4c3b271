"""The sky off the lines thread (tracking.py rule 8, skywork.py): the session asks, the sky
worker answers, and the answer is an input. In virtual time the bench plays the worker
(tests/engine/virtual.py rule 5), answering late on purpose; the real worker's thread and its
sharing of answers between rotators are proven on their own."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager

from bridge.core.model import ErrorKind
from bridge.session.actions import Ask
from bridge.sky import Body, Sky
from bridge.sky import worker as skywork
from bridge.sky.worker import Answer, PassQuestion, PositionsQuestion, Question, SkyWorker
from tests.engine.test_session_tracking import SUN_EPOCH, sun_up_somewhere
from tests.engine.virtual import VirtualRotator
from tests.support.sky import synthetic_tle
from tests.support.waiting import slow


class GuardedSky(Sky):
    """A Sky that refuses to compute unless the bench's sky worker is the one asking."""

    answering = False

    def positions(self, body: Body, times_unix: object) -> list[tuple[float, float]]:
        assert GuardedSky.answering, "the session computed the sky itself"
        return super().positions(body, times_unix)  # type: ignore[arg-type]

    def next_pass(self, *args: object, **kwargs: object) -> object:  # type: ignore[override]
        assert GuardedSky.answering, "the session searched a pass itself"
        return super().next_pass(*args, **kwargs)  # type: ignore[arg-type]


@contextmanager
def worker_answering() -> Iterator[None]:
    GuardedSky.answering = True
    try:
        yield
    finally:
        GuardedSky.answering = False


def answered_by_the_worker(question: Question) -> Answer:
    with worker_answering():
        return skywork.answer(question)


def sun_rotor(delay_s: float) -> VirtualRotator:
    lat, lon = sun_up_somewhere(SUN_EPOCH)
    v = VirtualRotator(
        "rot2prog",
        sky=GuardedSky(lat, lon),
        wall_epoch_s=SUN_EPOCH,
        sky_delay_s=delay_s,
        emulator={"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0},
        settings={"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0},
    )
    v.answer_sky = answered_by_the_worker
    v.run_until(lambda h: h.status.available, 10, "the controller answers")
    return v


def test_the_session_never_computes_the_sky_and_waits_for_the_answers() -> None:
    """The 8-rotor benchmark: pass searches of 70-95 ms ran on the thread that writes every
    stop. Now the session only asks; until the answer is in, it sends nothing of tracking."""
    with sun_rotor(delay_s=3.0) as v:
        t0 = v.now
        v.track(Body.sun())
        assert [type(a.question) for _t, a in v.asked] == [PassQuestion]
        v.run_for(2.9)
        assert v.frames("set", "set: clamped", since=t0) == []  # waiting for the pass
        assert v.status.tracking is not None and v.status.tracking.phase == "waiting"
        v.run_until(lambda h: h.frames("set", "set: clamped", since=t0), 15, "a sun target")
        kinds = {type(a.question) for _t, a in v.asked}
        assert kinds == {PassQuestion, PositionsQuestion}
        assert v.errors() == []


def test_a_late_answer_after_a_stop_or_off_is_ignored() -> None:
    for how in ("stop", "off"):
        with sun_rotor(delay_s=2.0) as v:
            t0 = v.now
            v.track(Body.sun())
            v.run_for(1.0)
            v.stop() if how == "stop" else v.track(None)
            v.run_for(30.0)  # the pass comes in at 2 s, for a tracking that has ended
            assert v.frames("set", "set: clamped", since=t0) == [], how
            assert v.status.tracking is None and v.status.tracking_ended == how
            late = [a for _t, a in v.asked if isinstance(a, Ask)]
            assert late and all(a.generation != v.session.tracker.generation for a in late)


def test_eight_rotors_asking_for_one_window_cost_one_computation() -> None:
    computed: list[Question] = []
    delivered: list[Answer] = []
    done = threading.Event()

    def compute(question: Question) -> Answer:
        computed.append(question)
        return Answer(question, [(1.0, 2.0)])

    def deliver(answer: Answer) -> None:
        delivered.append(answer)
        if len(delivered) == 8:
            done.set()

    worker = SkyWorker(compute)
    sky = Sky(52.5, 13.3)
    for _ in range(8):
        worker.ask(PositionsQuestion(sky, Body.sun(), (0.0, 10.0)), deliver)
    assert done.wait(slow(10))
    assert len(computed) == 1 and all(a.value == [(1.0, 2.0)] for a in delivered)


def test_a_sky_that_cannot_be_computed_is_answered_with_the_reason_never_raised() -> None:
    sky = Sky(52.5, 13.3)
    beyond = 2_700_000_000.0  # 2055: DE421 ends in 2053
    found = skywork.answer(PassQuestion(sky, Body.sun(), beyond, 0.0))
    assert found.failure == "date beyond the ephemeris (2053)"
    with sun_rotor(delay_s=0.0) as v:
        v.answer_sky = lambda q: Answer(q, failure="date beyond the ephemeris (2053)")
        v.track(Body.sun())
        v.run_for(2.0)
        assert v.status.tracking is None
        assert v.status.tracking_ended == "date beyond the ephemeris (2053)"
        assert not v.errors(ErrorKind.INTERNAL)


def test_a_slow_satellite_is_tracked_with_a_few_questions_a_minute() -> None:
    """Cold review: a geostationary satellite's lead reaches 300 s, so one step needs five
    windows of its track; with four kept, each answer dropped one the next step needed and the
    session and the sky worker passed two windows back and forth without end."""
    epoch = 1_781_020_000.0
    line1, line2 = synthetic_tle(
        "GEO",
        epoch,
        inclination_deg=0.05,
        raan_deg=0,
        mean_anomaly_deg=0,
        mean_motion_rev_day=1.00273791,
    )
    body = Body.satellite("QO", line1, line2)
    asked: list[Question] = []

    def answer(q: Question) -> Answer:
        asked.append(q)
        return skywork.answer(q)

    with VirtualRotator(
        "md01",
        sky=Sky(50.0, -160.0),
        wall_epoch_s=epoch,
        emulator={"az_speed_deg_s": 2.0, "el_speed_deg_s": 1.0},
        settings={"az_speed_deg_s": 2.0, "el_speed_deg_s": 1.0},
    ) as v:
        v.answer_sky = answer
        v.run_until(lambda h: h.status.available, 10, "up")
        v.track(body)
        v.run_for(240.0)
        assert v.status.tracking is not None
        assert len(asked) < 30, len(asked)
