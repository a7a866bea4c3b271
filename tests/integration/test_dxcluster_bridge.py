"""DX cluster spots end to end: a fake cluster node on real TCP (tests/support/cluster.py)
plays recorded-style lines, junk, a long line, a slow login prompt and a dropped connection
to one running bridge (the App in-process) with a private mosquitto, an emulated MD-01 on a
real pty and a small cty file written here (tests/dxcluster/cty_sample.py).

Asserted is what a user sees: B/spots (retained) with bearings checked against the vector
great circle of tests/integration/test_pointing_bridge.py, the rotor's ground truth after
``R/target {"call": ...}``, the refusals on R/error, and the login lines the node received.
"""

from __future__ import annotations

import json
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from bridge.app import App
from bridge.interfaces.dxcluster import DxCluster
from tests.dxcluster.cty_sample import CTY_DAT
from tests.integration.test_pointing_bridge import angle_between, locator_centre, reference_path
from tests.support import retained_snapshot, wait_until
from tests.support.clock import RunningWall
from tests.support.cluster import FakeCluster, Session
from tests.support.rig import Rig
from tests.support.waiting import slow

STATION = "JO62QM"  # Berlin
JAPAN = (36.40, 138.38)  # the small cty file's Japan, east-positive
AUSTRALIA = (-23.70, 132.33)
W1XYZ_GRID = "FN31PR"

FIRST = [  # the first session, after the login
    b"Hello G4ABC, this is GB7FAKE\r\n",
    b"DX de EA5WU:     14025.0  JA1ABC       cq up 2                        1829Z\r\n",
    b"\xff\xfb\x01 telnet junk \xfe\x00\r\n",  # not UTF-8
    b"DX de W3LPL-#:  " + b"9" * 3000 + b"\r\n",  # a long line: dropped whole
    b"WWV de W0MU <18>:   SFI=70, A=5, K=1\r\n",
    b"DX de G4ABC:   50313.0  W1XYZ   FT8 JO01<>FN31pr  1830Z\r\n",
    b"DX de G4ABC:  144300.0  F5ABC   2m is off the list   1830Z\r\n",
    b"DX de EA5WU:    14030.0  JA1ABC       QSX up                      1831Z\r\n",
]


Running = tuple[Rig, App, FakeCluster, threading.Event]


@pytest.fixture
def cluster_rig(rig: Rig, tmp_path: Path) -> Iterator[Running]:
    prompt_may_go = threading.Event()
    waited: list[bool] = []

    def first(s: Session) -> None:  # a slow login prompt, in two pieces, then spots and drop
        s.send(b"Connected to the fake node\r\n")
        prompt_may_go.wait(slow(30))  # the test lets it go when the client has waited a while
        waited.append(s.nothing_sent_yet())  # the client waited for the prompt
        s.send(b"log")
        s.send(b"in: ")
        cluster.logins.append(s.read_line())
        for line in FIRST:
            s.send(line)
        # returning drops the line: the client connects again

    def second(s: Session) -> None:
        s.send(b"Please enter your call: ")
        cluster.logins.append(s.read_line())
        s.send(b"DX de K1TTT:    7012.5  VK2XYZ/P     CW 21 dB 28 WPM CQ       1833Z\r\n")
        cluster.done.wait(slow(60))

    cluster = FakeCluster([first, second])
    cty = tmp_path / "cty.dat"
    cty.write_text(CTY_DAT)
    rig.add("tower", "md01", emu={"start_az_deg": 0})
    rig.sections = {
        "station": {"locator": STATION},
        "dxcluster": {
            "enabled": True,
            "host": "127.0.0.1",
            "port": cluster.port,
            "login": "g4abc",
            "cty_file": str(cty),
            "bands": ["6m", "20m", "40m"],
        },
    }
    rig.wall = RunningWall("1834")  # the spots' times are live (book.py rule 2)
    app = rig.start()
    rig.ready("tower")
    try:
        yield rig, app, cluster, prompt_may_go
    finally:
        cluster.close()
        assert waited in ([], [True])
        assert not cluster.errors, cluster.errors


def spots(rig: Rig, calls: set[str], newest_ja_khz: float = 14030.0) -> list[dict[str, Any]]:
    """B/spots once it lists ``calls`` and JA1ABC's newest spot (the node's last line of the
    first session: however TCP cut the lines, all of them have been read by then)."""

    def done(payload: bytes) -> bool:
        listed = {s["call"]: s for s in json.loads(payload)["spots"]}
        ja = listed.get("JA1ABC")
        return calls <= set(listed) and ja is not None and ja["frequency_khz"] == newest_ja_khz

    msg = rig.probe.wait_for("rotor/spots", lambda m: done(m.payload), 20)
    spots_: list[dict[str, Any]] = json.loads(msg.payload)["spots"]
    return spots_


