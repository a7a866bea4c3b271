"""Attack pass 26: the station's link to its broker goes dead mid-turn (a home router's reboot, a
mobile uplink), without a word to the broker: no FIN, so no last will until its keepalive runs out
(1.5 keepalives), and the station's bridge goes on turning the rotor to its target. The remote
still hears the station: its last heartbeat is under SILENT_S (6 s) old. The operator sees the
bearing stop changing and sends STOP: the remote takes the station for heard, so the STOP is no
halt "the station's bridge may not hear" (remote/rotator.py rule 3, ``until_heard``); the broker
acknowledges it (rotctld ``RPRT 0``), hands it to the dead connection, and it is gone. The
station's bridge, back on its broker with a clean session, never gets it, and nothing sends it
again: the rotor turns on to the end of its turn, 290 degrees, after a STOP answered ``RPRT 0``.
docs/remote.md: "A stop moves nothing and is never lost".

The route heals some 1.5 s later, halfway through the turn: a STOP sent again once the
station's bridge is heard again would still stop the rotor there. Real parts: mosquitto, the
station's bridge on an emulated Rotor-EZ, the remote in this process with a rotctld endpoint;
the station's bridge reaches the broker through a TCP link this test cuts (what either side
sends is lost, neither side is told) and heals (the dead connections closed, as both sides'
keepalives end them; the bridge connects again)."""

from __future__ import annotations

import contextlib
import json
import socket
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest

from bridge.core.errors import Refused
from bridge.core.model import Lock, Source
from bridge.interfaces.mqtt.heartbeat import beat_payload
from bridge.interfaces.mqtt.remote import RemoteLink, Standing
from bridge.remote.run import Remote, standing
from bridge.remote.settings import RemoteSettings
from bridge.settings.mqtt import MqttSettings
from tests.support import Probe, wait_until
from tests.support.mosquitto import Mosquitto, free_port
from tests.support.mqtt import Message
from tests.support.remote import ask, remote_published
from tests.support.rig import Rig
from tests.support.waiting import slow

START_AZ, TARGET_AZ = 10.0, 300.0
STATUS = "rotor/status"  # the one rotator's status, for the tests of the link alone


def turning_status(turn: int, taken: int | None = None, run: str = "run-1") -> bytes:
    """The station's ``R/status`` as its bridge publishes it, cut to what the link reads of
    it (interfaces/mqtt/remote.py rule 10): the rotor turning to a target taken at place
    ``turn``, every command up to ``taken`` (default: that one) shown, in the run ``run``."""
    order = {"run": run, "taken": turn if taken is None else taken, "turn": turn, "lock": 0}
    doc = {"target": 100.0, "state": "moving", "moving": True, "locked": False, "order": order}
    return json.dumps(doc).encode()


def rotor_standing(topic: str, payload: bytes) -> Standing | None:
    """What the remote reads of ``rotor/status`` on its halts (remote/run.py's ``_proof``)."""
    return standing("rotor/stop", "rotor/lock", payload) if topic == STATUS else None


def halting_link(
    port: int, client_id: str, on_message: Callable[[str, bytes, bool], None]
) -> RemoteLink:
    """The remote's link (not started) to a broker on ``port``, for the one rotator whose
    status is ``STATUS``: hearing the station's heartbeat, bridge state and status, holding
    its ``rotor/stop`` (interfaces/mqtt/remote.py rule 10)."""
    return RemoteLink(
        MqttSettings(host="127.0.0.1", port=port),
        client_id,
        ["rotor/bridge/heartbeat", "rotor/bridge/state", STATUS],
        on_message,
        last_word=lambda topic, payload: topic == "rotor/stop",
        heartbeat="rotor/bridge/heartbeat",
        station_state="rotor/bridge/state",
        proof=rotor_standing,
    )


def station_word(probe: Probe, heard: list[str]) -> Callable[[str, bytes], None]:
    """The station's bridge's word: ``topic`` and ``payload`` published as it would (QoS 0),
    returned once the link heard something more (``heard`` the topics it heard)."""

    def station(topic: str, payload: bytes) -> None:
        n = len(heard)
        probe.publish(topic, payload, qos=0)
        wait_until(lambda: len(heard) > n, slow(10), f"{topic} heard")

    return station


