"""The rotator's judgement of commands: the one place for limits, lock and capabilities.
No port is opened: every refusal here happens before anything could reach a worker."""

from __future__ import annotations

import pytest

from bridge.app import worker_config
from bridge.core.errors import Refused
from bridge.core.geo import parse_locator
from bridge.core.model import ErrorEvent, Lock, SetOption, Source, Stop, Target, Toward
from bridge.interfaces.mqtt.service import MqttService
from bridge.interfaces.mqtt.topics import Topics
from bridge.runtime.rotator import LOCK_OFF_STALE_MESSAGE, Rotator
from bridge.runtime.state_store import StateStore
from bridge.settings import RotatorSettings
from tests.mqtt.test_service import RecordingPublisher
from tests.support.waiting import slow


def rotator(
    model: str = "rotorez", station: tuple[float, float] | None = None, **settings: object
) -> tuple[Rotator, list]:
    events: list[ErrorEvent] = []
    cfg = worker_config(RotatorSettings(id="t", model=model, port="/dev/null", **settings))
    rot = Rotator(cfg, StateStore(None), lambda s: None, events.append, station=station)
    return rot, events


def code(rot: Rotator, command) -> str:  # noqa: ANN001
    with pytest.raises(Refused) as exc:
        rot.submit(command)
    return exc.value.code


def test_limits_are_judged_on_what_the_controller_will_get() -> None:
    rot, events = rotator(az_max_deg=350.6)
    assert code(rot, Target(350.6)) == "limits"  # a Rotor-EZ would be sent 351
    assert "becomes 351" in events[-1].message
    assert code(rot, Target(350.4)) == "offline"  # within limits; refused only for the link
    assert code(rot, Target(float("nan"))) == "limits"
    assert code(rot, Target(-0.1)) == "limits"


def test_lock_refuses_motion_but_never_a_stop() -> None:
    rot, events = rotator()
    rot.submit(Lock(True))
    assert code(rot, Target(10)) == "locked"
    rot.submit(Stop())  # accepted: queued for the worker
    assert events[-1].kind == "refused" and "locked" in events[-1].message


def test_capabilities() -> None:
    rot, _ = rotator("rotorcard")
    assert code(rot, SetOption("jam", True)) == "unsupported"
    assert code(rot, Target(10, 20)) == "unsupported"  # no elevation axis
    assert code(rot, Target(None, None)) == "invalid"
    spid, _ = rotator("rot2prog", el_max_deg=90)
    assert code(spid, Target(10, 91)) == "limits"
    assert code(spid, Target(10.3, 89.9)) == "offline"  # SPID rounds down: no rounding past


def test_the_station_itself_and_its_antipode_are_refused_as_targets_with_a_reason() -> None:
    """Neither has a bearing of its own: the station's own locator used to turn the antenna to
    north (0), and so did the antipode, where every direction is as short as any other."""
    home = parse_locator("JO62qm")
    rot, events = rotator(station=home)
    with pytest.raises(Refused) as exc:
        rot.submit(Toward(*home, "JO62qm"), "locator JO62qm")
    assert exc.value.code == "invalid"
    assert events[-1].kind == "refused"
    assert "JO62qm is the station's own position" in events[-1].message
    assert "no bearing" in events[-1].message
    # the same place typed as coordinates, by either path
    with pytest.raises(Refused):
        rot.submit(Toward(*home, long_path=True), "coordinates")
    assert "the station's own position" in events[-1].message
    # the antipode of a locator's centre is another locator's centre
    antipode = (-home[0], home[1] - 180.0)
    assert parse_locator("AD67ql") == pytest.approx(antipode)
    with pytest.raises(Refused) as exc:
        rot.submit(Toward(*parse_locator("AD67ql"), "AD67ql"), "locator AD67ql")
    assert exc.value.code == "invalid"
    assert "AD67ql is the station's antipode" in events[-1].message
    assert "every bearing" in events[-1].message
    # a neighbouring square still has a bearing: judged further on (no link here: offline)
    with pytest.raises(Refused) as exc:
        rot.submit(Toward(*parse_locator("JO62qn"), "JO62qn"), "locator JO62qn")
    assert exc.value.code == "offline"


def test_the_lock_and_options_are_saved_off_the_callers_thread(tmp_path) -> None:  # noqa: ANN001
    """state_store.py rule 5: an MQTT callback that sets the lock returns before the fsync
    (tens of milliseconds on an SD card, with the next stop on that connection behind it);
    the file has the last word once the writer is done."""
    import threading

    store = StateStore(tmp_path / "state.json")
    release = threading.Event()
    write = store._write
    waited_out: list[bool] = []  # a write that waited its 5 s: the caller was held all along

    def slow_write(*args, **kwargs) -> None:  # noqa: ANN002, ANN003
        waited_out.append(not release.wait(slow(5)))
        write(*args, **kwargs)

    store._write = slow_write  # type: ignore[method-assign]
    cfg = worker_config(RotatorSettings(id="t", model="rotorez", port="/dev/null"))
    rot = Rotator(cfg, store, lambda s: None, lambda e: None)
    rot.submit(Lock(True))  # returns while the write waits
    rot.submit(Lock(False))
    rot.submit(Lock(True))
    release.set()
    store.flush()
    assert not any(waited_out)
    assert StateStore(tmp_path / "state.json").locked("t") is True