def bearing_to(where: tuple[float, float]) -> float:
    return reference_path(locator_centre(STATION), where)[0]


def test_spots_reach_b_spots_the_client_reconnects_and_a_call_turns_the_rotor(
    cluster_rig: Running,
) -> None:
    rig, app, cluster, prompt_may_go = cluster_rig
    dx = app.services["dxcluster"]  # the feature's service (features/dxcluster)
    assert isinstance(dx, DxCluster)
    # the node has said hello and sent no prompt for a whole read timeout: the client goes on
    # waiting (this wait is the slow prompt under test), sends nothing and fails nothing
    wait_until(lambda: dx.counts.quiet_reads >= 1, 10, "a quiet read before the prompt")
    assert dx.counts.connects == 0 and dx.counts.failures == 0
    prompt_may_go.set()

    first = spots(rig, {"JA1ABC", "W1XYZ"})
    by_call = {s["call"]: s for s in first}
    assert set(by_call) == {"JA1ABC", "W1XYZ"}  # 2 m is not on the bands asked for
    ja = by_call["JA1ABC"]
    assert (ja["frequency_khz"], ja["spotter"], ja["time"]) == (14030.0, "EA5WU", "1831Z")
    assert (ja["position"], ja["entity"]) == ("cty", "Japan")
    assert angle_between(ja["bearing_deg"], bearing_to(JAPAN)) <= 1.0
    assert angle_between(ja["long_path_deg"], bearing_to(JAPAN) + 180) <= 1.0
    w1 = by_call["W1XYZ"]
    assert (w1["position"], w1["locator"]) == ("locator", W1XYZ_GRID)
    assert angle_between(w1["bearing_deg"], bearing_to(locator_centre(W1XYZ_GRID))) <= 1.0
    want_km = reference_path(locator_centre(STATION), locator_centre(W1XYZ_GRID))[1]
    assert abs(w1["distance_km"] - want_km) <= 0.01 * want_km

    # the node dropped the line: the client logs in again and the new spot joins the others
    again = spots(rig, {"JA1ABC", "W1XYZ", "VK2XYZ/P"})
    assert cluster.logins == [b"G4ABC", b"G4ABC"]
    assert again[0]["call"] == "VK2XYZ/P" and again[0]["entity"] == "Australia"
    assert angle_between(again[0]["bearing_deg"], bearing_to(AUSTRALIA)) <= 1.0
    assert dx.counts.long_lines == 1
    assert dx.counts.other_lines >= 3  # the greeting, the junk, WWV (and the 2 m one parsed)
    assert dx.counts.spots == 5 and dx.counts.connects == 2 and dx.counts.failures == 1
    held = json.loads(retained_snapshot(rig.broker_port, "rotor/spots")["rotor/spots"])
    assert [s["call"] for s in held["spots"]] == [s["call"] for s in again]  # retained

    # {"call": ...}: the newest spot of the call, through the judge, with its source
    rig.probe.publish("rotor/target", json.dumps({"call": "ja1abc"}))
    rig.arrived("tower", bearing_to(JAPAN), timeout_s=30)
    assert angle_between(rig.emu.state().az_deg, bearing_to(JAPAN)) <= 1.0
    status = rig.probe.wait_for(
        "rotor/status", lambda m: json.loads(m.payload).get("last_command_source") == "dxcluster"
    )
    assert json.loads(status.payload)["target_info"]["latitude"] == pytest.approx(JAPAN[0])

    # a call never spotted: its cty entity (Australia), the long path asked for
    rig.probe.publish("rotor/target", json.dumps({"call": "VK3ABC", "path": "long"}))
    rig.arrived("tower", (bearing_to(AUSTRALIA) + 180) % 360, timeout_s=40)

    # a call in no entity and not spotted: refused on R/error, nothing moves
    sets = len(rig.emu.frames("set"))
    rig.probe.publish("rotor/target", json.dumps({"call": "QQ1ABC"}))
    err = rig.probe.wait_for("rotor/error", lambda m: b"QQ1ABC" in m.payload, 10)
    assert "no entity" in json.loads(err.payload)["message"]
    rig.probe.publish("rotor/target", json.dumps({"call": "not a call"}))
    err = rig.probe.wait_for("rotor/error", lambda m: b"call sign" in m.payload, 10)
    assert len(rig.emu.frames("set")) == sets