def heard_turning(probe: Probe, heard: list[tuple[str, bool]]) -> int:
    """The station's bridge's heartbeat and its status turning to a target (place 1),
    published as it would: returned once the link heard the status live; what ``heard`` held
    before them."""
    n = len(heard)
    probe.publish("rotor/bridge/heartbeat", beat_payload(time.time()).encode(), qos=0)
    probe.publish(STATUS, turning_status(1), qos=0)  # turning to a target, place 1
    wait_until(lambda: (STATUS, False) in heard[n:], slow(10), "the station heard turning")
    return n


def still_turning_then_marker(
    broker: Mosquitto, probe: Probe, link: RemoteLink, heard: list[tuple[str, bool]], log_from: int
) -> None:
    """The station still turning to that target and its heartbeat, heard live; then the link's
    marker (``rotor/track``) behind anything sent again, returned once the broker logged it."""
    n = len(heard)
    probe.publish(STATUS, turning_status(1), qos=0)  # still turning to that target
    probe.publish("rotor/bridge/heartbeat", beat_payload(time.time()).encode(), qos=0)
    wait_until(lambda: ("rotor/bridge/heartbeat", False) in heard[n:], slow(10), "its beat heard")
    link.send("rotor/track", "off", "DL1ABC", 5)  # a marker behind anything sent again
    wait_until(lambda: b"track" in remote_published(broker, log_from), slow(10), "marker")


class CuttableLink:
    """A TCP link on a loopback port to ``target``. ``cut``: from then on every byte either side
    sends is read and dropped, and a new connection is taken and dropped likewise, while no side
    is told (a dead route). ``heal``: the connections made before are closed, as keepalives end
    them; new ones are forwarded."""

    def __init__(self, target: int) -> None:
        self.target = target
        self._cut = threading.Event()
        self._lock = threading.Lock()
        self._socks: list[socket.socket] = []
        self._server = socket.create_server(("127.0.0.1", 0))
        self.port = int(self._server.getsockname()[1])
        threading.Thread(target=self._accept, daemon=True).start()

    def cut(self) -> None:
        self._cut.set()

    def heal(self) -> None:
        with self._lock:  # (a connection accepted meanwhile is cut or forwarded, never both)
            dead, self._socks = self._socks, []
            for s in dead:  # closed before bytes pass again: what a pipe read from an old
                with contextlib.suppress(OSError):  # connection while cut, and sends after,
                    s.shutdown(socket.SHUT_RDWR)  # goes nowhere (under load the remote's
                s.close()  # lock ON, cut, reached the station at the heal: review 86's flake)
            self._cut.clear()

    def _accept(self) -> None:
        while True:
            try:
                conn, _ = self._server.accept()
            except OSError:
                return
            with self._lock:
                self._socks.append(conn)
                if self._cut.is_set():  # a dead route: taken, never answered
                    threading.Thread(target=self._pipe, args=(conn, None), daemon=True).start()
                    continue
                upstream = socket.create_connection(("127.0.0.1", self.target))
                self._socks.append(upstream)
            for a, b in ((conn, upstream), (upstream, conn)):
                threading.Thread(target=self._pipe, args=(a, b), daemon=True).start()

    def _pipe(self, src: socket.socket, dst: socket.socket | None) -> None:
        with contextlib.suppress(OSError):
            while data := src.recv(65536):
                if dst is not None and not self._cut.is_set():
                    dst.sendall(data)
        if dst is not None:
            with contextlib.suppress(OSError):
                dst.shutdown(socket.SHUT_WR)

    def close(self) -> None:
        self._server.close()
        self.heal()


@pytest.fixture
def route(rig: Rig) -> Iterator[CuttableLink]:
    link = CuttableLink(rig.broker.port)
    yield link
    link.close()


@pytest.fixture
def station(rig: Rig, route: CuttableLink) -> Rig:
    rig.mqtt_extra["port"] = route.port  # the station's bridge reaches its broker over the route
    rig.add("tower", emu={"start_az_deg": START_AZ, "jitter_deg": 0, "speed_deg_s": 20.0})
    rig.start()
    rig.ready("tower")
    return rig


