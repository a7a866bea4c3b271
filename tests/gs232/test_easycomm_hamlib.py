"""Easycomm II as Hamlib's ``-m 202``/``-m 204`` reads it: no reply to a line that asks nothing.

Hamlib's easycomm backend reads no reply to a set, a stop, a park, a reset or a move, then
reads the next question's answer as the first line that comes (easycomm.c, read_string up to
LF, taken as ``AZ%f EL%f``). A line the bridge sent for a refused move (``ALrefused locked``)
or a word it cannot do (``ALML not available``) was that first line: the next ``p`` failed
("Command rejected by the rig"), every time, in a tracker that sets and reads in turn. What
the bridge refuses is said on ``R/error`` (the judge's report, package rule 12); on the wire a
line gets an answer only if it asked something.
"""

from __future__ import annotations

import pytest

from bridge.core.model import Park, Stop, Target
from bridge.interfaces.gs232 import EMULATIONS, EasycommSession
from tests.gs232.test_dcu1 import _Tower
from tests.support.hamlib import run_rotctl


@pytest.mark.parametrize(
    "line",
    [b"AZ100.0 EL30.0\n", b"AZ100.0\n", b"PARK\n", b"ML\n", b"MR\n", b"RESET\n", b"AZnan EL0.0\n"],
)
def test_a_line_that_asks_nothing_is_answered_with_nothing(line: bytes) -> None:
    tower = _Tower()
    tower.refuse = {Target, Park}
    ec = EasycommSession(tower, "127.0.0.1")  # type: ignore[arg-type]
    assert ec.feed(line) == [b""]
    assert ec.feed(b"AZ EL \n") == [b"AZ120.0 EL0.0\n"]  # the answer is the next line read


def test_a_stop_the_remote_cannot_deliver_is_answered_with_nothing() -> None:
    tower = _Tower()
    tower.refuse = {Stop}
    ec = EasycommSession(tower, "127.0.0.1")  # type: ignore[arg-type]
    assert ec.feed(b"SA SE \n") == [b""]
    assert ec.feed(b"AZ EL \n") == [b"AZ120.0 EL0.0\n"]


def test_a_question_still_gets_its_one_line() -> None:
    tower = _Tower()
    ec = EasycommSession(tower, "127.0.0.1")  # type: ignore[arg-type]
    assert ec.feed(b"AZ ML\n") == [b"AZ120.0\n"]  # a garbled poll: its answer, one line
    assert ec.feed(b"AZnan AZ EL\n") == [b"ALinvalid AZnan\n"]  # asked, and malformed
    tower.status.available = False
    assert ec.feed(b"AZ EL \n") == [b"ALposition unknown\n"]
    assert len(tower.refusals) == 2  # ML and AZnan said on R/error


@pytest.mark.parametrize("model", ["202", "204"])
@pytest.mark.parametrize("first", [["P", "100", "30"], ["M", "8", "50"], ["R", "1"], ["K"]])
def test_hamlib_reads_the_position_after_a_refused_or_unsupported_command(
    rotctl_path: str, model: str, first: list[str]
) -> None:
    tower = _Tower()
    tower.refuse = {Target, Park}
    server = EMULATIONS["easycomm"].server(tower, 0)  # type: ignore[arg-type]
    server.start()
    try:
        done = run_rotctl(rotctl_path, model, server.port, *first, "p")
    finally:
        server.stop()
    assert done.returncode == 0, done.stderr[-600:]
    assert done.stdout.split()[-2:] == ["120.00", "0.00"], done.stdout


def test_a_set_that_fails_inside_the_bridge_is_answered_with_nothing_too() -> None:
    """Package rule 3 on the failure path (rule 8 of the house: logged): ``ALinternal error``
    after a set was the next ``AZ EL``'s answer to Hamlib, as the alarm lines were."""

    class Broken(_Tower):
        def submit(self, command: object, described: str | None = None) -> None:
            raise RuntimeError("a bug")

    ec = EasycommSession(Broken(), "127.0.0.1")  # type: ignore[arg-type]
    assert ec.feed(b"AZ100.0 EL0.0\n") == [b""]
    assert ec.feed(b"AZ EL \n") == [b"AZ120.0 EL0.0\n"]
    assert ec.feed(b"AZ100.0 AZ EL\n") == [b"ALinternal error\n"]  # asked: it is told
