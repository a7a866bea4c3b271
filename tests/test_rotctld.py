"""The rotctld port, byte for byte: real TCP sockets, the real Rotator, an emulated controller on
a pty. Expected bytes are those rotctld 4.5.4 sends (for models 401 and 403 also checked against
the real rotctld driving the same emulator).
"""

from __future__ import annotations

import socket
import subprocess
import sys
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from pydantic import ValidationError

from bridge import emulators
from bridge.app import worker_config
from bridge.core.model import ErrorEvent, Lock, MotionState, Source, Stop
from bridge.emulators import EmulatedPort
from bridge.interfaces import tcplines
from bridge.interfaces.rotctld import QUIT, Request, RequestParser, RotctldServer
from bridge.interfaces.rotctld.parser import OVERLONG, holds_stop
from bridge.interfaces.rotctld.server import RotctldSession
from bridge.runtime.rotator import Rotator
from bridge.runtime.state_store import StateStore
from bridge.settings import RotatorSettings, Settings
from tests.support import feed, wait_until
from tests.support.clock import FakeClock
from tests.support.hamlib import run_rotctl
from tests.support.rig import FAST_POLLING
from tests.support.waiting import slow


class Client:
    """A rotctld client on a real socket; replies are read until exactly the expected length."""

    def __init__(self, port: int) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=slow(5))

    def send(self, data: bytes) -> None:
        self.sock.sendall(data)

    def read(self, n: int) -> bytes:
        buf = b""
        while len(buf) < n:
            chunk = self.sock.recv(n - len(buf))
            if not chunk:
                break
            buf += chunk
        return buf

    def ask(self, request: bytes, expected: bytes) -> None:
        self.send(request)
        assert self.read(len(expected)) == expected

    def single_recv(self, request: bytes) -> bytes:
        """What one recv() returns, as Gpredict reads it."""
        self.send(request)
        return self.sock.recv(4096)

    def at_eof(self) -> bool:
        try:
            return self.sock.recv(4096) == b""
        except ConnectionResetError:  # turned away: reset
            return True

    def close(self) -> None:
        self.sock.close()


@dataclass
class Station:
    emu: EmulatedPort[Any]
    rotator: Rotator
    server: RotctldServer
    events: list[ErrorEvent]
    clients: list[Client]

    def connect(self) -> Client:
        client = Client(self.server.port)
        self.clients.append(client)
        return client

    def bearing_frames(self) -> list[bytes]:
        return [f.data for f in self.emu.log() if f.data.startswith((b"AP", b"AM"))]


StationFactory = Callable[..., Station]


@pytest.fixture
def station(tmp_path: Path) -> Iterator[StationFactory]:
    made: list[Station] = []

    def make(
        model: str = "rotorez",
        *,
        start_az_deg: float = 123,
        park_az_deg: float | None = None,
        **settings: Any,
    ) -> Station:
        link = tmp_path / f"serial-{model}-{len(made)}"
        spid = model in ("rot2prog", "rot1prog", "md01")
        axes = spid or model.startswith("gs232")  # an emulator of az_speed_deg_s, no brake
        faults = {} if axes else {"jitter_deg": 0, "power_on_junk": False}
        emu = emulators.start(
            model,
            link=str(link),
            start_az_deg=start_az_deg,
            **({"az_speed_deg_s": 40.0} if axes else {"speed_deg_s": 40.0}),
            **({} if axes else {"brake_delay_s": 0.0 if model == "rotorcard" else 1.5}),
            **faults,
        )
        cfg = RotatorSettings(
            id="tower",
            model=model,
            port=str(link),
            brake_delay_s=0 if model in ("rotorcard", "rot2prog", "rot1prog", "md01") else 1.5,
            park_az_deg=park_az_deg,
            **{**FAST_POLLING, **settings},
        )
        events: list[ErrorEvent] = []
        rotator = Rotator(
            worker_config(cfg),
            StateStore(tmp_path / f"state-{len(made)}.json"),
            on_status=lambda status: None,
            on_event=events.append,
        )
        server = RotctldServer(rotator, 0)
        st = Station(emu, rotator, server, events, [])
        made.append(st)
        rotator.start()
        server.start()
        wait_until(lambda: rotator.status.available, 5, "rotator available")
        return st

    yield make
    for st in made:
        for client in st.clients:
            client.close()
        st.server.stop()
        st.rotator.stop()
        st.emu.close()


# -- the request parser (sans-IO), fed three ways ------------------------------------------------


def parse(data: bytes, *, bytewise: bool = False) -> list[Request | object]:
    return feed(RequestParser(), data, "bytewise" if bytewise else "whole")


def summary(items: list[Request | object]) -> list[object]:
    return [
        (i.command.name, i.args, i.extended, i.sep) if isinstance(i, Request) else i for i in items
    ]


@pytest.mark.parametrize("bytewise", [False, True])
def test_parser_reads_commands_as_rotctld_does(bytewise: bool) -> None:
    data = (
        b"p\r\n"  # CR LF
        b"P 10,5 20\r"  # CR alone ends a line; comma kept as typed
        b"+\\set_pos 1 2\n"  # extended, long name
        b";p\n|_\n,S\n"  # separators
        b"P 10\n20\n"  # arguments taken from the next line
        b"Z\\nonsense p\n"  # unknown commands are skipped, what follows still counts
        b"#P 1 1\n"  # a comment line
        b"\\dump_state\n1\nq\n"
    )
    assert summary(parse(data, bytewise=bytewise)) == [
        ("get_pos", (), False, "\n"),
        ("set_pos", ("10,5", "20"), False, "\n"),
        ("set_pos", ("1", "2"), True, "\n"),
        ("get_pos", (), True, ";"),
        ("get_info", (), True, "|"),
        ("stop", (), True, ","),
        ("set_pos", ("10", "20"), False, "\n"),
        ("get_pos", (), False, "\n"),
        ("dump_state", (), False, "\n"),
        ("dump_caps", (), False, "\n"),
        QUIT,
    ]


def test_parser_runs_nothing_that_is_unfinished() -> None:
    parser = RequestParser()
    assert parser.feed(b"P 120 0") == []  # the last argument is not terminated yet
    assert not parser.idle
    assert summary(parser.feed(b"\n")) == [("set_pos", ("120", "0"), False, "\n")]
    assert parser.idle
    assert parser.feed(b"+P 1") == [] and not parser.idle