def killable_station(rig: Rig, route: CuttableLink, **tower: Any) -> Iterator[Rig]:
    """A fixture's body: the station's bridge as a process of its own (so that a test can kill
    it and start it again), reaching its broker over ``route``, one rotator ``tower``."""
    rig.mqtt_extra["port"] = route.port  # the station's bridge reaches its broker over the route
    rig.add("tower", **tower)
    rig.start_process()
    rig.ready("tower")
    yield rig
    rig.stop()


def remote_on(station: Rig, port: int) -> Remote:
    """The operator's remote on the station's broker (not through the route), a rotctld
    endpoint on ``port`` for ``tower``; started."""
    remote = Remote(
        RemoteSettings(
            operator="DL1ABC",
            mqtt={"host": "127.0.0.1", "port": station.broker.port, "base_topic": "rotor"},
            endpoints=[{"rotator": "tower", "rotctld_port": port}],
        )
    )
    remote.start()
    return remote


def remote_heard(station: Rig, port: int) -> Remote:
    """``remote_on``, returned once its rotator has heard the station (stopped if it never
    does)."""
    remote = remote_on(station, port)
    try:
        rotator = remote.rotators[0]
        wait_until(lambda: rotator.away() is None, slow(30), "the station heard")
    except BaseException:
        remote.stop()
        raise
    return remote


def turning_then_cut(station: Rig, route: CuttableLink, port: int) -> float:
    """The rotor sent toward TARGET_AZ by the remote's rotctld, the route cut mid-turn: the
    bearing then."""
    emu = station.emus["tower"]
    assert ask(port, f"P {TARGET_AZ:g} 0\n".encode()) == b"RPRT 0\n"
    wait_until(lambda: emu.state().az_deg > START_AZ + 20, slow(10), "the rotor turning")
    route.cut()  # the station's route dies mid-turn; the remote still hears it
    return float(emu.state().az_deg)


def healed_later(station: Rig, route: CuttableLink, remote: Remote, cut_az: float) -> None:
    """The route dead while the rotor turns on some 30 degrees (1.5 s), then healed: the
    station's bridge connects again, a clean session, and is heard again; the rotor still."""
    emu = station.emus["tower"]
    wait_until(lambda: emu.state().az_deg > cut_az + 30, slow(10), "the rotor turning on")
    route.heal()
    rotator = remote.rotators[0]
    wait_until(lambda: rotator.away() is None, slow(30), "the station's bridge back")
    wait_until(lambda: not emu.state().is_moving, slow(30), "the rotor still")


def station_showed_stop(station: Rig, mark: int) -> float:
    """The station's word, after ``mark``, that it has the STOP (``tower``'s status: still, no
    target), then the rotor still: its bearing."""
    emu = station.emus["tower"]
    status = station.topic("tower", "status")
    station.probe.wait(
        lambda m: (
            m.topic == status and b'"target":null' in m.payload and b'"moving":false' in m.payload
        ),
        slow(10),
        "the station's status: still, no target",
        mark,
    )
    wait_until(lambda: not emu.state().is_moving, slow(10), "the rotor still")
    return float(emu.state().az_deg)


def home_assistant_turn(station: Rig, past_az: float) -> None:
    """Home Assistant's target TARGET_AZ published to ``tower``: returned once the station's
    status shows it turning and the rotor is past ``past_az``."""
    emu = station.emus["tower"]
    status = station.topic("tower", "status")
    mark = station.probe.mark()
    station.probe.publish(station.topic("tower", "target"), f"{TARGET_AZ:g}")  # HA's, later
    station.probe.wait(
        lambda m: m.topic == status and b'"moving":true' in m.payload,
        slow(10),
        "the station turning for Home Assistant",
        mark,
    )
    wait_until(lambda: emu.state().az_deg > past_az, slow(10), "the rotor turning")


def bridge_back_after(station: Rig, remote: Remote, mark: int) -> None:
    """The station's bridge back (a clean session) as the probe saw it after ``mark``: its first
    heartbeat after it said ``online``; then the remote's rotator hearing it again."""
    bridge_state, beat = remote.station.bridge_state, remote.station.bridge_heartbeat
    online: list[bool] = []

    def beat_after_online(m: Message) -> bool:  # its first beat after it said online
        if m.topic == bridge_state and m.payload == b"online":
            online.append(True)
        return bool(online) and m.topic == beat

    station.probe.wait(beat_after_online, slow(30), "the station's bridge back", mark)
    rotator = remote.rotators[0]
    wait_until(lambda: rotator.away() is None, slow(30), "the station's bridge heard")


