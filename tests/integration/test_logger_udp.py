"""Contest and logging programs end to end (issue 18): PstRotator's UDP interface and N1MM
Logger+'s rotor messages on real UDP sockets, through one running bridge (the App in-process) with
a private mosquitto and two emulated controllers on real ptys: a Rotor-EZ (azimuth only) that
answers to PST, to N1MM as "Yagi" and reports its heading to N1MM, and an MD-01 (az/el) on PST.

The loggers' side is tests/support/udp_logger.py, written from the protocol fact sheet
(../shared/protocols/logger-udp.md), not from bridge/loggers. The issue asks for Hamlib 4.6's
``rotctl -m 3`` (its PstRotator backend) where the test machine has it. Debian 12's Hamlib is
4.5.4: ``rotctl -l | grep -i pst`` prints nothing there (the backend came in 4.6, model 1901 is
an iOptron), so that independent client is the fact sheet's one, sending what Hamlib 4.6.5 was
seen to send (``<PST><AZIMUTH>120.000000.2</AZIMUTH></PST>``, its separate ``AZ?``/``EL?``).

What is asserted is what a user sees: the frames the controller received (the emulators' logs:
``AP1xxx<CR>`` is the Rotor-EZ's "store and go", ``;`` its stop; an MD-01 logs "set" and
"stop"), where the rotor really is (their ground truth), the replies at port + 1, the position
reports, and what the bridge publishes (R/status, R/error). One App serves every test of a worker
(it takes seconds to start); each test first waits until its rotor is at rest and the bridge says
idle. Nothing sleeps to synchronise: absence is proven by order (a datagram the bridge answers or
acts on, sent after the ones that must do nothing, on the same socket) and a short bounded
receive after the answer.
"""

from __future__ import annotations

import contextlib
import json
import re
import socket
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from bridge.app import App
from bridge.emulators.base import LoggedFrame, RotatorState
from bridge.emulators.pty import EmulatedPort
from bridge.settings import ConfigError, Settings
from bridge.settings.pointing import StationSettings
from tests.integration.test_pointing_bridge import angle_between, locator_centre, reference_path
from tests.support import Probe, wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.ports import free_udp_port
from tests.support.rig import Rig
from tests.support.udp_logger import (
    N1MM_STOPS,
    N1mmListener,
    N1mmSender,
    PstClient,
    hamlib,
    minos_reply,
    n1mm_turn,
    pst,
    qlog,
    reserve_pst_ports,
    tag,
    udp_socket,
)

EZ, SAT = "ez", "sat"
YAGI = "Yagi"  # the Rotor-EZ's "Rotor Description" in N1MM's Antennas tab
STATION = "JO62qm"
PARK_AZ = 20
# quick rotors: the Rotor-EZ turns 90 deg/s with a 0.5 s brake (the bridge is told the same), the
# MD-01 90 / 45 deg/s; a long turn still takes seconds, time enough to stop it half-way
EZ_EMU = {"speed_deg_s": 90.0, "brake_delay_s": 0.5, "jitter_deg": 0, "start_az_deg": 10}
EZ_BRIDGE = {"brake_delay_s": 0.5, "settle_s": 0.3, "park_az_deg": PARK_AZ}
SAT_EMU = {"az_speed_deg_s": 90.0, "el_speed_deg_s": 45.0, "start_az_deg": 100, "start_el_deg": 10}
SAT_BRIDGE = {"az_speed_deg_s": 90.0, "el_speed_deg_s": 45.0}
AFTER_ANSWER_S = 0.1  # a bounded receive after an answer: anything wrong was sent before it
# N1MM position reports (fact sheet 2): at least every 15 s when idle
IDLE_REPORT_S = 15.0
MOVING_REPORT_S = 2.0  # fact sheet 2: every 1-2 s while moving