@pytest.mark.parametrize("stop", ["S", "\\stop", "+S", ";S", "|S", "+\\stop", "\\stop;", "+;S"])
def test_a_stop_where_a_number_is_awaited_is_a_stop_too(stop: str) -> None:
    """Rule 1's departure (attack passes): ``P 200`` left short, then a stop: rotctld takes the
    stop as the elevation and it is lost. Here it is carried out at once, and the P still
    takes its arguments as rotctld does (refused when whole): a line runs nothing else."""
    data = f"P 200\n{stop}\nP {stop} K\nM 2\n{stop}\nC S S\np\n".encode()
    assert summary(parse(data)) == [
        ("stop", (), False, "\n"),  # at once ...
        ("set_pos", ("200", stop), False, "\n"),  # ... then the P, refused (not a number)
        ("stop", (), False, "\n"),
        ("set_pos", (stop, "K"), False, "\n"),  # the K is its argument, as rotctld reads it
        ("stop", (), False, "\n"),
        ("move", ("2", stop), False, "\n"),
        ("stop", (), False, "\n"),  # words: a word that is a stop and nothing else stops
        ("stop", (), False, "\n"),
        ("set_conf", ("S", "S"), False, "\n"),
        ("get_pos", (), False, "\n"),
    ]
    parser = RequestParser()
    assert summary(parser.feed(b"P S ")) == [("stop", (), False, "\n")]  # not waiting for more
    assert not parser.idle and summary(parser.feed(b"20\n"))[0][0] == "set_pos"


def test_parser_survives_junk_and_keeps_an_overlong_argument_as_one() -> None:
    junk = bytes(range(256)).replace(b"q", b"").replace(b"Q", b"")
    parser = RequestParser()
    parser.feed(junk + b"\n")  # whatever junk parses into, the stream stays usable
    parser.feed(b"\n" * 3)
    assert summary(parser.feed(b"P " + b"9" * 500 + b" 0\np\n")) == [
        ("set_pos", (OVERLONG, "0"), False, "\n"),  # refused, as rotctld refuses it
        ("get_pos", (), False, "\n"),
    ]


def test_an_overlong_argument_is_one_and_the_next_line_is_still_the_commands() -> None:
    """An attack pass: the command was dropped with its line, and the next line, which rotctld
    takes as the command's last argument, ran as commands of its own (a park, a set_pos)."""
    assert summary(parse(b"P\n" + b"1" * 100 + b"\nK\n")) == [
        ("set_pos", (OVERLONG, "K"), False, "\n")
    ]
    assert summary(parse(b"P\n" + b"1" * 100 + b"\nP 20 30\n")) == [
        ("set_pos", (OVERLONG, "P"), False, "\n")  # then "20" and "30": no commands
    ]
    stopped = summary(parse(b"P 10\n" + b"S" * 70 + b"\n"))  # begins as a stop: stops
    assert stopped == [("stop", (), False, "\n"), ("set_pos", ("10", OVERLONG), False, "\n")]


@pytest.mark.parametrize("stop", [";;S", ";+S", "++;S", "ZS", "pS", "\\stop+"])
def test_every_form_a_stop_takes_as_a_command_stops_as_an_argument(stop: str) -> None:
    """Rule 1 (an attack pass): the argument is read as commands by a parser of its own."""
    items = summary(parse(f"P 200\n{stop}\n".encode()))
    assert items == [("stop", (), False, "\n"), ("set_pos", ("200", stop), False, "\n")]


def test_a_stop_argument_is_carried_out_before_its_token_ends() -> None:
    """Rule 1: a bare ``S`` runs at once as a command; as an argument too (an attack pass)."""
    assert summary(RequestParser().feed(b"P 200\nS")) == [("stop", (), False, "\n")]


def test_send_cmd_takes_its_line_as_rotctld_reads_it() -> None:
    """Rule 3 (an attack pass): a bare ``w`` line, or one ended by CR, let the next line run
    (a set_pos, a park); rotctld reads to LF, and again when the line had nothing on it."""
    assert summary(parse(b"w\nP 20 30\n")) == [("send_cmd", ("P 20 30",), False, "\n")]
    assert summary(parse(b"w abc\rK\n")) == [("send_cmd", ("abc\rK",), False, "\n")]
    # a review: rotctld reads again only when the rest of the line is empty, and only once
    assert summary(parse(b"w \nK\n")) == [
        ("send_cmd", ("",), False, "\n"),
        ("park", (), False, "\n"),
    ]
    assert summary(parse(b"w\n\nK\n"))[1][0] == "park"
    assert summary(parse(b"w\nS\n")) == [  # rule 1: a line that is a stop stops
        ("stop", (), False, "\n"),
        ("send_cmd", ("S",), False, "\n"),
    ]


def test_a_first_argument_asking_what_a_command_takes_is_its_last() -> None:
    """As rotctld (an attack pass): ``V ? S`` is set_level ``?``, then a stop."""
    assert summary(parse(b"V ? S\nP ?\nV SPEED\nS\n")) == [
        ("set_level", ("?", ""), False, "\n"),
        ("stop", (), False, "\n"),
        ("set_pos", ("?", ""), False, "\n"),
        ("stop", (), False, "\n"),  # rule 1: a stop where a word is awaited
        ("set_level", ("SPEED", "S"), False, "\n"),
    ]


def test_an_argument_is_read_as_commands_one_level_deep() -> None:
    """Rule 1 (an attack pass: nested readers made a line of P's 20 times the cost of one of
    numbers); ``PS`` as a command is a P whose argument is S: no stop, here as in rotctld."""
    assert summary(parse(b"P 1 " + b"P" * 64 + b"\n")) == [
        ("set_pos", ("1", "P" * 64), False, "\n")
    ]
    assert summary(parse(b"P 1 PS\n")) == [("set_pos", ("1", "PS"), False, "\n")]


def test_rotctlds_other_commands_keep_their_arguments() -> None:
    """Rule 3 (an attack pass): the bridge knew none of these, and their arguments ran as
    commands (``w P 20 30`` set the position; ``\\pause K`` parked)."""
    data = b"w P 20 30\n\\pause K\nD K K K K\nL K 1 2\nV K 1\nv K\nU K 1\nx K\nB 1 2 3 4\n"
    assert [i[0] for i in summary(parse(data))] == [
        "send_cmd",
        "pause",
        "dms2dec",
        "lonlat2loc",
        "set_level",
        "get_level",
        "set_func",
        "get_parm",
        "qrb",
    ]
    assert summary(parse(b"w P 20 30\n"))[0][1] == ("P 20 30",)  # the rest of the line


