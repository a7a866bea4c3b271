"""The DCU-1 / Rotor-EZ endpoint, sans-IO: its reader fed whole, byte by byte and split, junk
of every kind, and each client's session onto a rotator that records what it was handed (the
pending bearing, the stop first, the replies byte for byte); and the GS-232A readings."""

from __future__ import annotations

import random
from types import SimpleNamespace

import pytest

from bridge.config_doc import render
from bridge.core.errors import RefusalCode, Refused
from bridge.core.model import Source, Stop, Target
from bridge.interfaces.gs232 import Dcu1Session, Gs232Session
from bridge.interfaces.gs232.commands import DCU1_ERROR, DCU1_STORED_S, EMULATIONS
from bridge.interfaces.gs232.parser import DCU1_FRAME_MAX, Dcu1Kind, Dcu1Reader, Dcu1Request
from bridge.settings.rotator import EMULATION_KEYS
from tests.support import feed
from tests.support.clock import FakeClock
from tests.support.codecs import HOW

K = Dcu1Kind


def kinds(requests: list[Dcu1Request]) -> list[tuple[Dcu1Kind, int | None]]:
    return [(r.kind, r.az_deg) for r in requests]


@pytest.mark.parametrize("how", HOW)
def test_what_the_windows_loggers_and_hamlib_send_reads_the_same_however_it_is_cut(
    how: str,
) -> None:
    data = b"AP1123;AM1;AI1;;AS1;AP1360\rAI1\rE j S s\r\nV"
    assert kinds(feed(Dcu1Reader(), data, how)) == [
        (K.STORE, 123),
        (K.EXECUTE, None),
        (K.READ, None),
        (K.STOP, None),
        (K.STOP, None),
        (K.GOTO, 360),
        (K.READ, None),
        (K.OPTION, None),
        (K.INVALID, None),  # a space
        (K.OPTION, None),
        (K.INVALID, None),
        (K.OPTION, None),
        (K.INVALID, None),
        (K.OPTION, None),
        (K.VERSION, None),
    ]


def test_a_frame_is_held_until_it_ends() -> None:
    reader = Dcu1Reader()
    assert reader.feed(b"AP11") == [] and not reader.idle
    assert kinds(reader.feed(b"23;")) == [(K.STORE, 123)] and reader.idle


@pytest.mark.parametrize(
    ("frame", "stops"),
    [
        (b"AP199;", True),  # two digits: the board wants exactly three
        (b"AP1361;", True),  # past 360
        (b"AP1-12;", True),
        (b"AM1\r", False),  # AM1 and AS1 end at ";" only
        (b"AS1\r", False),
        (b"AX1;", True),
        (b"BI1;", False),  # not a frame: B is junk, I junk, 1 junk, then a plain stop
    ],
)
def test_a_frame_that_is_no_command_is_invalid_and_its_semicolon_still_stops(
    frame: bytes, stops: bool
) -> None:
    out = Dcu1Reader().feed(frame)
    if frame.startswith(b"B"):
        assert kinds(out) == [(K.INVALID, None), (K.STOP, None)]
        return
    assert [(r.kind, r.stops) for r in out] == [(K.INVALID, stops)]
    assert out[0].text == frame.decode()


def test_an_overlong_frame_is_junk_at_its_seventh_byte_and_the_rest_reads_on_its_own() -> None:
    reader = Dcu1Reader()
    out = reader.feed(b"AP11234;")
    assert [(r.kind, r.text) for r in out] == [
        (K.INVALID, "AP11234"[: DCU1_FRAME_MAX + 1]),
        (K.STOP, ";"),  # outside a frame now: a stop
    ]
    assert reader.idle