@dataclass
class Bench:
    rig: Rig
    pst: dict[str, PstClient]  # by rotator id
    n1mm: N1mmSender
    reports: N1mmListener

    @property
    def probe(self) -> Probe:
        return self.rig.probe

    @property
    def app(self) -> App:
        assert self.rig.app is not None
        return self.rig.app

    def emu(self, rid: str) -> EmulatedPort[Any]:
        return self.rig.emus[rid]

    def status(self, rid: str) -> dict[str, Any]:
        last = self.probe.last(self.rig.topic(rid, "status"))
        assert last is not None, f"{rid}: no status yet"
        doc: dict[str, Any] = json.loads(last.payload)
        return doc

    def at_rest(self, rid: str) -> RotatorState:
        """The rotor still, out of its brake window, and the bridge saying idle: ready for a
        command whose frames are all its own."""
        state = self.emu(rid).wait_for(lambda s: not s.is_moving and not s.in_brake_delay, 15)
        wait_until(lambda: self.status(rid)["state"] == "idle", 10, f"{rid} idle")
        return state

    def motion(self, rid: str, since: float) -> list[LoggedFrame]:
        return [f for f in self.emu(rid).log() if f.time_s >= since and _moves(rid, f)]

    def settled_at(
        self,
        rid: str,
        az_deg: float,
        el_deg: float | None = None,
        after: float = 0.0,
        tol: float = 0.3,
    ) -> dict[str, Any]:
        """Wait until the rotor stands at ``az_deg`` (and ``el_deg``) within ``tol`` and the
        bridge publishes it idle there; that status."""

        def there(s: RotatorState) -> bool:
            el_ok = el_deg is None or (s.el_deg is not None and abs(s.el_deg - el_deg) <= tol)
            return not s.is_moving and angle_between(s.az_deg, az_deg) <= tol and el_ok

        self.emu(rid).wait_for(there, 15)

        def idle_there(m: Any) -> bool:
            doc = json.loads(m.payload)
            return doc["state"] == "idle" and angle_between(doc["bearing"], az_deg) <= 1

        topic = self.rig.topic(rid, "status")
        return dict(json.loads(self.probe.wait_for(topic, idle_there, 10, after).payload))


def _moves(rid: str, f: LoggedFrame) -> bool:
    """A frame that moves or stops the rotor (not a poll)."""
    if rid == EZ:
        return f.data.startswith((b"AP", b"AM")) or f.data == b";"
    return f.outcome.startswith(("set", "stop", "move"))


def far_from(az_deg: float) -> int:
    """A target most of the Rotor-EZ's 0..360 away (it has no overlap: no short way round)."""
    return 350 if az_deg < 180 else 10


@pytest.fixture(scope="module")
def bench(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Bench]:
    tmp: Path = tmp_path_factory.mktemp("loggers")
    with contextlib.ExitStack() as stack:
        broker = Mosquitto(tmp / "broker").start()
        stack.callback(broker.stop)
        probe = Probe(broker.port, "rotor/#")
        stack.callback(probe.close)
        rig = Rig(tmp, broker, probe)
        stack.callback(rig.close)
        ez_port, ez_replies = reserve_pst_ports()
        sat_port, sat_replies = reserve_pst_ports()
        clients = {EZ: PstClient(ez_port, replies=ez_replies)}
        stack.callback(clients[EZ].close)
        clients[SAT] = PstClient(sat_port, replies=sat_replies)
        stack.callback(clients[SAT].close)
        reports = N1mmListener()
        stack.callback(reports.close)
        n1mm_port = free_udp_port()
        sender = N1mmSender(n1mm_port)
        stack.callback(sender.close)
        rig.add(
            EZ,
            "rotorez",
            emu=EZ_EMU,
            pst_udp_port=ez_port,
            n1mm_rotor_name=YAGI,
            n1mm_udp_port=n1mm_port,
            n1mm_report_to=reports.address,
            **EZ_BRIDGE,
        )
        rig.add(SAT, "md01", emu=SAT_EMU, pst_udp_port=sat_port, **SAT_BRIDGE)
        station = StationSettings(locator=STATION)
        rig.app = App(rig.settings.model_copy(update={"station": station}))
        rig.app.start()
        rig.ready(EZ, 15)
        rig.ready(SAT, 15)
        yield Bench(rig, clients, sender, reports)


# -- PstRotator: turn, ask, stop, park, locator ---------------------------------------------------
def test_a_pst_azimuth_turns_the_rotor_as_the_manual_and_hamlib_46_write_it(bench: Bench) -> None:
    client = bench.pst[EZ]
    # the manual's integer, Hamlib 4.6's "%f.2" (its range is -180..450: folded into 0..360),
    # QLog's one decimal
    for value, deg in (("85", 85), (hamlib(120), 120), (hamlib(-90), 270), (qlog(200.4), 200)):
        bench.at_rest(EZ)
        t = time.monotonic()
        client.command(tag("AZIMUTH", value))
        status = bench.settled_at(EZ, deg, after=t)
        assert [f.data for f in bench.motion(EZ, t)] == [f"AP1{deg:03d}\r".encode()], value
        assert status["last_command_source"] == "pst"
        assert bench.emu(EZ).state().az_deg == deg