def cut_then_healed_later(station: Rig, route: CuttableLink, remote: Remote) -> None:
    """The station's route cut now, mid-turn, then ``healed_later``."""
    cut_az = float(station.emus["tower"].state().az_deg)
    route.cut()  # the station's route dies mid-turn, heals 30 degrees later
    healed_later(station, route, remote, cut_az)


def test_a_stop_sent_as_the_stations_route_dies_still_stops_the_rotor(
    station: Rig, route: CuttableLink
) -> None:
    port = free_port()
    remote = remote_on(station, port)
    try:
        emu = station.emus["tower"]
        cut_az = turning_then_cut(station, route, port)
        said = ask(port, b"S\n")  # the operator's STOP, at once
        healed_later(station, route, remote, cut_az)
    finally:
        remote.stop()
    az = emu.state().az_deg
    assert said in (b"RPRT 0\n", b"RPRT -5\n", b"RPRT -6\n")
    assert abs(az - TARGET_AZ) > 30, f"STOP answered {said!r}; the rotor turned on to {az:.0f}"


def test_a_lock_on_sent_as_the_stations_route_dies_is_held_and_sent_again(
    station: Rig, route: CuttableLink
) -> None:
    """The same partition, the console's lock ON instead of a STOP (the same path: a halt the
    broker took and passed into the dead connection): someone about to climb the tower was
    told it is locked while the station's bridge, back with a clean session, never had it."""
    port = free_port()
    remote = remote_on(station, port)
    try:
        emu = station.emus["tower"]
        cut_az = turning_then_cut(station, route, port)
        with contextlib.suppress(Refused):  # (taken by the broker, or said not delivered)
            remote.rotators[0].submit(Lock(on=True, source=Source.MQTT), "lock ON")
        healed_later(station, route, remote, cut_az)
        wait_until(lambda: station.status("tower").locked, slow(10), "the station locked")
        lock_state = station.topic("tower", "lock/state")
        wait_until(
            lambda: (said := station.probe.last(lock_state)) is not None and said.payload == b"ON",
            slow(10),
            "the station's retained lock/state ON",
        )
        rotator = remote.rotators[0]  # (its own connection reads it after the station's probe)
        wait_until(lambda: rotator.status.locked, slow(10), "the remote's view locked")
        assert ask(port, b"P 100 0\n") == b"RPRT -9\n"  # and the remote sees it so
    finally:
        remote.stop()
    az = emu.state().az_deg
    assert abs(az - TARGET_AZ) > 30, f"lock ON lost: the rotor turned on to {az:.0f}"


def test_a_stop_the_station_showed_it_took_is_not_sent_again_over_a_later_move(
    station: Rig, route: CuttableLink
) -> None:
    """The station's own status showing the rotor with no target after the STOP is its word
    that it has the STOP (interfaces/mqtt/remote.py rule 10): the remote no longer holds it.
    Home Assistant then turns the rotor at the station; the station's route dies and heals
    meanwhile, and the STOP, held for ever, would be sent again when the station's bridge
    connects again and stop that later turn short of its target."""
    port = free_port()
    remote = remote_on(station, port)
    try:
        emu = station.emus["tower"]
        assert ask(port, f"P {TARGET_AZ:g} 0\n".encode()) == b"RPRT 0\n"
        wait_until(lambda: emu.state().az_deg > START_AZ + 60, slow(10), "the rotor turning")
        mark = station.probe.mark()
        assert ask(port, b"S\n") == b"RPRT 0\n"  # taken at once: the route is fine
        status = station.topic("tower", "status")
        stopped_az = station_showed_stop(station, mark)
        mark = station.probe.mark()
        station.probe.publish(station.topic("tower", "target"), "5")  # Home Assistant's
        station.probe.wait(
            lambda m: m.topic == status and b'"moving":true' in m.payload,
            slow(10),
            "the station turning to 5",
            mark,
        )
        cut_az = float(emu.state().az_deg)
        route.cut()
        wait_until(lambda: emu.state().az_deg < cut_az - 10, slow(10), "the rotor turning on")
        route.heal()
        rotator = remote.rotators[0]
        wait_until(lambda: rotator.away() is None, slow(30), "the station's bridge back")
        station.arrived("tower", 5)
    finally:
        remote.stop()
    assert stopped_az > 5 + 60