def test_any_bytes_keep_the_stream_usable_and_never_read_as_a_move() -> None:
    reader = Dcu1Reader()
    junk = bytes(b for b in range(256) if b not in b"A;") * 4  # no frame, no stop in it
    out = reader.feed(junk)
    assert {r.kind for r in out} <= {K.INVALID, K.OPTION, K.VERSION}
    assert kinds(reader.feed(b"AP1045;AM1;")) == [(K.STORE, 45), (K.EXECUTE, None)]


@pytest.mark.parametrize("seed", range(5))
def test_random_streams_read_the_same_commands_however_they_are_cut(seed: int) -> None:
    """Only where a run of junk is cut may differ (one banner or two), never a command."""
    rng = random.Random(seed)
    said = (b"AP1123;", b"AM1;", b"AI1;", b";", b"AS1;", b"AP1045\r")
    data = b"".join(  # junk, a CR (which ends a frame it opened), a command
        bytes(rng.choice(b"AP1MIS;\r\n0123V Eex\xff") for _ in range(rng.randint(0, 30)))
        + b"\r"
        + rng.choice(said)
        for _ in range(200)
    )
    runs = {how: feed(Dcu1Reader(), data, how) for how in HOW}
    commands = {
        how: [(r.kind, r.az_deg, r.stops) for r in out if r.kind is not K.INVALID or r.stops]
        for how, out in runs.items()
    }
    assert commands["whole"] == commands["bytewise"] == commands["split"]
    assert {K.STORE, K.EXECUTE, K.READ, K.STOP, K.GOTO} <= {k for k, _, _ in commands["whole"]}


# -- the session ------------------------------------------------------------------------------


class _Tower:
    """What a DCU-1 session uses of a rotator: a bearing, every submit and refusal recorded;
    ``refuse`` makes submit raise Refused as the judge does."""

    id = "tower"
    spec = SimpleNamespace(has_elevation=False, can_report_position=True)

    def __init__(self, bearing_deg: float | None = 120.0) -> None:
        self.status = SimpleNamespace(bearing_deg=bearing_deg, elevation_deg=0.0, available=True)
        self.submitted: list[Target | Stop] = []
        self.refusals: list[tuple[str, str | None]] = []
        self.refuse: set[type] = set()
        self.halts = 0  # the judge's count of STOPs and lock ONs, every interface's

    def halts_for(self, source: Source) -> int:
        return self.halts

    def submit(
        self,
        command: Target | Stop,
        described: str | None = None,
        *,
        since: int | None = None,
        seen_s: float | None = None,
        reader: object = None,
    ) -> None:
        if since is not None and since != self.halts:  # (mailbox.py rule 10, as the judge)
            raise Refused(RefusalCode.STALE, "a STOP came after it")
        if isinstance(command, Stop):
            self.halts += 1
        if type(command) in self.refuse:
            raise Refused(RefusalCode.LOCKED, "locked")
        self.submitted.append(command)

    def report_refusal(self, message: str, command: str | None, *, origin: object = None) -> None:
        self.refusals.append((message, command))


def session(tower: _Tower, clock: FakeClock | None = None) -> Dcu1Session:
    return Dcu1Session(tower, "192.168.1.20", clock=clock or FakeClock())  # type: ignore[arg-type]


def test_ap1_keeps_a_bearing_and_am1_turns_to_it_once() -> None:
    tower = _Tower()
    dcu = session(tower)
    assert dcu.feed(b"AP1123;") == [b""] and tower.submitted == []  # no motion yet
    assert dcu.feed(b"AM1;") == [b""]
    (target,) = tower.submitted
    assert isinstance(target, Target) and (target.az_deg, target.el_deg) == (123, None)
    assert target.source is Source.DCU1 and target.origin is not None
    assert target.origin.who == "dcu1 192.168.1.20"
    assert dcu.feed(b"AM1;") == [DCU1_ERROR]  # once: nothing kept for a second AM1
    assert len(tower.submitted) == 1
    assert tower.refusals == [
        (f"AM1; with no bearing stored by AP1 in the last {DCU1_STORED_S:g} s", "dcu1 AM1;")
    ]


