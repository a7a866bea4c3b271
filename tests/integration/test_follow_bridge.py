"""Following the QSO partner end to end: WSJT-X's Status messages on real UDP (encoded by
tests/support/wsjtx.py from the protocol's fact sheet, the encoder WSJT-X's own udp_daemon
judges in tests/wsjtx/test_udp_daemon.py), one running bridge (the App in-process) with a
private mosquitto and an emulated MD-01 (a SPID: digital encoders, 0.1 degree) on a real pty.

What is asserted is what a user sees: the frames the controller received (the emulator's log:
"set" is a target), where the rotor really is (its ground truth) against bearings computed
here by other means (tests/integration/test_pointing_bridge.py's vector great circle), and
what the bridge publishes (R/follow/state, R/status, R/error). Absence ("moves nothing") is
proven by order: what must do nothing is sent first, then something the bridge shows it has
taken (a held grid, the newest status in its follow part), and only then is the log read.
"""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from typing import Any

import pytest

from bridge.app import App
from bridge.runtime.rotator import Rotator
from bridge.session.follow import Heard
from tests.integration.test_pointing_bridge import angle_between, locator_centre, reference_path
from tests.support import wait_until
from tests.support import wsjtx as w
from tests.support.ports import free_udp_port
from tests.support.rig import Rig

STATION = "JO62QM"  # Berlin
TOKYO = "PM95VQ"
SYDNEY = "QF56OC"
NEW_YORK = "FN30AS"


def bearing_to(grid: str) -> float:
    return reference_path(locator_centre(STATION), locator_centre(grid))[0]


def distance_to(grid: str) -> float:
    return reference_path(locator_centre(STATION), locator_centre(grid))[1]


@pytest.fixture
def follow_rig(rig: Rig) -> Iterator[tuple[Rig, App, tuple[str, int]]]:
    port = free_udp_port()
    rig.add("tower", "md01", emu={"start_az_deg": 0})
    rig.sections = {
        "station": {"locator": STATION},
        "wsjtx": {"enabled": True, "port": port, "bind": "127.0.0.1"},
    }
    app = rig.start()
    rig.ready("tower")
    yield rig, app, ("127.0.0.1", port)


def rotator(app: App) -> Rotator:
    return app.rotators[0]


def status_doc(rig: Rig) -> dict[str, Any]:
    last = rig.probe.last("rotor/status")
    assert last is not None
    doc: dict[str, Any] = json.loads(last.payload)
    return doc


DIAL = w.StatusFields().dial_hz  # what the statuses sent here carry (follow.py rule 9)


def heard_by_follow_part(app: App, heard: Heard) -> None:
    """Wait until the rotator's follow part has taken ``heard`` in (the order a test proves
    absence by; read across threads, only to wait on)."""
    session = rotator(app)._worker.session
    wait_until(lambda: session.follower._heard == heard, 10, f"the follow part hears {heard}")


def test_a_dx_grid_turns_the_rotor_the_same_grid_does_not_tx_holds_and_off_ends(
    follow_rig: tuple[Rig, App, tuple[str, int]],
) -> None:
    rig, app, to = follow_rig
    emu = rig.emu
    rig.probe.publish("rotor/follow", "wsjtx")
    rig.probe.wait_value("rotor/follow/state", "wsjtx", 10)

    # a DX grid: the rotor turns to its great-circle bearing, within 1 degree
    w.send(w.status(w.StatusFields(dx_call="JA1ABC", dx_grid=TOKYO)), to)
    want = bearing_to(TOKYO)
    rig.arrived("tower", want, timeout_s=30)
    assert angle_between(emu.state().az_deg, want) <= 1.0
    msg = rig.probe.wait_for(  # (the status of the turn: an MD-01 just online may be asked
        "rotor/status",  # once more first, spid.py rule 5, while the grid is already shown)
        lambda m: (
            (json.loads(m.payload).get("following") or {}).get("grid") == TOKYO
            and json.loads(m.payload)["last_command_source"] == "wsjtx"
        ),
        10,
    )
    following = json.loads(msg.payload)["following"]
    assert following["call"] == "JA1ABC" and following["source"] == "wsjtx"
    assert abs(following["bearing"] - want) <= 1.0
    assert abs(following["distance_km"] - distance_to(TOKYO)) <= 0.01 * distance_to(TOKYO)
    assert "instance" not in following  # (not published: the WSJT-X listener reads it)
    assert rotator(app).followed == "WSJT-X"  # its budget room kept (wsjtx/server.py rule 5)
    assert app.wsjtx is not None and app.wsjtx.counts.faults == 0  # (asked at each wake-up)
    sets = len(emu.frames("set"))

    # the same grid again (WSJT-X sends a status on every change: decoding, Rx DF...)
    for decoding in (True, False):
        same = w.StatusFields(dx_call="JA1ABC", dx_grid=TOKYO, decoding=decoding, rx_df=900)
        w.send(w.status(same), to)
    # then a new grid while transmitting: held, and shown as held
    w.send(w.status(w.StatusFields(dx_call="VK2XYZ", dx_grid=SYDNEY, transmitting=True)), to)
    rig.probe.wait_for(
        "rotor/status", lambda m: (json.loads(m.payload).get("following") or {}).get("held"), 10
    )
    assert len(emu.frames("set")) == sets  # neither the same grid nor the held one moved it
    assert not emu.state().is_moving

    # the transmission ends: the held grid is turned to
    w.send(w.status(w.StatusFields(dx_call="VK2XYZ", dx_grid=SYDNEY, transmitting=False)), to)
    rig.arrived("tower", bearing_to(SYDNEY), timeout_s=30)
    assert angle_between(emu.state().az_deg, bearing_to(SYDNEY)) <= 1.0
    assert len(emu.frames("set")) == sets + 1
    rig.probe.wait_for(
        "rotor/status",
        lambda m: (json.loads(m.payload).get("following") or {}).get("grid") == SYDNEY,
        10,
    )
    assert status_doc(rig)["following"]["held"] is False

    # follow off: a new grid moves nothing
    t_off = time.monotonic()  # (follow/state said off before it was on: that is no answer)
    rig.probe.publish("rotor/follow", "off")
    rig.probe.wait_value("rotor/follow/state", "off", 10, after=t_off)
    w.send(w.status(w.StatusFields(dx_call="W2ABC", dx_grid=NEW_YORK)), to)
    heard_by_follow_part(app, Heard("W2ABC", NEW_YORK, False, "WSJT-X", DIAL))
    assert len(emu.frames("set")) == sets + 1
    ended = rig.probe.wait_for(
        "rotor/status", lambda m: json.loads(m.payload).get("following_ended") == "off", 10
    )
    assert "following" not in json.loads(ended.payload)