# -- get_pos ------------------------------------------------------------------------------------


def test_get_pos_answers_from_status_in_one_send(station: StationFactory) -> None:
    st = station()
    c = st.connect()
    assert c.single_recv(b"p\n") == b"123.00\n0.00\n"
    assert c.single_recv(b"\\get_pos\r\n") == b"123.00\n0.00\n"
    assert c.single_recv(b"p\r") == b"123.00\n0.00\n"


def test_get_pos_causes_no_serial_traffic(station: StationFactory) -> None:
    st = station()
    c = st.connect()

    def queries() -> int:
        return sum(1 for f in st.emu.log() if f.data.startswith(b"AI1"))

    wait_until(lambda: queries() > 0, 5, "the bridge's own first poll")  # the counter counts
    before = queries()
    c.ask(b"p\n" * 200, b"123.00\n0.00\n" * 200)
    assert queries() - before < 10  # the bridge's own idle polling, not one query per p


def test_get_pos_extended_forms(station: StationFactory) -> None:
    c = station().connect()
    c.ask(b"+p\n", b"get_pos:\nAzimuth: 123.00\nElevation: 0.00\nRPRT 0\n")
    c.ask(b";p\n", b"get_pos:;Azimuth: 123.00;Elevation: 0.00;RPRT 0\n")
    c.ask(b"|p\n", b"get_pos:|Azimuth: 123.00|Elevation: 0.00|RPRT 0\n")
    c.ask(b",p\n", b"get_pos:,Azimuth: 123.00,Elevation: 0.00,RPRT 0\n")
    c.ask(b"+\\get_pos\n", b"get_pos:\nAzimuth: 123.00\nElevation: 0.00\nRPRT 0\n")


@pytest.mark.parametrize("blank", [b" ", b"\t", b"\n", b"\r\n"])
def test_a_prefix_not_followed_at_once_by_its_command_is_forgotten(
    station: StationFactory, blank: bytes
) -> None:
    """Rule 1, as rotctld 4.5.4 reads it (compared with ``rotctld -m 401`` on the same
    emulator): the character after ``+`` or ``;`` is the command; a blank there is the
    unknown command ' ' and the prefix is gone, so ``+ p`` is answered in the terse form."""
    c = station().connect()
    c.ask(b"+" + blank + b"p\n", b"123.00\n0.00\n")
    c.ask(b";" + blank + b"S\n", b"RPRT 0\n")
    c.ask(b"+;" + blank + b"p\n", b"123.00\n0.00\n")
    c.ask(b"+p\n", b"get_pos:\nAzimuth: 123.00\nElevation: 0.00\nRPRT 0\n")  # still extended


def test_get_pos_on_a_dcu1_is_not_available(station: StationFactory) -> None:
    c = station("dcu1").connect()
    c.ask(b"p\n", b"RPRT -11\n")
    c.ask(b"+p\n", b"get_pos:\nRPRT -11\n")
    c.ask(b";p\n", b"get_pos:;RPRT -11\n")


def test_a_port_that_is_gone_gives_an_io_error_never_the_old_bearing(
    station: StationFactory,
) -> None:
    st = station()
    c = st.connect()
    c.ask(b"p\n", b"123.00\n0.00\n")
    st.emu.unplug()
    wait_until(lambda: not st.rotator.status.connected, 5, "port closed")
    c.ask(b"p\n", b"RPRT -6\n")
    c.ask(b"+p\n", b"get_pos:\nRPRT -6\n")
    c.ask(b"P 10 0\n", b"RPRT -6\n")
    c.ask(b"+P 10 0\n", b"set_pos: 10 0\nRPRT -6\n")


def test_a_silent_controller_gives_a_timeout(station: StationFactory) -> None:
    st = station()
    c = st.connect()
    st.emu.set_silent(True)
    wait_until(lambda: not st.rotator.status.available, 5, "controller silent")
    assert st.rotator.status.connected
    c.ask(b"p\n", b"RPRT -5\n")
    c.ask(b";p\n", b"get_pos:;RPRT -5\n")
    c.ask(b"P 10 0\n", b"RPRT -5\n")
    assert st.bearing_frames() == []


# -- set_pos ------------------------------------------------------------------------------------


def test_set_pos_moves_the_rotor_through_the_rotator(station: StationFactory) -> None:
    st = station("rotorcard")
    c = st.connect()
    c.ask(b"P 200 0\n", b"RPRT 0\n")
    st.emu.wait_for_frame(b"AP1200\r", "executed")
    wait_until(lambda: st.rotator.status.last_command_source == "rotctld", 5, "source rotctld")
    c.ask(b"S\n", b"RPRT 0\n")
    st.emu.wait_for(lambda s: not s.is_moving)


def test_set_pos_extended_echoes_the_arguments_as_typed(station: StationFactory) -> None:
    st = station("rotorcard")
    c = st.connect()
    c.ask(b"+P 10,5 0\n", b"set_pos: 10,5 0\nRPRT 0\n")
    st.emu.wait_for(lambda s: s.target_az_deg is not None and abs(s.target_az_deg - 10.5) <= 0.5)
    c.ask(b";\\set_pos 20 0\n", b"set_pos: 20 0;RPRT 0\n")
    c.ask(b",P 30 0\n", b"set_pos: 30 0,RPRT 0\n")


def test_set_pos_errors(station: StationFactory) -> None:
    st = station("rotorez", az_max_deg=350)
    c = st.connect()
    c.ask(b"P 999 0\n", b"RPRT -1\n")
    c.ask(b"+P 999 0\n", b"set_pos: 999 0\nRPRT -1\n")
    c.ask(b"P 350,5 0\n", b"RPRT -1\n")  # the comma is a decimal point: 350.5 > 350
    c.ask(b"P 90 10\n", b"RPRT -1\n")  # azimuth-only model: elevation must be 0
    c.ask(b"P abc 0\n", b"RPRT -1\n")
    c.ask(b"P nan 0\n", b"RPRT -1\n")
    c.ask(b"|P 90 x\n", b"set_pos: 90 x|RPRT -1\n")
    assert st.bearing_frames() == []
    refused = [(e.kind, e.command) for e in st.events]
    assert ("refused", "rotctld set_pos 999 0") in refused
    assert ("refused", "rotctld set_pos 90 10") in refused  # MQTT's error topic hears of it
    for typed in ("abc 0", "nan 0", "90 x"):  # no numbers: said too (package rule 6)
        assert ("refused", f"rotctld set_pos {typed}") in refused
    said = next(e.message for e in st.events if e.command == "rotctld set_pos nan 0")
    assert said == "P 'nan 0': the azimuth and elevation are no numbers"