def test_a_bearing_kept_too_long_turns_nothing() -> None:
    """A pty outlives its clients: what one left stored is not the next one's to execute."""
    clock, tower = FakeClock(), _Tower()
    dcu = session(tower, clock)
    dcu.feed(b"AP1200;")
    clock.t += DCU1_STORED_S + 0.1
    assert dcu.feed(b"AM1;") == [DCU1_ERROR] and tower.submitted == []
    dcu.feed(b"AP1210;")
    clock.t += DCU1_STORED_S - 0.1
    assert dcu.feed(b"AM1;") == [b""] and [t.az_deg for t in tower.submitted] == [210]  # type: ignore[union-attr]


def test_a_bearing_kept_before_a_stop_turns_nothing_after_it() -> None:
    """Package rule 10 (review 102): a STOP or lock ON from any interface, or this client's own
    ``;``, between AP1 and AM1 leaves the AP1's bearing behind, however soon AM1 comes."""
    tower = _Tower()
    dcu = session(tower)
    dcu.feed(b"AP1200;")
    tower.halts += 1  # an operator's STOP, on MQTT
    assert dcu.feed(b"AM1;") == [DCU1_ERROR] and tower.submitted == []
    assert tower.refusals[-1][1] == "dcu1 AM1;"
    assert dcu.feed(b"AP1210;;AM1;") == [b"", b"", DCU1_ERROR]
    assert [type(c) for c in tower.submitted] == [Stop]
    assert dcu.feed(b"AP1220;AM1;") == [b"", b""]  # a STOP before it: taken
    assert [t.az_deg for t in tower.submitted[1:]] == [220]  # type: ignore[union-attr]


def test_a_bearing_whose_bytes_came_before_a_stop_turns_nothing_though_read_after_it() -> None:
    """Package rule 10 (attack 11): the halts that count are those of the look that held the
    AP1's bytes (tcplines.py rule 9, the fence), not those when it is read: a client paused
    over its budget has it read after a STOP that came after it. The client's own ``;``
    before it, in the same read, leaves it standing."""
    tower = _Tower()
    dcu = session(tower)
    dcu.fence.arrived = tower.halts  # the look that held AP1200;
    tower.halts += 1  # an operator's STOP, on MQTT, before the read
    assert dcu.feed(b"AP1200;") == [b""]
    dcu.fence.arrived = tower.halts  # AM1; came after the STOP
    assert dcu.feed(b"AM1;") == [DCU1_ERROR] and tower.submitted == []
    assert tower.refusals[-1] == (
        "AM1; after a STOP or lock ON that came after the AP1's bearing",
        "dcu1 AM1;",
    )
    assert dcu.feed(b";AP1220;AM1;") == [b"", b"", b""]  # its own stop first: taken
    assert [type(c) for c in tower.submitted] == [Stop, Target]
    assert tower.submitted[1].az_deg == 220  # type: ignore[union-attr]


def test_ap1_with_cr_turns_at_once() -> None:
    tower = _Tower()
    assert session(tower).feed(b"AP1359\r") == [b""]
    assert [(t.az_deg, t.source) for t in tower.submitted] == [(359, Source.DCU1)]  # type: ignore[union-attr]


@pytest.mark.parametrize(
    ("bearing", "reply"),
    [(120.0, b";120"), (0.4, b";000"), (45.5, b";046"), (359.6, b";000"), (7.0, b";007")],
)
def test_ai1_answers_four_bytes_the_bearing_in_whole_degrees(bearing: float, reply: bytes) -> None:
    assert session(_Tower(bearing)).feed(b"AI1;") == [reply]
    assert session(_Tower(bearing)).feed(b"AI1\r") == [reply]


def test_an_unknown_position_is_no_answer_never_a_number() -> None:
    tower = _Tower(None)
    assert session(tower).feed(b"AI1;") == [b""]
    tower = _Tower(100.0)
    tower.status.available = False
    assert session(tower).feed(b"AI1;") == [b""]


