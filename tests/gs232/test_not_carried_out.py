"""Package rule 12: a line that is no command the bridge carries out is answered in the
protocol's way and said on R/error (the rotator's ``report_refusal``, which also puts it in the
audit trail), so the client's user learns why nothing moved; nothing is submitted."""

from __future__ import annotations

from types import SimpleNamespace

from bridge.core.model import Stop, Target
from bridge.interfaces.gs232 import Dcu1Session, EasycommSession, Gs232Session
from bridge.interfaces.gs232.commands import DCU1_ERROR, GS232_ERROR
from tests.gs232.test_dcu1 import _Tower


def test_gs232_lines_it_does_not_carry_out_are_said_and_move_nothing() -> None:
    tower = _Tower()
    gs = Gs232Session(tower, "192.168.1.20")  # type: ignore[arg-type]
    sent = [b"M180.5\r", b"W180,045\r", "M\u0661\u0668\u0660\r".encode("latin-1", "replace")]
    sent += [b"\x1fM180\r", b"X" * 300 + b"\r"]  # a blank that is no ASCII one; too long
    assert [gs.feed(line) for line in sent] == [[GS232_ERROR]] * 5
    assert tower.submitted == []
    said = [message for message, _ in tower.refusals]
    assert said[:4] == [
        "'M180.5' is no GS-232 command the bridge carries out",
        "'W180,045' is no GS-232 command the bridge carries out",
        "'M???' is no GS-232 command the bridge carries out",
        "'\\x1fM180' is no GS-232 command the bridge carries out",
    ]
    assert said[4] == "a line too long to be a GS-232 command"
    assert tower.refusals[0][1] == "gs232 M180.5"  # what was sent, for the audit trail
    assert gs.feed(b" M180 \r") == [b""] and [type(c) for c in tower.submitted] == [Target]
    assert len(tower.refusals) == 5  # a command carried out says nothing


def test_easycomm_malformed_and_unsupported_words_are_said() -> None:
    tower = _Tower()
    ec = EasycommSession(tower, "192.168.1.20")  # type: ignore[arg-type]
    assert ec.feed(b"AZnan\n") == [b""]  # asked nothing: answered with nothing
    assert ec.feed(b"AZ ML\n") == [b"AZ120.0\n"]  # a garbled poll: its one line
    assert tower.submitted == []
    assert [m for m, _ in tower.refusals] == [
        "Easycomm: invalid AZnan",
        "Easycomm: ML not carried out by the bridge",
    ]
    assert ec.feed(b"AZ EL\n") == [b"AZ120.0 EL0.0\n"] and len(tower.refusals) == 2


def test_a_dcu1_command_that_is_none_is_said_and_a_stop_still_stops() -> None:
    tower = _Tower()
    dcu = Dcu1Session(tower, "192.168.1.20")  # type: ignore[arg-type]
    assert dcu.feed(b"Q\r") == [DCU1_ERROR] and tower.submitted == []
    assert dcu.feed(b"AP1999;") == [DCU1_ERROR]  # a bearing past 360: its ; still stops
    assert [type(c) for c in tower.submitted] == [Stop]
    assert [m for m, _ in tower.refusals] == [
        "'Q' is no DCU-1 command",
        "'AP1999;' is no DCU-1 command",
    ]


def test_an_easycomm_axis_word_behind_junk_turns_neither_axis() -> None:
    """Package rule 3: ``\x1fAZ200.0`` is no azimuth (``\x1fM180`` is no ``M180`` either, rule
    12), nor ``AZ200.0;``, and the line beside it is malformed: nothing turns, not even the
    elevation its good word names, and it is said."""
    tower = _Tower()
    tower.spec = SimpleNamespace(has_elevation=True, can_report_position=True)
    ec = EasycommSession(tower, "192.168.1.20")  # type: ignore[arg-type]
    assert ec.feed(b"\x1fAZ200.0 EL30.0\n") == [b""]
    assert ec.feed(b"AZ200.0; EL30.0\n") == [b""]
    assert ec.feed(b";;AZ EL\n") == [b"ALinvalid ;AZ\n"]  # not half an answer
    assert tower.submitted == []
    assert [m for m, _ in tower.refusals] == [
        "Easycomm: invalid \x1fAZ200.0",
        "Easycomm: invalid AZ200.0;",
        "Easycomm: invalid ;AZ",
    ]
    assert ec.feed(b"\x1fSA SE\n") == [b""]  # a stop beside it still stops (rule 6)
    assert [type(c) for c in tower.submitted] == [Stop]
    # a radio's words are still ignored (Hamlib's -m 201 line)
    assert ec.feed(b"AZ200.0 EL30.0 UP000 XXX DN000 XXX\n") == [b""]
    assert [type(c) for c in tower.submitted] == [Stop, Target]


def test_hamlibs_easycomm3_line_after_a_configuration_command_is_carried_out() -> None:
    """Package rule 3: Hamlib's -m 204 ends its configuration commands with ``\\n;``
    (``GS\\n;``, ``CR 1\\n;``), which puts a ``;`` in front of its next line: that line is
    Hamlib's own command and does what it says, both axes turned, both asked answered. Before:
    refused as malformed (``;AZ200.0`` said on R/error, nothing turned; ``;AZ`` answered
    ``ALinvalid``, and rotctl's next ``p`` failed)."""
    tower = _Tower()
    tower.spec = SimpleNamespace(has_elevation=True, can_report_position=True)
    tower.status = SimpleNamespace(available=True, bearing_deg=200.0, elevation_deg=30.0)
    ec = EasycommSession(tower, "192.168.1.20")  # type: ignore[arg-type]
    assert ec.feed(b"GS\n;AZ200.0 EL30.0\n") == [b"", b""]
    assert [(c.az_deg, c.el_deg) for c in tower.submitted] == [(200.0, 30.0)]  # type: ignore[union-attr]
    assert ec.feed(b"CR 1\n;AZ\n") == [b"", b"AZ200.0\n"]
    assert ec.feed(b"VE\n;SA SE \n")[1] == b""
    assert [type(c) for c in tower.submitted] == [Target, Stop]
    assert tower.refusals == []