def test_a_locked_rotator_rejects_moves_but_not_stop(station: StationFactory) -> None:
    st = station(park_az_deg=10)
    st.rotator.submit(Lock(True))
    c = st.connect()
    c.ask(b"P 100 0\n", b"RPRT -9\n")
    c.ask(b"+P 100 0\n", b"set_pos: 100 0\nRPRT -9\n")
    c.ask(b"K\n", b"RPRT -9\n")
    c.ask(b"S\n", b"RPRT 0\n")
    assert st.bearing_frames() == []
    refusal = next(e for e in st.events if e.kind == "refused")
    assert refusal.command == "rotctld set_pos 100 0" and "locked" in refusal.message


# -- stop, park, move, reset, get_status --------------------------------------------------------


def test_stop_forms(station: StationFactory) -> None:
    c = station().connect()
    c.ask(b"S\n", b"RPRT 0\n")
    c.ask(b"\\stop\n", b"RPRT 0\n")
    c.ask(b"+S\n", b"stop:\nRPRT 0\n")
    c.ask(b";S\n", b"stop:;RPRT 0\n")


def test_a_stop_after_a_command_left_short_stops(station: StationFactory) -> None:
    st = station(start_az_deg=10)  # 290 degrees to go: over 7 s at 40 degrees a second
    c = st.connect()
    c.ask(b"P 300 0\n", b"RPRT 0\n")
    st.emu.wait_for(lambda s: s.is_moving, slow(10))
    c.ask(b"P 200\nS\n", b"RPRT 0\nRPRT -1\n")  # the stop carried out, the short P refused
    st.emu.wait_for(lambda s: not s.is_moving, slow(10))
    assert st.emu.state().az_deg < 290  # stopped on its way, not arrived


def test_rotctlds_other_commands_are_not_available_and_move_nothing(
    station: StationFactory,
) -> None:
    st = station()
    c = st.connect()
    c.ask(b"w P 200 0\n", b"RPRT -11\n")
    c.ask(b"\\pause K\n", b"RPRT -11\n")
    c.ask(b"V SPEED 5\n", b"RPRT -11\n")  # a word beginning with S is no stop here
    c.ask(b"p\n", b"123.00\n0.00\n")
    assert st.bearing_frames() == []


def test_park_without_a_park_position_is_not_available(station: StationFactory) -> None:
    c = station().connect()
    c.ask(b"K\n", b"RPRT -11\n")
    c.ask(b"+K\n", b"park:\nRPRT -11\n")
    c.ask(b"\\park\n", b"RPRT -11\n")


def test_park_goes_to_the_configured_position(station: StationFactory) -> None:
    st = station("rotorcard", park_az_deg=30)
    c = st.connect()
    c.ask(b"+K\n", b"park:\nRPRT 0\n")
    st.emu.wait_for_frame(b"AP1030\r", "executed")
    st.emu.wait_for(lambda s: not s.is_moving and abs(s.az_deg - 30) < 1, 10)


def test_move_reset_set_conf_and_get_status_are_not_available(station: StationFactory) -> None:
    c = station().connect()
    c.ask(b"M 2 5\n", b"RPRT -11\n")
    c.ask(b"+M 8 5\n", b"move: 8 5\nRPRT -11\n")
    c.ask(b"\\move 2 5\n", b"RPRT -11\n")
    c.ask(b"M x 5\n", b"RPRT -1\n")
    c.ask(b"R 1\n", b"RPRT -11\n")
    c.ask(b"C jam 0\n", b"RPRT -11\n")
    c.ask(b"s\n", b"RPRT -11\n")
    c.ask(b"+s\n", b"get_status:\nRPRT -11\n")


def test_move_and_reset_read_their_arguments_as_rotctld_does(station: StationFactory) -> None:
    """As rotctld 4.5.4 (compared with ``rotctld -m 401`` on the same emulator): a direction
    by name (LEFT, CCW, RIGHT, CW, UP, DOWN) and a number read as C's ``%d`` reads it (its
    leading integer) are the command's; not carried out, "not available", never "invalid"."""
    c = station().connect()
    for words in (
        b"LEFT 50",
        b"CCW 50",
        b"RIGHT 5",
        b"CW 5",
        b"UP 1",
        b"DOWN 1",
        b"8x 5",
        b"8 5.5",
    ):
        c.ask(b"M " + words + b"\n", b"RPRT -11\n")
    c.ask(b"+M CW 5\n", b"move: CW 5\nRPRT -11\n")
    c.ask(b"R 1x\n", b"RPRT -11\n")
    for wrong in (b"M left 50", b"M x 50", b"M 8 x", b"M 8 -", b"R x"):  # no number: invalid
        c.ask(wrong + b"\n", b"RPRT -1\n")


# -- get_info, dump_state, dump_caps ------------------------------------------------------------


@pytest.mark.parametrize(
    ("model", "info"),
    [("rotorez", b"Rotor-EZ"), ("rotorcard", b"RotorCard"), ("dcu1", b"DCU-1/DCU-1X")],
)
def test_get_info(station: StationFactory, model: str, info: bytes) -> None:
    c = station(model).connect()
    c.ask(b"_\n", info + b"\n")
    c.ask(b"\\get_info\n", info + b"\n")
    c.ask(b"+_\n", b"get_info:\nInfo: " + info + b"\nRPRT 0\n")
    c.ask(b";_\n", b"get_info:;Info: " + info + b";RPRT 0\n")


@pytest.mark.parametrize(("model", "number"), [("rotorez", 401), ("rotorcard", 402), ("dcu1", 403)])
def test_dump_state_is_what_rotctl_needs_to_open(
    station: StationFactory, model: str, number: int
) -> None:
    c = station(model).connect()
    c.ask(
        b"\\dump_state\n",
        b"1\n%d\nmin_az=0.000000\nmax_az=360.000000\nmin_el=0.000000\nmax_el=0.000000\n"
        b"south_zero=0\nrot_type=Other\ndone\n" % number,
    )