def test_a_stop_goes_first_is_never_answered_and_an_invalid_frames_semicolon_stops_too() -> None:
    tower = _Tower()
    dcu = session(tower)
    assert dcu.feed(b";") == [b""]
    assert dcu.feed(b"AS1;") == [b""]
    assert dcu.feed(b"AP1999;") == [DCU1_ERROR]  # junk, answered with the banner, and a stop
    assert [type(c) for c in tower.submitted] == [Stop, Stop, Stop]
    assert all(c.source is Source.DCU1 for c in tower.submitted)


def test_refusals_are_answered_with_the_banner_and_nothing_else_happens() -> None:
    tower = _Tower()
    tower.refuse = {Target, Stop}  # a lock refuses the move; the remote, offline, the stop
    dcu = session(tower)
    assert dcu.feed(b"AP1100\r") == [DCU1_ERROR]
    assert dcu.feed(b"AP1100;AM1;") == [b"", DCU1_ERROR]
    assert dcu.feed(b";") == [DCU1_ERROR]
    assert tower.submitted == []


def test_junk_options_and_version_turn_nothing() -> None:
    tower = _Tower()
    dcu = session(tower)
    assert dcu.feed(b"EeJjOoSs") == [b""] * 8  # options: taken, the station's are its own
    assert dcu.feed(b"V") == [DCU1_ERROR]  # the board's banner names its version
    assert dcu.feed(b"xyz 123!\r\n") == [DCU1_ERROR]  # a run of junk: one answer
    assert dcu.feed(b"AP1\x00\x01\x02\x03") == [DCU1_ERROR]
    assert tower.submitted == [] and dcu.idle


def test_a_failure_inside_is_answered_with_the_banner() -> None:
    tower = _Tower()
    tower.status = None  # type: ignore[assignment]
    assert session(tower).feed(b"AI1;") == [DCU1_ERROR]


# -- GS-232A readings -------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("replies", "line", "reply"),
    [
        ("A", b"C\r", b"+0120\r\n"),
        ("A", b"B\r", b"+0030\r\n"),
        ("A", b"C2\r", b"+0120+0030\r\n"),
        ("B", b"C2\r", b"AZ=120  EL=030\r\n"),
        ("A", b"H\r", b"?>\r\n"),
    ],
)
def test_gs232_a_or_b_readings(replies: str, line: bytes, reply: bytes) -> None:
    tower = _Tower()
    tower.spec = SimpleNamespace(has_elevation=True, can_report_position=True)
    tower.status.elevation_deg = 30.0
    assert Gs232Session(tower, replies=replies).feed(line) == [reply]  # type: ignore[arg-type]


def test_the_configuration_reference_quotes_the_readings_byte_for_byte() -> None:
    """docs/configuration.md's gs232_replies shows each reading as the port sends it (a
    GS-232B's two spaces too: the page's generator ran them together)."""
    tower = _Tower()
    tower.spec = SimpleNamespace(has_elevation=True, can_report_position=True)
    tower.status.elevation_deg = 0.0
    (line,) = [ln for ln in render().splitlines() if ln.startswith("- **`gs232_replies`**")]
    for replies in ("A", "B"):
        (reply,) = Gs232Session(tower, replies=replies).feed(b"C2\r")  # type: ignore[arg-type]
        assert f"`{reply.decode().rstrip()}`" in line, (replies, line)


def test_gs232_replies_are_a_or_b() -> None:
    with pytest.raises(ValueError, match="A or B"):
        Gs232Session(_Tower(), replies="C")  # type: ignore[arg-type]


def test_the_settings_name_every_emulation_the_table_has() -> None:
    assert tuple(EMULATIONS) == EMULATION_KEYS
    assert EMULATIONS["dcu1"].ends == b"\r\n;"  # a DCU-1 command ends at ";" as well