def test_az_query_is_answered_to_the_sender_at_port_plus_one_in_integer_degrees_with_a_cr(
    bench: Bench,
) -> None:
    client = bench.pst[EZ]
    rest = bench.at_rest(EZ)
    client.drain()
    client.send(pst("AZ?"))
    data = client.reply()
    assert data == f"AZ:{round(rest.az_deg)}\r".encode()  # exactly: no padding, one CR
    assert minos_reply(data) == ("AZ", round(rest.az_deg))
    assert client.peers[-1][0] == "127.0.0.1"
    assert client.stray(AFTER_ANSWER_S) is None, "a reply went to the ephemeral source port"
    # an azimuth-only rotor keeps quiet on EL? (clients keep their last elevation)
    client.send(pst("EL?"))
    client.send(pst("AZ?"))
    assert client.reply() == data, "EL? was answered by an azimuth-only rotator"
    assert client.reply(AFTER_ANSWER_S) is None


def test_an_az_el_rotator_takes_a_combined_datagram_and_answers_az_and_el(
    bench: Bench,
) -> None:
    client = bench.pst[SAT]
    bench.at_rest(SAT)
    t = time.monotonic()
    # QLog / horus-gui: TRACK (PstRotator's own tracking, ignored), azimuth and elevation at once
    client.command(tag("TRACK", 0), tag("AZIMUTH", "123.4"), tag("ELEVATION", "45.6"))
    # within one of the MD-01's half-degree pulses (the bridge truncates, as Hamlib does)
    status = bench.settled_at(SAT, 123.4, 45.6, after=t, tol=0.5)
    assert [f.outcome for f in bench.motion(SAT, t)] == ["set"], "one move for both axes"
    assert status["last_command_source"] == "pst"
    truth = bench.emu(SAT).state()
    assert truth.el_deg is not None
    client.drain()
    for query, deg in (("AZ", truth.az_deg), ("EL", truth.el_deg)):  # Hamlib asks one by one
        name, value = minos_reply(client.ask(query))
        assert name == query and abs(value - deg) <= 0.5, (query, value, deg)
    assert client.reply(AFTER_ANSWER_S) is None


def test_pst_stop_stops_a_turning_rotor_and_park_goes_to_the_park_position(bench: Bench) -> None:
    client, emu = bench.pst[EZ], bench.emu(EZ)
    start = bench.at_rest(EZ).az_deg
    if angle_between(start, PARK_AZ) < 60:  # the park must be a real move below
        t = time.monotonic()
        client.command(tag("AZIMUTH", 180))
        bench.settled_at(EZ, 180, after=t)
        start = bench.at_rest(EZ).az_deg
    target = far_from(start)
    t = time.monotonic()
    client.command(tag("AZIMUTH", target))
    emu.wait_for(lambda s: s.is_moving and angle_between(s.az_deg, start) > 20, 5)
    t_stop = time.monotonic()
    client.command(tag("STOP", 1))  # Minos, KST4Contest
    stopped = emu.wait_for(lambda s: not s.is_moving, 3)
    assert [f.data for f in bench.motion(EZ, t)] == [f"AP1{target:03d}\r".encode(), b";"]
    assert [f.data for f in bench.motion(EZ, t_stop)] == [b";"], "the stop was not what it sent"
    assert angle_between(stopped.az_deg, target) > 30, "it was not stopped, it arrived"

    bench.at_rest(EZ)
    t = time.monotonic()
    client.command(tag("PARK", 1))  # Hamlib's `K`, KST4Contest
    status = bench.settled_at(EZ, PARK_AZ, after=t)
    assert [f.data for f in bench.motion(EZ, t)] == [f"AP1{PARK_AZ:03d}\r".encode()]
    assert status["parked"] is True and status["last_command_source"] == "pst"