def test_dump_state_shows_the_configured_limits_and_the_extended_forms(
    station: StationFactory,
) -> None:
    c = station(az_min_deg=10, az_max_deg=350.5).connect()
    c.ask(
        b"\\dump_state\n",
        b"1\n401\nmin_az=10.000000\nmax_az=350.500000\nmin_el=0.000000\nmax_el=0.000000\n"
        b"south_zero=0\nrot_type=Other\ndone\n",
    )
    c.ask(
        b"+\\dump_state\n",
        b"dump_state:\nrotctld Protocol Ver: 1\nRotor Model: 401\n"
        b"Minimum Azimuth: 10.000000\nMaximum Azimuth: 350.500000\n"
        b"Minimum Elevation: 0.000000\nMaximum Elevation: 0.000000\nSouth Zero: 0\n"
        b"rot_type=Other\ndone\nRPRT 0\n",
    )
    c.ask(
        b";\\dump_state\n",
        b"dump_state:;rotctld Protocol Ver: 1;Rotor Model: 401;"
        b"Minimum Azimuth: 10.000000;Maximum Azimuth: 350.500000;"
        b"Minimum Elevation: 0.000000;Maximum Elevation: 0.000000;South Zero: 0;"
        b"rot_type=Other;done;RPRT 0\n",
    )


def test_dump_caps_is_caps_text_then_rprt_0(station: StationFactory) -> None:
    c = station().connect()
    caps = (
        b"Caps dump for model:\t401\nModel name:\t\tRotor-EZ\nMfg name:\t\tIdiom Press\n"
        b"Backend version:\trotor-bridge\nBackend status:\t\tStable\nRot type:\t\tOther\n"
        b"Port type:\t\tNetwork link (rotor-bridge)\n"
        b"Min Azimuth:\t\t0.00\nMax Azimuth:\t\t360.00\n"
        b"Min Elevation:\t\t0.00\nMax Elevation:\t\t0.00\n"
        b"Can set Position:\tY\nCan get Position:\tY\nCan Stop:\t\tY\nCan Park:\t\tN\n"
        b"Can Reset:\t\tN\nCan Move:\t\tN\nCan get Info:\t\tY\nCan get Status:\t\tN\n"
        b"\nOverall backend warnings: 0\n"
    )
    c.ask(b"1\n", caps + b"RPRT 0\n")
    c.ask(b"\\dump_caps\n", caps + b"RPRT 0\n")
    c.ask(b"+1\n", b"dump_caps:\n" + caps + b"RPRT 0\n")


# Hamlib 4.5.4's own answers for each model: model number and rot_type (dump_state), get_info
# ("None" where the backend has none; dump_caps then says it cannot), with the model's range
HAMLIB_FACTS = {
    "rotorez": (401, b"Other", b"Rotor-EZ"),
    "rotorcard": (402, b"Other", b"RotorCard"),
    "dcu1": (403, b"Other", b"DCU-1/DCU-1X"),
    "rot2prog": (901, b"AzEl", b"None"),
    "rot1prog": (902, b"Az", b"None"),
    "md01": (903, b"AzEl", b"None"),
    "satel": (2101, b"AzEl", b"SatEL rotator"),
    "prosistel": (1701, b"Az", b"None"),
    "prosistel-el": (1702, b"Az", b"None"),  # its elevation is the bearing it answers
    "prosistel-el-a": (1704, b"Az", b"None"),  # the same, a box answering as unit A
    "prosistel-combi": (1703, b"AzEl", b"None"),
}
RANGES = {
    "rot2prog": b"min_az=-180.000000\nmax_az=540.000000\nmin_el=-20.000000\nmax_el=210.000000\n",
    "rot1prog": b"min_az=-180.000000\nmax_az=540.000000\nmin_el=0.000000\nmax_el=0.000000\n",
    "md01": b"min_az=-180.000000\nmax_az=540.000000\nmin_el=-20.000000\nmax_el=210.000000\n",
    "satel": b"min_az=0.000000\nmax_az=360.000000\nmin_el=0.000000\nmax_el=90.000000\n",
    "prosistel-el": b"min_az=0.000000\nmax_az=90.000000\nmin_el=0.000000\nmax_el=0.000000\n",
    "prosistel-el-a": b"min_az=0.000000\nmax_az=90.000000\nmin_el=0.000000\nmax_el=0.000000\n",
    "prosistel-combi": b"min_az=0.000000\nmax_az=360.000000\nmin_el=0.000000\nmax_el=90.000000\n",
}
CAPS_ROT_TYPE = {b"Other": b"Other", b"Az": b"Azimuth", b"AzEl": b"Az-El"}


@pytest.fixture
def unstarted(tmp_path: Path) -> Iterator[Callable[[str], Client]]:
    """A rotctld port onto a rotator of ``model`` whose worker never runs: what rotctld says
    about the model alone, without a controller."""
    servers: list[tuple[RotctldServer, Client]] = []

    def make(model: str) -> Client:
        cfg = RotatorSettings(id="tower", model=model, port=str(tmp_path / "no-such-port"))
        rotator = Rotator(
            worker_config(cfg),
            StateStore(tmp_path / f"state-{model}.json"),
            on_status=lambda status: None,
            on_event=lambda event: None,
        )
        server = RotctldServer(rotator, 0)
        server.start()
        client = Client(server.port)
        servers.append((server, client))
        return client

    yield make
    for server, client in servers:
        client.close()
        server.stop()


@pytest.mark.parametrize("model", sorted(HAMLIB_FACTS))
def test_every_model_is_shown_as_hamlib_shows_it(
    unstarted: Callable[[str], Client], model: str
) -> None:
    number, rot_type, info = HAMLIB_FACTS[model]
    c = unstarted(model)
    c.ask(b"_\n", info + b"\n")
    ranges = RANGES.get(
        model, b"min_az=0.000000\nmax_az=360.000000\nmin_el=0.000000\nmax_el=0.000000\n"
    )
    c.ask(
        b"\\dump_state\n",
        b"1\n%d\n" % number + ranges + b"south_zero=0\nrot_type=" + rot_type + b"\ndone\n",
    )
    c.send(b"1\n")
    caps = b""
    while not caps.endswith(b"RPRT 0\n"):
        chunk = c.sock.recv(4096)
        assert chunk, caps
        caps += chunk
    assert caps.startswith(b"Caps dump for model:\t%d\n" % number)
    assert b"Rot type:\t\t" + CAPS_ROT_TYPE[rot_type] + b"\n" in caps
    assert b"Can get Info:\t\t" + (b"N" if info == b"None" else b"Y") + b"\n" in caps


