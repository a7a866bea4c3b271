"""The sky worker: the one thread beside the lines thread that computes the sky
(docs/architecture.md rule 12). Pass searches, position windows and TLE file look-ups take
from a millisecond to a second; the lines thread writes every stop, so none of them runs there.

A session asks by returning an ``Ask`` action (a question and its tracking generation); the
worker (worker.py) hands the question here with a callback, and the answer comes back to the
session as an input (``RotatorSession.sky_answer``). ``answer`` is the computation itself, also
called directly by the virtual-time bench (tests/engine/virtual.py), so the session's decisions
are proven with the same answers in virtual time.

Rules:
1. A question is a frozen value; equal questions have equal answers. Positions (a window of a
   body's track, a pass's samples for the flip decision) are kept per question, so eight
   rotators tracking one body from one station cost one computation; passes are kept by
   ``Sky.next_pass`` itself (one pass serves every later time up to its LOS). A look-up is
   never kept: the file may change (catalog.py keeps what it parsed).
2. An answer never raises: a question that cannot be answered carries ``failure``, a few words
   a user reads in the status (``tracking_ended``: "satellite orbit decayed", "date beyond the
   ephemeris (2053)") or, for a look-up, the refusal. A bug is logged and answered as a failure.
3. One thread, started with the first question and ending after IDLE_EXIT_S with nothing to do;
   questions are answered in the order asked, each callback called on this thread (it must only
   queue, as worker.py's does).
"""

from __future__ import annotations

import logging
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass

from bridge.core.ondemand import OnDemandThread
from bridge.sky import Body, Pass, Sky, SkyError
from bridge.sky.catalog import CatalogError, TleCatalog

log = logging.getLogger(__name__)

KEPT = 64  # positions answers kept (rule 1): a few windows per body tracked
IDLE_EXIT_S = 30.0


@dataclass(frozen=True)
class PassQuestion:
    """The pass of ``body`` in progress at ``utc``, or the next one (None: none in sight)."""

    sky: Sky
    body: Body
    utc: float
    min_el_deg: float


@dataclass(frozen=True)
class PositionsQuestion:
    """(azimuth, elevation) of ``body`` at each of ``times``."""

    sky: Sky
    body: Body
    times: tuple[float, ...]


@dataclass(frozen=True)
class LookupQuestion:
    """The satellite called ``name`` in the TLE file (the file is read here, off paho's thread)."""

    catalog: TleCatalog
    name: str


Question = PassQuestion | PositionsQuestion | LookupQuestion
Value = Pass | list[tuple[float, float]] | Body | None


@dataclass(frozen=True)
class Answer:
    question: Question
    value: Value = None
    failure: str | None = None  # rule 2: why there is no value


def answer(question: Question) -> Answer:
    """Compute the answer to ``question`` (never raises, rule 2)."""
    try:
        if isinstance(question, PassQuestion):
            q = question
            q.sky.position(q.body, q.utc)  # an orbit decayed, a date past the ephemeris: say so
            return Answer(q, q.sky.next_pass(q.body, q.utc, q.min_el_deg))
        if isinstance(question, PositionsQuestion):
            return Answer(question, question.sky.positions(question.body, question.times))
        return Answer(question, question.catalog.lookup(question.name))
    except SkyError as exc:
        return Answer(question, failure=exc.reason)
    except CatalogError as exc:
        return Answer(question, failure=str(exc))
    except Exception:
        log.exception("computing %s failed", type(question).__name__)
        return Answer(question, failure="internal error computing the sky (see the log)")


Deliver = Callable[[Answer], None]


class SkyWorker:
    """Rule 3. ``ask`` may be called from any thread; it never blocks."""

    def __init__(self, compute: Callable[[Question], Answer] = answer) -> None:
        self._compute = compute
        self._thread = OnDemandThread("sky", IDLE_EXIT_S)
        self._kept: OrderedDict[PositionsQuestion, Answer] = OrderedDict()

    def ask(self, question: Question, deliver: Deliver) -> None:
        self._thread.put(lambda: self._run(question, deliver))

    def _run(self, question: Question, deliver: Deliver) -> None:
        try:
            found = self._answer(question)
        except Exception:  # rule 2: a question is always answered, or tracking waits
            log.exception("computing %s failed", type(question).__name__)
            found = Answer(question, failure="internal error computing the sky (see the log)")
        deliver(found)  # (one that raises is logged by the thread, which goes on)

    def _answer(self, question: Question) -> Answer:
        if not isinstance(question, PositionsQuestion):
            return self._compute(question)
        kept = self._kept.get(question)
        if kept is not None:
            self._kept.move_to_end(question)
            return kept
        found = self._compute(question)
        if found.failure is None:
            self._kept[question] = found
            while len(self._kept) > KEPT:
                self._kept.popitem(last=False)
        return found