def test_a_qra_locator_turns_to_its_great_circle_bearing_from_the_station(bench: Bench) -> None:
    want, _km = reference_path(locator_centre(STATION), locator_centre("PM95vq"))
    bench.at_rest(EZ)
    t = time.monotonic()
    bench.pst[EZ].command(tag("QRA", "PM95vq"))  # the manual's <QRA>: PstRotator computes it
    status = bench.settled_at(EZ, round(want), after=t)
    (frame,) = [f.data for f in bench.motion(EZ, t)]
    assert re.fullmatch(rb"AP1\d{3}\r", frame) and angle_between(int(frame[3:6]), want) <= 1
    assert status["target_info"]["locator"] == "PM95vq"
    assert status["last_command_source"] == "pst"


# -- N1MM: turn, the position reports, the three stops, other rotors ----------------------------
def test_n1mm_goazi_turns_the_rotor_and_its_heading_is_reported_in_the_documented_form(
    bench: Bench,
) -> None:
    start = bench.at_rest(EZ).az_deg
    target = 90 if angle_between(start, 90) > 20 else 270
    t = time.monotonic()
    bench.n1mm.send(n1mm_turn(YAGI, target))  # n1kdo's captured sample, one line
    status = bench.settled_at(EZ, target, after=t)
    assert [f.data for f in bench.motion(EZ, t)] == [f"AP1{target:03d}\r".encode()]
    assert status["last_command_source"] == "n1mm"
    # once when the move ends (then at least every 15 s), at the configured destination
    final = bench.reports.wait(lambda r: r.heading_deg == target, MOVING_REPORT_S + 1, "at rest")
    assert final.raw == f"{YAGI} @ {target * 10}".encode()
    assert all(r.name == YAGI for r in bench.reports.seen)


SELF_CLOSED_STOP = "rotor beside <stop/>"
STOPS: dict[str, Callable[[str], bytes]] = {
    **N1MM_STOPS,
    # the third form as an empty element: the fact sheet says "treat any <stop element as stop"
    SELF_CLOSED_STOP: lambda rotor: f"<N1MMRotor>{tag('rotor', rotor)}<stop/></N1MMRotor>".encode(),
}


@pytest.mark.parametrize("form", list(STOPS))
def test_each_n1mm_stop_form_stops_a_turning_rotor(bench: Bench, form: str) -> None:
    emu = bench.emu(EZ)
    start = bench.at_rest(EZ).az_deg
    target = far_from(start)
    t = time.monotonic()
    bench.n1mm.send(n1mm_turn(YAGI, target, layout="readme"))  # netrotor's layout, CR LF
    emu.wait_for(lambda s: s.is_moving and angle_between(s.az_deg, start) > 20, 5)
    t_stop = time.monotonic()
    bench.n1mm.send(STOPS[form](YAGI))
    stopped = emu.wait_for(lambda s: not s.is_moving, 3)
    assert [f.data for f in bench.motion(EZ, t)] == [f"AP1{target:03d}\r".encode(), b";"], form
    assert [f.data for f in bench.motion(EZ, t_stop)] == [b";"], "the stop was not what it sent"
    assert angle_between(stopped.az_deg, target) > 30, "it was not stopped, it arrived"


def test_an_n1mm_datagram_for_another_rotor_is_ignored(bench: Bench) -> None:
    start = bench.at_rest(EZ).az_deg
    ours = 90 if angle_between(start, 90) > 20 else 270
    t = time.monotonic()
    bench.n1mm.send(n1mm_turn("Tribander", 300))  # another antenna's rotor, same port
    bench.n1mm.send(n1mm_turn("yagi", 300))  # the name must match exactly
    bench.n1mm.send(n1mm_turn(YAGI, ours))  # handled after them: it shows they did nothing
    bench.settled_at(EZ, ours, after=t)
    assert [f.data for f in bench.motion(EZ, t)] == [f"AP1{ours:03d}\r".encode()]