# -- the stream: unknown commands, quit, clients ------------------------------------------------


def test_unknown_commands_get_no_reply_at_all(station: StationFactory) -> None:
    st = station()
    c = st.connect()
    # each reply is the next thing on the socket: nothing came before it
    c.ask(b"Z\np\n", b"123.00\n0.00\n")
    c.ask(b"\\nonsense\np\n", b"123.00\n0.00\n")
    c.ask(b"#P 200 0\n_\n", b"Rotor-EZ\n")
    assert st.bearing_frames() == [] and st.events == []


@pytest.mark.parametrize("quit_cmd", [b"q\n", b"Q\n", b"+q\n"])
def test_quit_closes_the_connection_without_a_reply(
    station: StationFactory, quit_cmd: bytes
) -> None:
    st = station()
    c = st.connect()
    c.ask(b"p\n", b"123.00\n0.00\n")
    c.send(quit_cmd)
    assert c.at_eof()
    wait_until(lambda: st.server.client_count == 0, 5, "client gone")


def test_several_clients_at_once_each_with_its_own_half_finished_line(
    station: StationFactory,
) -> None:
    st = station("rotorcard")
    a, b = st.connect(), st.connect()
    wait_until(lambda: st.server.client_count == 2, 5, "two clients")
    a.send(b"P 2")  # half a command on one connection ...
    b.ask(b"+p\n", b"get_pos:\nAzimuth: 123.00\nElevation: 0.00\nRPRT 0\n")  # ... another works
    a.ask(b"00 0\n", b"RPRT 0\n")
    st.emu.wait_for_frame(b"AP1200\r", "executed")
    b.ask(b"S\n", b"RPRT 0\n")


def test_a_client_gone_mid_command_leaves_nothing_behind(station: StationFactory) -> None:
    st = station("rotorcard")
    wait_until(lambda: st.rotator.status.state is MotionState.IDLE, 5, "idle")
    for partial in (b"P 200", b"P 200 0", b"+\\set_pos 200"):
        c = st.connect()
        c.send(partial)
        c.close()
        wait_until(lambda: st.server.client_count == 0, 5, "client gone")
    # a complete command afterwards is the only one the controller ever sees
    st.connect().ask(b"P 60 0\n", b"RPRT 0\n")
    st.emu.wait_for(lambda s: not s.is_moving and abs(s.az_deg - 60) < 1, 10)
    assert st.bearing_frames() == [b"AP1060\r"]


def test_stopping_the_server_closes_its_clients_and_frees_the_port(
    station: StationFactory,
) -> None:
    st = station()
    c = st.connect()
    c.ask(b"p\n", b"123.00\n0.00\n")
    port = st.server.port
    st.server.stop()
    assert c.at_eof()
    again = RotctldServer(st.rotator, port)
    again.start()  # the port is free again at once
    try:
        Client(port).ask(b"_\n", b"Rotor-EZ\n")
    finally:
        again.stop()


def test_a_port_in_use_is_a_clear_error(station: StationFactory) -> None:
    st = station()
    other = RotctldServer(st.rotator, st.server.port)
    with pytest.raises(OSError, match="rotctld for rotator 'tower': cannot listen on 127.0.0.1"):
        other.start()


def test_a_client_beyond_the_limit_takes_the_slot_of_the_one_idle_longest(
    station: StationFactory,
) -> None:
    """Every slot taken: the newcomer gets in (it may be the operator's stop) and the client
    idle longest goes; one in the middle of a command goes last, but goes: a newcomer is
    never turned away (attack passes kept every stop out with clients always mid-command)."""
    st = station()
    small = RotctldServer(st.rotator, 0, max_clients=1, clock=FakeClock())
    small.start()
    try:
        first = Client(small.port)
        first.ask(b"_\n", b"Rotor-EZ\n")
        second = Client(small.port)
        second.ask(b"_\n", b"Rotor-EZ\n")
        assert first.at_eof()
        second.send(b"\\")  # half a command
        wait_until(lambda: small.client_count == 1, 5, "the first gone")
        wait_until(
            lambda: all(c.pending_s is not None for c in small._clients.values()), 5, "mid-command"
        )
        third = Client(small.port)
        third.ask(b"S\n", b"RPRT 0\n")
        assert second.at_eof()
        for client in (first, second, third):
            client.close()
    finally:
        small.stop()


def _turned_away(port: int) -> bool:
    try:
        return Client(port).at_eof()
    except ConnectionResetError:  # the reset came before connect() returned
        return True


# -- configuration ------------------------------------------------------------------------------


def rotator_settings(**kw: Any) -> RotatorSettings:
    return RotatorSettings(id="tower", model="rotorez", port="/dev/ttyUSB0", **kw)


def test_settings_defaults_keep_rotctld_off_and_on_loopback() -> None:
    r = rotator_settings()
    assert (r.rotctld_port, r.rotctld_bind, r.park_az_deg, r.park_el_deg) == (
        None,
        "127.0.0.1",
        None,
        None,
    )
    assert rotator_settings(rotctld_port=4533, park_az_deg=180).rotctld_port == 4533


@pytest.mark.parametrize(
    "kw",
    [
        {"rotctld_port": 0},
        {"rotctld_port": 65536},
        {"park_az_deg": 361},
        {"park_az_deg": 5, "az_min_deg": 10},
        {"park_az_deg": 5, "park_el_deg": 0},  # an azimuth-only model has no elevation to park
        {"park_el_deg": 0},
    ],
)
def test_settings_reject_bad_rotctld_values(kw: dict[str, Any]) -> None:
    with pytest.raises(ValidationError):
        rotator_settings(**kw)


def test_two_rotators_cannot_share_a_rotctld_port() -> None:
    rotators = [
        {"id": "a", "model": "rotorez", "port": "/dev/ttyUSB0", "rotctld_port": 4533},
        {"id": "b", "model": "rotorcard", "port": "/dev/ttyUSB1", "rotctld_port": 4533},
    ]
    with pytest.raises(
        ValidationError, match=r"rotators\[1\].rotctld_port 4533 is also rotators\[0\]"
    ):
        Settings(rotators=rotators)


