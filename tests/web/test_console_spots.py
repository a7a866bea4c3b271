"""DX cluster spots on the console's map: a fake cluster node on real TCP (tests/support/cluster.py)
feeds a running bridge (the App in-process, a private mosquitto, an emulated MD-01 on a pty, a
small cty file); the console's feed carries the spot list (``spots``), a page that connects
after the spots came gets them, and in Debian's Chromium each spot is a dot labelled with its
call at its bearing and distance, and a click on one turns the rotor toward it (shift: the long
path). What is judged
is what the user notices: the dots and their calls on the page, the rotor's final bearing."""

from __future__ import annotations

import json
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from playwright.sync_api import Browser, Page, expect

from bridge.interfaces.web.projection import RIM_KM
from tests.dxcluster.cty_sample import CTY_DAT
from tests.integration.test_dxcluster_bridge import JAPAN, W1XYZ_GRID, bearing_to
from tests.integration.test_pointing_bridge import angle_between, locator_centre
from tests.support.clock import RunningWall
from tests.support.cluster import FakeCluster, Session
from tests.support.console import ConsoleClient, EventStream, web_section
from tests.support.rig import Rig
from tests.support.waiting import slow
from tests.web.conftest import STATION_LOCATOR, open_console

SPOTS = [
    b"DX de EA5WU:     14025.0  JA1ABC       cq up 2                        1829Z\r\n",
    b"DX de G4ABC:   50313.0  W1XYZ   FT8 JO01<>FN31pr  1830Z\r\n",
]


@pytest.fixture
def spotted(rig: Rig, tmp_path: Path) -> Iterator[tuple[Rig, int, list[dict[str, Any]]]]:
    """A bridge with [web] and [dxcluster], its node's two spots on B/spots: (rig, the
    console's port, the spots as B/spots lists them)."""

    def node(s: Session) -> None:
        s.send(b"login: ")
        s.read_line()
        for line in SPOTS:
            s.send(line)
        cluster.done.wait(slow(60))  # the line stays open until the test ends

    cluster = FakeCluster([node])
    cty = tmp_path / "cty.dat"
    cty.write_text(CTY_DAT)
    rig.add("tower", "md01", emu={"start_az_deg": 0})
    web = web_section()
    rig.sections = {
        "station": {"locator": STATION_LOCATOR},
        "web": web,
        "dxcluster": {
            "enabled": True,
            "host": "127.0.0.1",
            "port": cluster.port,
            "login": "g4abc",
            "cty_file": str(cty),
            "bands": ["6m", "20m"],
        },
    }
    rig.wall = RunningWall("1831")  # the spots' times are live (book.py rule 2)
    rig.start()
    rig.ready("tower")
    try:
        msg = rig.probe.wait_for(
            "rotor/spots", lambda m: len(json.loads(m.payload)["spots"]) == 2, 20
        )
        yield rig, web["port"], json.loads(msg.payload)["spots"]
    finally:
        cluster.close()
    assert not cluster.errors, cluster.errors


def test_a_page_that_connects_after_the_spots_came_gets_them(
    spotted: tuple[Rig, int, list[dict[str, Any]]],
) -> None:
    _, port, spots = spotted
    client = ConsoleClient(port)
    client.session()
    stream = EventStream(client)
    try:
        while (event := stream.next())[0] != "spots":  # after the newest status
            assert event[0] == "status", event
        assert event[1] == {"spots": spots}  # B/spots' document, as MQTT has it
    finally:
        stream.close()
    ja = next(s for s in spots if s["call"] == "JA1ABC")
    assert angle_between(ja["bearing_deg"], bearing_to(JAPAN)) <= 1.0


def _spot_place(page: Page, call: str) -> tuple[float, float]:
    """(bearing, radius) of a spot's dot on #map, in the map's own units."""
    x, y = page.evaluate(
        """(call) => {
          const spot = document.querySelector(`#map .spot[data-call="${call}"]`);
          const m = spot.transform.baseVal.consolidate().matrix;
          return [m.e, m.f];
        }""",
        call,
    )
    return math.degrees(math.atan2(x, -y)) % 360.0, math.hypot(x, y)


def test_spots_are_dots_with_their_calls_and_a_click_turns_the_rotor_toward_one(
    spotted: tuple[Rig, int, list[dict[str, Any]]], browser: Browser
) -> None:
    rig, port, spots = spotted
    page = open_console(browser, f"http://127.0.0.1:{port}/")
    errors: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    try:
        for s in spots:
            spot = page.locator(f'#map .spot[data-call="{s["call"]}"]')
            expect(spot).to_be_visible()
            expect(spot.locator(".spot-call")).to_have_text(s["call"])
            bearing, radius = _spot_place(page, s["call"])
            assert angle_between(bearing, s["bearing_deg"]) <= 0.1
            assert radius == pytest.approx(s["distance_km"] / RIM_KM, abs=1e-3)
        w1 = next(s for s in spots if s["call"] == "W1XYZ")
        assert angle_between(w1["bearing_deg"], bearing_to(locator_centre(W1XYZ_GRID))) <= 1.0

        ja = next(s for s in spots if s["call"] == "JA1ABC")
        page.locator('#map .spot[data-call="JA1ABC"] .spot-dot').click()
        expect(page.locator("#pointer")).to_contain_text("sent: JA1ABC")
        rig.arrived("tower", ja["bearing_deg"], timeout_s=30)
        assert angle_between(rig.emu.state().az_deg, ja["bearing_deg"]) <= 1.0

        # shift: the long path, as on the map
        page.locator('#map .spot[data-call="W1XYZ"] .spot-dot').click(modifiers=["Shift"])
        expect(page.locator("#pointer")).to_contain_text("sent: W1XYZ")
        expect(page.locator("#pointer")).to_contain_text("long path")
        rig.arrived("tower", w1["long_path_deg"], timeout_s=30)
        assert angle_between(rig.emu.state().az_deg, w1["long_path_deg"]) <= 1.0
    finally:
        page.context.close()
    assert not errors, errors