# -- the lock, malformed datagrams -------------------------------------------------------------
def test_the_lock_refuses_commands_from_both_endpoints_and_r_error_names_the_source(
    bench: Bench,
) -> None:
    client, probe = bench.pst[EZ], bench.probe
    start = bench.at_rest(EZ).az_deg
    errors = bench.rig.topic(EZ, "error")
    lock_state = bench.rig.topic(EZ, "lock/state")
    t_lock = time.monotonic()
    probe.publish(bench.rig.topic(EZ, "lock"), "ON")
    try:
        probe.wait_value(lock_state, "ON", after=t_lock)
        t = time.monotonic()
        client.command(tag("AZIMUTH", 200))
        client.command(tag("PARK", 1))
        client.command(tag("QRA", "PM95vq"))
        bench.n1mm.send(n1mm_turn(YAGI, 200))
        refused: dict[str, list[dict[str, Any]]] = {"pst": [], "n1mm": []}

        def seen_all() -> bool:
            docs = [json.loads(m.payload) for m in probe.on(errors) if m.t >= t]
            for source in refused:
                refused[source] = [d for d in docs if d.get("command", "").startswith(source)]
            return len(refused["pst"]) == 3 and len(refused["n1mm"]) == 1

        wait_until(seen_all, 10, "three pst and one n1mm refusals on R/error")
        for doc in refused["pst"] + refused["n1mm"]:
            assert doc["kind"] == "refused" and "locked" in doc["message"], doc
        assert "<AZIMUTH>200</AZIMUTH>" in refused["pst"][0]["command"]
        assert "<goazi>200.0</goazi>" in refused["n1mm"][0]["command"]
        client.drain()
        assert client.ask("AZ") == f"AZ:{round(start)}\r".encode()  # reading is still allowed
        # no target went out; the lock's own stop (;) may reach the line after its state was
        # published, on a loaded machine
        moved = [f for f in bench.motion(EZ, t) if f.data != b";"]
        assert moved == [] and not bench.emu(EZ).state().is_moving
    finally:
        t_unlock = time.monotonic()
        probe.publish(bench.rig.topic(EZ, "lock"), "OFF")
        probe.wait_value(lock_state, "OFF", after=t_unlock)


PST_JUNK = [
    b"",
    b"\x00\xff\x10junk",
    b"AZ?",  # not wrapped
    b"<PST>AZ?",  # never closed
    b"<PST>AZ?</PST>trailing",
    b"<PST>AZ?</PST>\xff",
    b"<PST>AZ\xc3\x9f?</PST>",  # not ASCII
    b"<PST>" + b" " * 5000 + b"AZ?</PST>",  # oversized
    b"<PST><AZIMUTH>NaN</AZIMUTH>AZ?</PST>",  # a query beside a value that is no number
    b"<PST><AZIMUTH>inf</AZIMUTH></PST>",
    b"<PST><AZIMUTH>1e999</AZIMUTH></PST>",
    b"<PST><AZIMUTH></AZIMUTH></PST>",
    b"<PST><AZIMUTH> </AZIMUTH></PST>",
    b"<PST><AZIMUTH>12x</AZIMUTH></PST>",
    b"<PST><AZIMUTH>0x50</AZIMUTH></PST>",
    "<PST><AZIMUTH>９０</AZIMUTH></PST>".encode(),  # fullwidth digits
    b"<PST><AZIMUTH>90</AZIMUTH>",  # never closed
    b"<PST><AZIMUTH>90</PST>",  # a tag left open
    b"<PST><AZIMUTH>90</AZIMUTH></PST>\x00",
]
N1MM_JUNK = [
    b"",
    b"\x00\xff\x10junk",
    n1mm_turn(YAGI, 0).replace(b"0.0</goazi>", b"nan</goazi>"),
    n1mm_turn(YAGI, 0).replace(b"0.0</goazi>", b"</goazi>"),
    n1mm_turn(YAGI, 0).replace(b"0.0</goazi>", b"66.0x</goazi>"),
    n1mm_turn(YAGI, 0).replace(b"0.0</goazi>", b"400.0</goazi>"),  # N1MM takes 0..360
    n1mm_turn(YAGI, 0).replace(b"0.0</goazi>", b"-5.0</goazi>"),
    n1mm_turn(YAGI, 0).replace(b"0.0</goazi>", "６６.0</goazi>".encode()),
    n1mm_turn(YAGI, 66).replace(b"</N1MMRotor>", b""),  # never closed
    n1mm_turn(YAGI, 66) + b" " * 5000,  # oversized
    b"<N1MMRotor><rotor>Yagi</rotor></N1MMRotor>",  # neither goazi nor stop
    b"<N1MMRotor><goazi>66.0</goazi></N1MMRotor>",  # no rotor
]