def test_p_answers_past_360_only_to_a_client_that_named_the_side(station: StationFactory) -> None:
    """A client that sent P 40 reads 40 even where the bridge took the rotor on to raw 400 (the
    shorter way from 300); one that sent P 400 reads 400 (the range \\dump_state gives)."""
    st = station("md01", start_az_deg=300)
    compass, overlap = st.connect(), st.connect()
    compass.ask(b"P 40 0\n", b"RPRT 0\n")
    wait_until(lambda: abs(st.emu.state().az_deg - 400) < 1 and not st.emu.state().is_moving, 20)
    wait_until(lambda: st.rotator.status.state is MotionState.IDLE, 10, "idle")
    assert compass.single_recv(b"p\n") == b"40.00\n0.00\n"
    overlap.ask(b"P 400 0\n", b"RPRT 0\n")
    assert overlap.single_recv(b"p\n") == b"400.00\n0.00\n"
    assert compass.single_recv(b"p\n") == b"40.00\n0.00\n"  # each client in its own terms


def test_dump_state_never_says_south_zero(station: StationFactory) -> None:
    c = station("rotorcard", az_offset_deg=180).connect()
    reply = c.single_recv(b"\\dump_state\n")
    assert b"min_az=0.000000\nmax_az=360.000000\n" in reply and b"south_zero=0\n" in reply


@pytest.mark.hamlib
@pytest.mark.parametrize(("offset", "lo", "hi"), [(180, 0, 630), (30, 0, 480), (-135, -135, 360)])
def test_every_true_bearing_is_in_dump_states_range_on_a_rotor_past_360_with_an_offset(
    station: StationFactory, rotctl_path: str, offset: float, lo: float, hi: float
) -> None:
    """pointing.py rules 1 and 2: a 450-degree GS-232 with an offset takes every true bearing
    in 0..360 and, naming the side, its limits shifted by the offset. ``\\dump_state`` gave
    the shifted limits alone (180..630), and Hamlib's ``rotctl -m 2`` refused ``P 90 0``
    itself, "Invalid parameter", before it reached the bridge."""
    st = station("gs232b-450", start_az_deg=200, az_offset_deg=offset)
    reply = st.connect().single_recv(b"\\dump_state\n")
    assert f"min_az={lo:f}\nmax_az={hi:f}\n".encode() in reply
    bearing = 340 if offset == -135 else 10  # not in the shifted limits alone
    done = run_rotctl(rotctl_path, 2, st.server.port, "P", str(bearing), "0")
    assert done.returncode == 0, done
    raw = (bearing - offset) % 360
    st.emu.wait_for(lambda s: s.target_az_deg == raw)


def test_dump_states_range_on_limits_narrowed_under_a_turn_with_an_offset_is_theirs_alone(
    station: StationFactory,
) -> None:
    """pointing.py ``target_range``: 0..360 and the overlap is the range only where every
    bearing has a raw value inside the limits; a 450-degree GS-232 narrowed to 0..300 with
    offset 30 said 0..360 since f29e7dcc, though the bridge refuses 330..360 and 0..30 (Hamlib's
    client and Home Assistant's number offered them), where it had said 30..330."""
    st = station("gs232b-450", start_az_deg=200, az_offset_deg=30, az_min_deg=0, az_max_deg=300)
    reply = st.connect().single_recv(b"\\dump_state\n")
    assert b"min_az=30.000000\nmax_az=330.000000\n" in reply
    assert st.connect().single_recv(b"P 345 0\n") != b"RPRT 0\n"


# -- hostile neighbours (issue 14, item 1): HTTP is not rotctld ----------------------------------
BROWSER_GET = (
    b"GET / HTTP/1.1\r\nHost: 127.0.0.1:4533\r\nUser-Agent: Mozilla/5.0 (X11; Linux x86_64) "
    b"AppleWebKit/537.36 (KHTML, like Gecko) Chrome/120.0 Safari/537.36\r\nAccept: */*\r\n\r\n"
)
FORM_POST = (  # what curl --data-binary sends: the body would be read as a set_pos
    b"POST / HTTP/1.1\r\nHost: 127.0.0.1\r\nUser-Agent: curl/7.88.1\r\nAccept: */*\r\n"
    b"Content-Type: text/plain\r\nContent-Length: 9\r\n\r\n\nP 200 0\n"
)


@pytest.mark.parametrize(
    "request_",
    [
        BROWSER_GET,
        FORM_POST,
        BROWSER_GET[:5],  # the request line sent in pieces: held until it is complete
        b"p\nHost: x\n\nK\n",  # a header line later on (a rotctld line is never "Name: ...")
    ],
)
def test_a_connection_speaking_http_is_closed_and_nothing_it_sent_runs(
    station: StationFactory, request_: bytes
) -> None:
    st = station("rotorcard", park_az_deg=30)
    c = st.connect()
    if request_ == BROWSER_GET[:5]:
        c.send(request_)
        request_ = BROWSER_GET[5:]
    c.send(request_)
    try:
        while c.sock.recv(4096):  # the bridge closes it (a query before the header was answered)
            pass
    except ConnectionResetError:  # closed with some of it unread: it reads a little at a time
        pass
    other = st.connect()  # the rotor went nowhere: nothing was parked, nothing set
    other.ask(b"S\n", b"RPRT 0\n")
    assert st.bearing_frames() == []


def test_gpredict_and_hamlib_lines_are_not_taken_for_http(station: StationFactory) -> None:
    c = station("rot2prog").connect()
    c.ask(b"P 180.00 45.00\n", b"RPRT 0\n")  # Gpredict
    c.ask(b"S\n", b"RPRT 0\n")
    c.ask(b"\\stop\n", b"RPRT 0\n")


def test_idle_clients_are_dropped_and_a_slot_frees_for_gpredict(station: StationFactory) -> None:
    """Issue 14, item 5: 16 idle (or one-byte-a-second) connections held every slot for ever."""
    st = station("rotorcard")
    small = RotctldServer(st.rotator, 0, max_clients=2, idle_timeout_s=0.5, useful_within_s=1.0)
    small.start()
    try:
        silent = Client(small.port)  # sends nothing
        trickle = Client(small.port)  # sends a byte at a time, never a whole command
        trickle.send(b"\\")
        wait_until(lambda: small.client_count == 2, 5, "both connected")
        trickle.send(b"d")
        assert silent.at_eof()  # dropped after 0.5 s of silence
        assert trickle.at_eof()  # dropped: bytes, but no command within 1 s
        gpredict = Client(small.port)
        gpredict.ask(b"S\n", b"RPRT 0\n")
        for c in (silent, trickle, gpredict):
            c.close()
    finally:
        small.stop()


