"""Review 107: after a replug, the stops first readings that never confirm get are written but
not said: the words keep the last connection's clock.

controller.py rule 9 (``_unwatched_stop``, commits 025ee699 and 110b095c): FIRST_UNWATCHED_READINGS
first readings in a row that confirmed none get a stop, and again each as many more, and a
``stop`` error says why "at most every ``junk_report_interval_s``", on a clock of its own
(``_unwatched_said_t``). That clock is the controller's, not the connection's: a port replugged
within the interval after the last such word (a flaky adapter: the very line that garbles is the
one that drops) has its new connection's stops written, one every 1.6 s, with nothing said. The
rotor is stopped over and over while R/error and R/status's ``last_error`` say only "virtual port
unplugged", a word about a port that is back; the doubt's own "first readings in a row disagree"
keeps rule 6's clock and is not said either.

In virtual time: the emulated Easycomm II box at rest at 150; every position answer reaches the
host off by 0, +60 or -60 degrees in turn (review 100's line); the port unplugged three seconds
after the start and plugged back two seconds later, the line as bad as before.
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import ErrorKind
from tests.engine.garblers import every_answer_off
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
OFFSETS = [0.0, 60.0, -60.0]
FIRST_S = 3.0  # the first connection: its first stop written and said (virtual time)
UNPLUGGED_S = 2.0  # a flaky adapter's drop (virtual time)
WATCH_S = 10.0  # several stops of the new connection, well inside junk_report_interval_s


def test_the_stops_of_a_replugged_line_that_never_confirms_are_said(rig: Rig) -> None:
    v = rig("easycomm2", emulator={"start_az_deg": REST_DEG}, connect=False)
    v.to_host = every_answer_off(OFFSETS)
    v.link_up()
    v.run_for(FIRST_S)
    first = [e.message for e in v.errors() if e.kind == ErrorKind.STOP]
    assert len(first) == 1 and "do not agree" in first[0], first  # (the first connection's)
    v.link_down()
    v.run_for(UNPLUGGED_S)
    t = v.now
    v.link_up()
    v.run_for(WATCH_S)
    stops = v.frames("stop", since=t)
    assert len(stops) > 2, stops  # (stopped again and again on the new connection)
    said = [e.message for e in v.errors(since=t)]
    assert any("do not agree" in m for m in said), (
        f"{len(stops)} stop frames written on the new connection, nothing said; R/error since "
        f"the replug: {said}; R/status last_error: {v.status.last_error!r}"
    )
