"""A call (``R/target {"call": ...}``) is looked up on the DX cluster's aim thread, a while after
it was asked: a target sent after it was asked is the later word, however long the look-up
took (dxcluster/client.py rule 4, mailbox.py rule 10a). The judge and the session are the real
ones, on a virtual MD-01 (tests/engine/test_halt_epoch.py's bench): what the controller receives
is what is asserted. The look-up is held on an Event, so no timing decides the order."""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from bridge.core.errors import Refused
from bridge.core.model import Origin, Source, Stop, Target
from bridge.interfaces.dxcluster.book import Book, Kept
from bridge.interfaces.dxcluster.client import DxCluster
from bridge.interfaces.dxcluster.cty import parse_dat
from bridge.interfaces.dxcluster.spots import Spot
from bridge.interfaces.mqtt.service import MqttService
from bridge.interfaces.mqtt.topics import Topics
from tests.dxcluster.cty_sample import CTY_DAT
from tests.engine.test_halt_epoch import Bench
from tests.mqtt.test_service import RecordingPublisher
from tests.support.clock import wall_at
from tests.support.waiting import slow

WHO = Origin(Source.MQTT, "G4ABC")


@pytest.fixture
def bench(tmp_path: Path) -> Iterator[Bench]:
    made = Bench(tmp_path)
    yield made
    made.close()


def held_cluster() -> tuple[DxCluster, threading.Event]:
    """A cluster whose look-ups wait for the Event (a busy aim queue, a big cty file)."""
    book = Book(parse_dat(CTY_DAT), (52.52, 13.40), wall=lambda: wall_at("1234"))
    book.add(Spot("JA1ABC", 14025.0, "G4ABC", "1234", "FT8 PM95vq"))  # Tokyo: about 40 deg
    book.add(Spot("PY1ABC", 14025.0, "G4ABC", "1234", "FT8 GG87"))  # Rio: about 230 deg
    go = threading.Event()
    newest = book.newest

    def held(call: str) -> Kept | None:
        assert go.wait(slow(10))
        return newest(call)

    book.newest = held  # type: ignore[method-assign]
    return DxCluster("127.0.0.1", 9, "G4ABC", book, lambda doc: None), go


def turned(dx: DxCluster, n: int) -> Callable[[], None]:
    """The aim thread's turns of the next ``n`` calls asked, on a thread; the join."""

    def run() -> None:
        for _ in range(n):
            try:
                dx._turn(dx._aims.get_nowait())
            except Refused:
                pass  # reported on R/error (the aim loop does the same)

    thread = threading.Thread(target=run)
    thread.start()
    return lambda: thread.join(slow(10))


def test_a_target_sent_while_a_call_is_looked_up_is_the_later_word(bench: Bench) -> None:
    """An attack pass: the call, looked up after a target of 200 was put, turned the rotor back
    to Tokyo's bearing: the older word overrode the newer."""
    dx, go = held_cluster()
    dx.aim(bench.rot, "JA1ABC", False, 'target {"call":"JA1ABC"}', WHO)
    join = turned(dx, 1)
    bench.rot.submit(Target(200.0, None, Source.MQTT, origin=WHO), "target '200'")
    go.set()
    join()
    bench.v._take()  # (the bench takes the mailbox when told)
    bench.v.run_for(40.0)
    assert bench.rot.status.bearing_deg == pytest.approx(200.0, abs=1.0)
    assert [f[1:5] for f in bench.sets()] == [b"1120"]  # (200 + 360) at two counts a degree
    refusals = [e.message for e in bench.events if "newer command" in e.message]
    assert refusals == ["a newer command came after it was asked: not carried out"]


def test_two_calls_asked_in_a_row_both_turn_the_later_last(bench: Bench) -> None:
    """Places in the order are taken when asked: the first call's put is no newer word for the
    second, asked after it."""
    dx, go = held_cluster()
    dx.aim(bench.rot, "JA1ABC", False, 'target {"call":"JA1ABC"}', WHO)
    dx.aim(bench.rot, "PY1ABC", False, 'target {"call":"PY1ABC"}', WHO)
    go.set()
    turned(dx, 2)()
    bench.v._take()  # (the bench takes the mailbox when told)
    bench.v.run_for(40.0)
    assert not [e.message for e in bench.events], "neither call refused"
    bearing = bench.rot.status.bearing_deg
    assert bearing is not None and 200.0 < bearing < 260.0  # Rio's, the later call


def test_a_call_asked_while_another_holds_the_lease_is_refused_when_asked(bench: Bench) -> None:
    """dxcluster/client.py rule 4: DL2BBB asks for a call while DL1AAA holds the rotator, and
    DL1AAA releases it before the look-up ends. Judged only when put, the call turned the rotor
    (an attack pass): it was asked when it would have been refused, and is refused then."""
    holder = Origin(Source.MQTT, "DL1AAA")
    bench.rot.operators.claim("DL1AAA", 30, holder)
    dx, go = held_cluster()
    dx.aim(bench.rot, "JA1ABC", False, 'target {"call":"JA1ABC"}', WHO)
    bench.rot.operators.release(holder)
    go.set()
    assert dx._aims.empty()  # nothing queued for the look-up
    bench.v._take()
    bench.v.run_for(40.0)
    assert bench.sets() == []
    assert [e.message for e in bench.events][-1].startswith("DL1AAA holds the rotator")


def test_the_asker_s_own_claim_during_the_look_up_does_not_refuse_their_call(
    bench: Bench,
) -> None:
    """The lease claimed by the call's own asker while it is looked up is no word against it
    (a review: when a change of the lease took a place in the order, it dropped the call)."""
    dx, go = held_cluster()
    dx.aim(bench.rot, "JA1ABC", False, 'target {"call":"JA1ABC"}', WHO)
    join = turned(dx, 1)
    bench.rot.operators.claim("G4ABC", 30, WHO)
    go.set()
    join()
    bench.v._take()
    bench.v.run_for(40.0)
    assert bench.sets() != []
    assert not [e.message for e in bench.events]


def test_a_call_read_on_mqtt_as_rotctld_stops_is_refused_not_turned_to(bench: Bench) -> None:
    """interfaces/mqtt/service.py rule 11 (a review): the main connection reads a call target
    published before rotctld's S, finds no fence yet, and rotctld's stop is put before the
    call reaches the aimer. The halt count the service read before it asked the fence goes
    with the call: read again by the aimer, after the stop, it let the call turn the rotor
    after the stop."""
    svc = MqttService(Topics("rotor", {"v": "rotor"}), RecordingPublisher(), wall=lambda: 0.0)
    svc.attach(bench.rot)
    dx, go = held_cluster()
    svc.aim_calls_with(dx.aim)
    unfenced = svc._halts.fenced

    def stopped_right_after(rotator_id: str, lock_off: bool = False) -> bool:
        fenced = unfenced(rotator_id, lock_off)
        bench.rot.submit(Stop(Source.ROTCTLD), "S")  # rotctld's thread, between the two
        return fenced

    svc._halts.fenced = stopped_right_after  # type: ignore[method-assign]
    svc.on_message("rotor/target", b'{"call": "JA1ABC"}', False, "G4ABC")
    go.set()
    turned(dx, 1)()
    bench.v._take()
    bench.v.run_for(40.0)
    assert bench.sets() == []  # the controller was never told to turn
    assert [e.message for e in bench.events] == [
        "JA1ABC: a stop came after it was asked: not turned"
    ]