def test_a_quiet_client_keeps_its_slot_until_the_idle_timeout(station: StationFactory) -> None:
    """Cold review: the 60 s 'no command' limit also ran from the connect, so a client silent
    (or polling every 61-299 s) was dropped after 60 s whatever rotctld_idle_timeout_s said."""
    st = station("rotorcard")
    small = RotctldServer(st.rotator, 0, idle_timeout_s=3.0, useful_within_s=0.5)
    small.start()
    try:
        quiet = Client(small.port)
        quiet.sock.settimeout(1.5)  # a quiet period, not a deadline
        with pytest.raises(TimeoutError):  # no command for 1.5 s, past the 0.5 s: still there
            quiet.sock.recv(1)
        quiet.ask(b"S\n", b"RPRT 0\n")
        quiet.sock.settimeout(slow(10))
        assert quiet.at_eof()  # and dropped at the idle timeout
        quiet.close()
    finally:
        small.stop()


def test_clients_dropped_for_room_are_logged_once_with_a_count(
    station: StationFactory, caplog: pytest.LogCaptureFixture
) -> None:
    st = station("rotorcard")
    clock = FakeClock()
    small = RotctldServer(st.rotator, 0, max_clients=1, clock=clock)
    small.start()
    clients = []
    try:
        for _ in range(30):
            clock.t += 0.05  # within the address's 20 connections a second
            client = Client(small.port)
            client.ask(b"S\n", b"RPRT 0\n")  # in: the one before it dropped for room
            clients.append(client)
        assert all(c.at_eof() for c in clients[:-1])
        lines = [r.getMessage() for r in caplog.records if "to let one in" in r.getMessage()]
        assert len(lines) == 1, lines  # 29 dropped, one line
    finally:
        for client in clients:
            client.close()
        small.stop()


@pytest.mark.parametrize(
    ("data", "stop"),
    [
        (b"S\n", True),
        (b"p\nS\n", True),
        (b"\\stop\n", True),
        (b"+S\n", True),
        (b"P 200 S\n", True),  # rule 1: a stop where a number is awaited
        (b"p\n", False),
        (b"P 200 10\n", False),
        (b"\\get_pos\n", False),
        (b"q\nS\n", False),  # (the quit ends the connection first: an attack pass)
    ],
)
def test_a_stop_among_the_first_commands_is_told_for_the_accept_loop(
    data: bytes, stop: bool
) -> None:
    """interfaces/tcplines.py rule 5: a connection whose first commands hold a stop goes
    ahead of its address's budget."""
    assert holds_stop(data) is stop


def test_a_move_sent_after_a_stop_by_a_client_whose_handshake_was_answered_is_carried_out(
    station: StationFactory, monkeypatch: pytest.MonkeyPatch
) -> None:
    """tcplines.py rules 8 and 9 (a cold review): a connection waiting over its address's
    budget had its ``\\dump_state`` answered by the accept loop, and the bytes that question
    took were counted again as the first the client's thread read: its ``P 100 0``, sent after
    an operator's STOP elsewhere, was refused as sent before it."""
    monkeypatch.setattr(tcplines, "ACCEPTS_S", 1.0)  # one thread a second for an address
    st = station()
    first = st.connect()  # (the address's thread for this second)
    first.ask(b"p\n", b"123.00\n0.00\n")
    waiting = st.connect()  # over the budget: it waits, no thread
    answer = b"".join(
        out for out in RotctldSession(st.rotator).feed(b"\\dump_state\n") if isinstance(out, bytes)
    )
    waiting.ask(b"\\dump_state\n", answer)  # answered while it waits
    st.rotator.submit(Stop(Source.MQTT), "stop")  # an operator's STOP, elsewhere, now
    waiting.ask(b"P 100 0\n", b"RPRT 0\n")  # sent after it: carried out once let in


HALF_FLOOD = """
import collections, socket, sys, threading
port = int(sys.argv[1]); held = collections.deque(); lock = threading.Lock()
def flood():
    while True:
        try:
            s = socket.create_connection(("127.0.0.1", port), timeout=2)  # not a deadline
            s.sendall(b"P 1")  # half a command, never finished
        except OSError:
            continue
        with lock:
            held.append(s)
            old = held.popleft() if len(held) > 100 else None
        if old is not None:
            old.close()
for _ in range(4):
    threading.Thread(target=flood, daemon=True).start()
print("started", flush=True)
sys.stdin.read()
"""


def test_a_stop_on_a_new_connection_beside_a_half_command_flood_is_carried_out(
    station: StationFactory,
) -> None:
    """An attack pass (docs/performance.md, a stop on a new connection beside half-command
    connections): a program on the host holds 100 connections to the port, each with ``P 1``
    sent and no line end, its four threads opening new ones as fast as they connect. The
    operator's ``S`` on a new connection, as ``rotctl -m 2`` sends it, is answered ``RPRT 0``
    and the rotor stops on its way. How soon is the benchmark's to say (stop_beside_floods):
    here the kernel may drop its handshake once or twice, the first retry a second later."""
    st = station(start_az_deg=10)  # 290 degrees to go: over 7 s at 40 degrees a second
    c = st.connect()
    c.ask(b"P 300 0\n", b"RPRT 0\n")
    st.emu.wait_for(lambda s: s.is_moving, slow(10))
    flood = subprocess.Popen(
        [sys.executable, "-c", HALF_FLOOD, str(st.server.port)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
    )
    try:
        assert flood.stdout is not None and flood.stdout.readline() == b"started\n"
        wait_until(lambda: len(st.server.waiting) >= 32, slow(10), "the flood under way")
        with socket.create_connection(("127.0.0.1", st.server.port), timeout=slow(30)) as op:
            op.sendall(b"S\n")
            assert op.recv(64) == b"RPRT 0\n"
        st.emu.wait_for(lambda s: not s.is_moving, slow(10))
    finally:
        flood.kill()
        flood.wait()
    assert st.emu.state().az_deg < 290  # stopped on its way, not arrived
