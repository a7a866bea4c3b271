"""What tracking knows of one body's sky: the answers of the sky worker (skywork.py) to the
questions asked for it, and the questions still to ask. Pure, no clock: ``utc`` comes in.

Rules:
1. Nothing is computed here (docs/architecture.md, "nothing slow beside a stop"): the body's
   track is asked for in windows of WINDOW samples (SAMPLE_S apart for a satellite, SLOW_SAMPLE_S
   for the sun and the moon) and interpolated; the window after the one in use is asked for
   before it is needed; at most WINDOWS_KEPT are kept.
2. A question is asked once until its answer is in (``asks`` holds those not yet handed out).
3. The pass now or next is searched for again PASS_RETRY_S after an answer of "none in sight",
   once the pass in hand is over, and when the wall clock steps back past the time the pass
   in hand was searched from (NTP: an attack pass, a clock stepped back an hour mid-pass left
   the rotor where the satellite had been, waiting for that same pass an hour on, and after
   "none in sight" nothing was searched for until the clock caught up again). Once the pass
   in hand is over the next is searched for at once, not PASS_RETRY_S after the search that
   found the one over (attack 19: a pass tracked from its last minute ended into 40 s of "no
   pass", the park after it waiting as long); but a search made after that pass's end (one
   that gave a pass already over) keeps the pace, as "none in sight" does: no search loop.
4. A new body (or a new start) is a new ``SkyTrack``: nothing asked for the old one is kept.
"""

from __future__ import annotations

import math

from bridge.session.config import TrackConfig
from bridge.sky import Body, Pass
from bridge.sky.worker import Answer, PassQuestion, PositionsQuestion, Question

SAMPLE_S = 1.0
SLOW_SAMPLE_S = 10.0
WINDOW = 120
WINDOWS_KEPT = 8  # more than one step needs: now, +10 s, +60 s, + a lead of 300 s, the next
PASS_RETRY_S = 60.0  # no pass in sight: look again this often
CLOCK_BACK_S = 1.0  # rule 3: a clock stepped back further than this searches again
FLIP_SAMPLE_S = 10.0
FLIP_SAMPLES = 120  # at most, over a pass


class SkyTrack:
    def __init__(self, cfg: TrackConfig, body: Body) -> None:
        assert cfg.sky is not None
        self._cfg, self._sky, self.body = cfg, cfg.sky, body
        self.asks: list[Question] = []  # rule 2: not yet handed to the sky worker
        self._asked: set[Question] = set()  # handed out, no answer yet
        self._pass: Pass | None = None
        self._pass_checked = -math.inf
        self.after_pass = False  # a pass has ended since tracking started
        self._flip_track: dict[PositionsQuestion, list[tuple[float, float]]] = {}
        self._windows: dict[int, list[tuple[float, float]]] = {}

    def _ask(self, question: Question) -> None:
        if question not in self._asked:
            self._asked.add(question)
            self.asks.append(question)

    def answered(self, answer: Answer) -> str | None:
        """Take an answer in; why tracking must end (the sky cannot be computed), if it must."""
        q = answer.question
        self._asked.discard(q)
        if answer.failure is not None:
            return answer.failure
        if isinstance(q, PassQuestion):
            self._pass_checked = q.utc
            self._pass = answer.value if isinstance(answer.value, Pass) else None
        elif isinstance(q, PositionsQuestion) and isinstance(answer.value, list):
            index = self._window_index(q)
            if index is not None:
                if len(self._windows) >= WINDOWS_KEPT:  # the farthest from this one (the
                    # oldest, unless the clock stepped back: then the min was the window the
                    # step needs beside this one, and each evicted the other without end)
                    self._windows.pop(max(self._windows, key=lambda i: abs(i - index)))
                self._windows[index] = answer.value
            else:
                self._flip_track = {q: answer.value}
        return None

    def _step_s(self) -> float:
        return SAMPLE_S if self.body.kind == "satellite" else SLOW_SAMPLE_S

    def _window(self, index: int) -> PositionsQuestion:
        step = self._step_s()
        times = tuple(index * step * WINDOW + i * step for i in range(WINDOW + 1))
        return PositionsQuestion(self._sky, self.body, times)

    def _window_index(self, q: PositionsQuestion) -> int | None:
        span = self._step_s() * WINDOW
        index = math.floor(q.times[0] / span)
        return index if q == self._window(index) else None

    def at(self, utc: float) -> tuple[float, float] | None:
        """The body's (azimuth, elevation) at ``utc``; None while its window is being computed
        (asked for here, with the one after it: rule 1)."""
        step = self._step_s()
        span = step * WINDOW
        index = math.floor(utc / span)
        track = self._windows.get(index)
        if index + 1 not in self._windows:
            self._ask(self._window(index + 1))
        if track is None:
            self._ask(self._window(index))
            return None
        x = (utc - index * span) / step
        i = min(int(x), WINDOW - 1)
        f = x - i
        (az0, el0), (az1, el1) = track[i], track[i + 1]
        daz = (az1 - az0 + 180.0) % 360.0 - 180.0
        return (az0 + f * daz) % 360.0, el0 + f * (el1 - el0)

    def searching(self, utc: float) -> bool:
        """Whether the pass now or next must be found first (rule 3; asked for here): tracking
        waits for the answer. Afterwards ``pass_now`` is it (None: none in sight)."""
        p = self._pass
        if p is not None and utc > p.los_s:
            self.after_pass, self._pass = True, None
            if self._pass_checked <= p.los_s:  # rule 3: the next one at once (a search made
                self._pass_checked = -math.inf  # after this LOS that gave it keeps its pace)
        if utc < self._pass_checked - CLOCK_BACK_S:  # the clock stepped back: what was found
            self._pass, self._pass_checked = None, -math.inf  # from later may not come next
        if self._pass is not None or utc - self._pass_checked < PASS_RETRY_S:
            return False
        if not any(isinstance(q, PassQuestion) for q in self._asked):
            self._ask(PassQuestion(self._sky, self.body, utc, self._cfg.min_el_deg))
        return True

    @property
    def pass_now(self) -> Pass | None:
        return self._pass

    def flip_track(self, p: Pass) -> list[tuple[float, float]] | None:
        """The body's track over the pass, sampled for the flip decision (at ``flip_times``);
        None while it is being computed."""
        q = PositionsQuestion(self._sky, self.body, flip_times(p))
        track = self._flip_track.get(q)
        if track is None:
            self._ask(q)
        return track


def flip_times(p: Pass) -> tuple[float, ...]:
    """When ``flip_track`` samples the pass: AOS to LOS, evenly, at most FLIP_SAMPLES."""
    n = min(FLIP_SAMPLES, max(2, int((p.los_s - p.aos_s) / FLIP_SAMPLE_S) + 1))
    return tuple(p.aos_s + (p.los_s - p.aos_s) * i / (n - 1) for i in range(n))