def test_malformed_datagrams_move_nothing_get_no_reply_and_are_counted(bench: Bench) -> None:
    client, loggers = bench.pst[EZ], bench.app.loggers
    start = bench.at_rest(EZ).az_deg
    before = {k: c.malformed for k, c in loggers.counts.items()}
    client.drain()
    t = time.monotonic()
    for datagram in PST_JUNK:
        client.send(datagram)
    for datagram in N1MM_JUNK:
        bench.n1mm.send(datagram)
    client.send(pst("AZ?"))  # answered after every junk datagram on that port was handled
    assert client.reply() == f"AZ:{round(start)}\r".encode(), "junk was answered"
    assert client.reply(AFTER_ANSWER_S) is None, "junk was answered"
    assert client.stray() is None
    ours = 90 if angle_between(start, 90) > 20 else 270
    bench.n1mm.send(n1mm_turn(YAGI, ours))  # acted on after every N1MM junk datagram
    bench.settled_at(EZ, ours, after=t)
    assert [f.data for f in bench.motion(EZ, t)] == [f"AP1{ours:03d}\r".encode()]
    assert bench.motion(SAT, t) == []
    assert loggers.counts["pst"].malformed - before["pst"] == len(PST_JUNK)
    assert loggers.counts["n1mm"].malformed - before["n1mm"] == len(N1MM_JUNK)


# -- start-up -----------------------------------------------------------------------------------
@pytest.mark.parametrize("held", ["pst", "n1mm"])
def test_a_logger_port_another_program_holds_is_a_start_up_error_naming_it(
    tmp_path: Path, held: str
) -> None:
    """The one line ``rotor-bridge run`` prints (cli.py) is this ConfigError's text; nothing is
    kept: the other port is free again."""
    holder = udp_socket()  # the test is the other program (a PstRotator, a second bridge)
    taken = holder.getsockname()[1]
    other = free_udp_port()
    ports = {"pst": taken, "n1mm": other} if held == "pst" else {"pst": other, "n1mm": taken}
    settings = Settings(
        mqtt={"host": "127.0.0.1", "port": free_udp_port()},  # never reached
        rotators=[
            {
                "id": "tower",
                "model": "rotorez",
                "port": str(tmp_path / "tty"),
                "pst_udp_port": ports["pst"],
                "n1mm_rotor_name": YAGI,
                "n1mm_udp_port": ports["n1mm"],
            }
        ],
        state_file=tmp_path / "state.json",
    )
    app = App(settings)
    try:
        with pytest.raises(ConfigError) as caught:
            app.start()
    finally:
        holder.close()
        app.stop()
    said = str(caught.value)
    assert f"127.0.0.1:{taken}" in said and "Address already in use" in said, said
    who = "rotator 'tower'" if held == "pst" else YAGI
    assert who in said, said
    assert "\n" not in said
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as again:
        again.bind(("127.0.0.1", other))  # the endpoint that could listen let go of its port


# -- found by these tests: an azimuth and an elevation datagram back to back; reports ---------
def test_hamlibs_azimuth_and_elevation_datagrams_sent_back_to_back_both_apply(
    bench: Bench,
) -> None:
    """Hamlib 4.6's ``P 200 30`` (rot_pstrotator.c): two datagrams, azimuth then elevation,
    each ``"%f.2"``, one right after the other."""
    client = bench.pst[SAT]
    start = bench.at_rest(SAT)
    az = 200 if angle_between(start.az_deg, 200) > 20 else 300
    el = 30 if start.el_deg is None or abs(start.el_deg - 30) > 10 else 60
    t = time.monotonic()
    client.command(tag("AZIMUTH", hamlib(az)))
    client.command(tag("ELEVATION", hamlib(el)))
    bench.settled_at(SAT, az, el, after=t)
    client.drain()
    assert client.ask("AZ") == f"AZ:{az}\r".encode()
    assert client.ask("EL") == f"EL:{el}\r".encode()


def test_n1mm_position_reports_come_while_the_rotor_turns_and_when_it_stops(
    bench: Bench,
) -> None:
    start = bench.at_rest(EZ).az_deg
    target = far_from(start)
    bench.reports.drain()
    t = time.monotonic()
    bench.n1mm.send(n1mm_turn(YAGI, target))
    lo, hi = sorted((start, target))

    def under_way(r: Any) -> bool:  # a heading the rotor only has while it turns
        return lo + 10 < r.heading_deg < hi - 10

    travel_s = abs(target - start) / EZ_EMU["speed_deg_s"]
    bench.reports.wait(under_way, travel_s + MOVING_REPORT_S, "while it turns")
    bench.settled_at(EZ, target, after=t)
    final = bench.reports.wait(lambda r: r.heading_deg == target, 3, f"at {target}")
    assert final.raw == f"{YAGI} @ {target * 10}".encode()