def test_a_lock_off_while_the_lock_is_off_writes_nothing(tmp_path) -> None:  # noqa: ANN001
    """Attack 24: a client republishing lock OFF in a loop cost each word an owner's step, a
    state file save and a wake of the serial-lines thread. An OFF while the last word was OFF
    changes nothing and is not saved again; the first OFF after a start (it ends the wait for
    the lock's word, kept.py rule 10) and every word that changes the lock still are."""
    store = StateStore(tmp_path / "state.json")
    writes: list[object] = []
    write = store._write

    def counted(*args, **kwargs) -> None:  # noqa: ANN002, ANN003
        writes.append(args)
        write(*args, **kwargs)

    store._write = counted  # type: ignore[method-assign]
    cfg = worker_config(RotatorSettings(id="t", model="rotorez", port="/dev/null"))
    rot = Rotator(cfg, store, lambda s: None, lambda e: None)
    rot.submit(Lock(False))  # the first word since the start: taken and saved
    store.flush()
    first = len(writes)
    assert first >= 1
    epoch = rot.halts
    for _ in range(1_000):
        rot.submit(Lock(False))
    store.flush()
    assert len(writes) == first and rot.halts == epoch and not rot.locked
    rot.submit(Lock(True))
    rot.submit(Lock(False))
    store.flush()
    assert len(writes) > first
    assert StateStore(tmp_path / "state.json").locked("t") is False
    rot.submit(Lock(True))
    store.flush()
    assert StateStore(tmp_path / "state.json").locked("t") is True


class _Fence:
    """What the MQTT service is told of a halt from another interface (rotator.py
    ``HaltFence``); ``fail``: it raises."""

    def __init__(self, rot: list[Rotator], fail: bool = False) -> None:
        self.told: list[tuple[str, object]] = []
        self._rot, self._fail = rot, fail

    def fence_asked(self, rotator_id: str) -> None:
        self.told.append(("asked", self._rot[0].halts))  # before the put: the count then
        if self._fail:
            raise RuntimeError("a bug in the fence")

    def fence_carried(self, rotator_id: str, lock: bool) -> None:
        self.told.append(("carried", lock))
        if self._fail:
            raise RuntimeError("a bug in the fence")


@pytest.mark.parametrize("fail", [False, True], ids=["fence", "a fence that raises"])
def test_another_interfaces_halt_is_told_to_the_fence_around_its_put_and_mqtts_is_not(
    fail: bool,
) -> None:
    """interfaces/mqtt/lastword.py rule 11: the console's lock ON and rotctld's stop are told
    before their put (the halt count not yet up) and after; MQTT's own are ordered by the last
    word, not told; a fence that raises costs the halt nothing."""
    holder: list[Rotator] = []
    fence = _Fence(holder, fail)
    cfg = worker_config(RotatorSettings(id="t", model="rotorez", port="/dev/null"))
    rot = Rotator(cfg, StateStore(None), lambda s: None, lambda e: None, fence=fence)
    holder.append(rot)
    rot.submit(Stop(Source.ROTCTLD))
    rot.submit(Lock(True, source=Source.WEB))
    rot.submit(Lock(False, source=Source.WEB))  # a lock OFF fences nothing
    rot.submit(Stop(Source.MQTT))
    rot.submit(Lock(True, source=Source.MQTT))
    assert fence.told == [("asked", 0), ("carried", False), ("asked", 1), ("carried", True)]
    assert rot.halts == 4 and rot.locked


def test_an_mqtt_lock_off_read_as_the_consoles_lock_on_is_put_leaves_the_lock_on() -> None:
    """interfaces/mqtt/lastword.py rule 11 (a review): the main connection reads a lock OFF
    published before the console's lock ON and finds no fence yet; the console's lock ON is
    asked, put and fenced before the lock OFF reaches the judge. The lock OFF then unlocked
    the rotator under a page that had said ON: it is refused, the lock stays ON."""
    events: list[ErrorEvent] = []
    cfg = worker_config(RotatorSettings(id="t", model="rotorez", port="/dev/null"))
    svc = MqttService(Topics("rotor", {"t": "rotor"}), RecordingPublisher(), wall=lambda: 0.0)
    rot = Rotator(cfg, StateStore(None), lambda s: None, events.append, fence=svc)
    svc.attach(rot)
    unfenced = svc._halts.fenced

    def locked_right_after(rotator_id: str, lock_off: bool = False) -> bool:
        fenced = unfenced(rotator_id, lock_off)
        rot.submit(Lock(True, source=Source.WEB))  # the console's thread, between the two
        return fenced

    svc._halts.fenced = locked_right_after  # type: ignore[method-assign]
    svc.on_message("rotor/lock", b"OFF", False, "G4ABC")
    assert rot.locked
    assert [e.message for e in events] == [LOCK_OFF_STALE_MESSAGE]