def test_a_stop_sent_again_never_undoes_a_later_target(broker: Mosquitto, probe: Probe) -> None:
    """interfaces/mqtt/remote.py rule 10: a STOP the station has not shown done is sent again
    when its bridge connects again and its status shows the turn the STOP was asked against
    still on, but not once its status shows a turn taken after the STOP (a later target, from
    this remote or another front end): sent again then, it would stop the newer target (the
    order the commands were taken in)."""
    heard: list[str] = []
    link = halting_link(
        broker.port, "remote-order-test", lambda topic, payload, retain: heard.append(topic)
    )
    link.start()
    try:
        wait_until(lambda: link.subscribed_since is not None, slow(10), "the link subscribed")
        station = station_word(probe, heard)
        station("rotor/bridge/heartbeat", beat_payload(time.time()).encode())
        station(STATUS, turning_status(1))  # turning to a target taken at place 1
        log_from = broker.log.stat().st_size
        link.send("rotor/stop", "stop", "DL1ABC", 5)  # into a dead connection, maybe
        link.send(
            "rotor/target", '{"azimuth":100}', "DL1ABC", 5, lambda: None, after=("rotor/stop",)
        )
        station("rotor/bridge/state", b"online")  # its bridge connected again
        station(STATUS, turning_status(2))  # turning to the later target (place 2)
        station("rotor/bridge/heartbeat", beat_payload(time.time()).encode())
        link.send("rotor/track", "off", "DL1ABC", 5)  # a marker behind anything sent again
        wait_until(lambda: len(remote_published(broker, log_from)) >= 3, slow(10), "the marker")
        assert remote_published(broker, log_from) == [b"stop", b"target", b"track"]
        # with the STOP's own turn still shown, the same STOP goes again (what the test above
        # would miss)
        log_from = broker.log.stat().st_size
        link.send("rotor/stop", "stop", "DL1ABC", 5)
        station("rotor/bridge/state", b"online")
        station(STATUS, turning_status(2))
        station("rotor/bridge/heartbeat", beat_payload(time.time()).encode())
        link.send("rotor/track", "off", "DL1ABC", 5)
        wait_until(lambda: len(remote_published(broker, log_from)) >= 3, slow(10), "the marker")
        assert remote_published(broker, log_from) == [b"stop", b"stop", b"track"]
    finally:
        link.stop()


def test_a_station_without_order_gets_no_hold(broker: Mosquitto, probe: Probe) -> None:
    """interfaces/mqtt/remote.py rule 10: a station's bridge whose status carries no ``order``
    (an older version) cannot say whether a turn it shows came before a halt or after it:
    the remote holds nothing for it and sends its STOP once, as before rule 10, whatever
    the station's ``online`` and turning statuses say after it."""
    heard: list[str] = []
    link = halting_link(
        broker.port, "remote-no-order-test", lambda topic, payload, retain: heard.append(topic)
    )
    old = json.loads(turning_status(1))
    del old["order"]
    link.start()
    try:
        wait_until(lambda: link.subscribed_since is not None, slow(10), "the link subscribed")
        station = station_word(probe, heard)
        station("rotor/bridge/heartbeat", beat_payload(time.time()).encode())
        station(STATUS, json.dumps(old).encode())
        log_from = broker.log.stat().st_size
        link.send("rotor/stop", "stop", "DL1ABC", 5)
        station("rotor/bridge/state", b"online")
        station(STATUS, json.dumps(old).encode())  # still turning, as far as it says
        station("rotor/bridge/heartbeat", beat_payload(time.time()).encode())
        link.send("rotor/track", "off", "DL1ABC", 5)  # a marker behind anything sent again
        wait_until(lambda: len(remote_published(broker, log_from)) >= 2, slow(10), "the marker")
        assert remote_published(broker, log_from) == [b"stop", b"track"]
    finally:
        link.stop()