def test_any_other_command_ends_following_and_a_long_path_is_asked_in_json(
    follow_rig: tuple[Rig, App, tuple[str, int]],
) -> None:
    rig, app, to = follow_rig
    rig.probe.publish("rotor/follow", json.dumps({"source": "wsjtx", "path": "long"}))
    rig.probe.wait_value("rotor/follow/state", "wsjtx", 10)
    w.send(w.status(w.StatusFields(dx_call="JA1ABC", dx_grid=TOKYO)), to)
    long_path = (bearing_to(TOKYO) + 180.0) % 360.0
    rig.arrived("tower", long_path, timeout_s=30)
    assert angle_between(rig.emu.state().az_deg, long_path) <= 1.0
    rig.probe.wait_for(
        "rotor/status",
        lambda m: (json.loads(m.payload).get("following") or {}).get("path") == "long",
        10,
    )

    rig.probe.publish("rotor/target", "200")  # a manual target ends it, like tracking
    rig.probe.wait_value("rotor/follow/state", "off", 10)
    rig.arrived("tower", 200.0, timeout_s=30)
    rig.probe.wait_for(
        "rotor/status", lambda m: json.loads(m.payload).get("following_ended") == "mqtt target", 10
    )
    sets = len(rig.emu.frames("set"))
    w.send(w.status(w.StatusFields(dx_call="W2ABC", dx_grid=NEW_YORK)), to)
    heard_by_follow_part(app, Heard("W2ABC", NEW_YORK, False, "WSJT-X", DIAL))
    assert len(rig.emu.frames("set")) == sets


def test_a_retained_follow_never_switches_it_on_and_malformed_datagrams_change_nothing(
    follow_rig: tuple[Rig, App, tuple[str, int]],
) -> None:
    rig, app, to = follow_rig
    mark = rig.probe.mark()
    rig.probe.publish("rotor/follow", "wsjtx", retain=True)  # docs/architecture.md rule 7
    error = rig.probe.wait(lambda m: m.topic == "rotor/error", 10, "the refusal", mark)
    assert "retained" in json.loads(error.payload)["message"]
    rig.probe.publish("rotor/follow", "", retain=True)  # (cleared: the broker keeps nothing)
    assert rig.retained()["rotor/follow/state"] == b"off"

    rig.probe.publish("rotor/follow", "wsjtx")
    rig.probe.wait_value("rotor/follow/state", "wsjtx", 10)
    good = w.status(w.StatusFields(dx_call="JA1ABC", dx_grid=TOKYO))
    junk = [
        b"",
        b"\x00" * 3,
        w.u32(0xDEADBEEF) + good[4:],  # wrong magic
        good[:4] + w.u32(1) + good[8:],  # schema 1 (never sent: broken)
        good[:40],  # truncated inside a string
        good[:12] + w.u32(60_000) + good[16:],  # the Id's length past the end
        good[: good.index(TOKYO.encode()) + 2],  # cut inside the DX grid
        b"\xff" * 65_000,  # 64 KB of junk
    ]
    listener = app.wsjtx
    before = listener.counts.malformed
    for datagram in junk:
        w.send(datagram, to)
    # then a status the follow part takes in: every datagram before it has been read
    w.send(w.status(w.StatusFields(dx_call="", dx_grid="")), to)
    heard_by_follow_part(app, Heard("", "", False, "WSJT-X", DIAL))
    assert listener.counts.malformed - before == len(junk)
    assert rig.emu.frames("set") == []  # nothing moved the rotor
    shown = rig.probe.wait_for("rotor/status", lambda m: "following" in json.loads(m.payload), 10)
    assert json.loads(shown.payload)["following"]["grid"] is None  # nothing turned to


def test_without_the_station_following_is_refused_saying_what_it_needs(rig: Rig) -> None:
    rig.add("tower", "md01")
    rig.sections = {"wsjtx": {"enabled": True, "port": free_udp_port()}}
    rig.start()
    rig.ready("tower")
    mark = rig.probe.mark()
    rig.probe.publish("rotor/follow", "wsjtx")
    error = rig.probe.wait(lambda m: m.topic == "rotor/error", 10, "the refusal", mark)
    doc = json.loads(error.payload)
    assert doc["kind"] == "refused" and "[station] locator" in doc["message"]
    assert doc["command"] == "follow 'wsjtx'"
    assert "rotor/follow/state" not in rig.retained()  # nothing to follow: no switch either
