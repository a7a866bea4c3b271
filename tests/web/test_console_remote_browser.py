"""The console served by ``rotor-bridge remote`` (``[web]`` in remote.toml), in Debian's Chromium:
the page on the operator's computer shows the station's map and drives the station's rotator
over the broker, as the station's own console does. Real parts: a mosquitto, the station's
bridge on an emulated Rotor-EZ, the remote in this process. What is judged is what the operator
would notice: the map's marks, where the station's rotor ends up, what the page says."""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from playwright.sync_api import Browser, expect

from bridge.core import geo
from bridge.remote.run import Remote
from bridge.remote.settings import RemoteSettings
from tests.support.console import web_section
from tests.support.mosquitto import Mosquitto, free_port
from tests.support.mqtt import Probe
from tests.support.rig import Rig, arrival_tol
from tests.support.waiting import slow_ms
from tests.web.conftest import (
    PRESETS,
    STATION_LOCATOR,
    angle_apart,
    click_map,
    open_console,
    wait_page_bearing,
)

TOL = arrival_tol("rotorez")
START_AZ = 100.0


@dataclass
class Station:
    rig: Rig
    remote: Remote
    url: str


@pytest.fixture(scope="module")
def station(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Station]:
    tmp: Path = tmp_path_factory.mktemp("remote-console")
    broker = Mosquitto(tmp).start()
    probe = Probe(broker.port)
    try:
        with Rig(tmp, broker, probe) as rig:
            rig.sections["station"] = {"locator": STATION_LOCATOR}
            rig.add("tower", "rotorez", emu={"start_az_deg": START_AZ}, presets=PRESETS)
            rig.start()
            rig.ready("tower", timeout_s=20)
            web = web_section()
            remote = Remote(
                RemoteSettings(
                    operator="DL1ABC",
                    mqtt={"host": "127.0.0.1", "port": broker.port, "base_topic": "rotor"},
                    endpoints=[{"rotator": "tower", "rotctld_port": free_port()}],
                    web=web,
                )
            )
            remote.start()
            try:
                yield Station(rig, remote, f"http://127.0.0.1:{web['port']}/")
            finally:
                remote.stop()
    finally:
        probe.close()
        broker.stop()


def test_the_remote_page_shows_the_station_map_and_turns_its_rotator(
    station: Station, browser: Browser
) -> None:
    rig = station.rig
    page = open_console(browser, station.url)
    errors: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    try:
        # the station's map: its locator at the centre, land drawn round it, its presets
        expect(page.locator("#map .station-label")).to_have_text(STATION_LOCATOR)
        expect(page.locator("#map .land-layer path").first).to_be_attached()
        expect(page.locator('#map .preset[data-preset="EU"] text')).to_have_text("EU")
        expect(page.locator("#state")).to_have_text("idle", timeout=slow_ms(15_000))
        wait_page_bearing(page, START_AZ, TOL)

        target = 200.0
        click_map(page, target, radius=0.4)  # a click: a place, the station's bearing to it
        expect(page.locator("#pointer")).to_contain_text("sent")
        rig.arrived("tower", target)
        wait_page_bearing(page, target, TOL)
        expect(page.locator("#state")).to_have_text("idle", timeout=slow_ms(10_000))

        page.locator('#map .preset[data-preset="EU"] text').click()  # a preset's tick
        rig.arrived("tower", PRESETS["EU"])
        wait_page_bearing(page, PRESETS["EU"], TOL)

        page.fill("#locator", "FN31pr")  # a locator: the path drawn, the target named
        page.press("#locator", "Enter")
        lat0, lon0 = geo.parse_locator(STATION_LOCATOR)
        path = geo.great_circle(lat0, lon0, *geo.parse_locator("FN31pr"))
        expect(page.locator("#target")).to_contain_text("FN31pr", timeout=slow_ms(10_000))
        rig.arrived("tower", path.short_path_deg)
        page.click("#path-long")  # the other way round, by the station's judge
        expect(page.locator("#path-long")).to_have_attribute("aria-pressed", "true")
        rig.arrived("tower", path.long_path_deg)
        assert angle_apart(path.long_path_deg, path.short_path_deg) > 90

        # the station's bridge goes: the page greys the rotator, no stale bearing
        rig.stop()
        expect(page.locator("#state")).to_have_text("offline", timeout=slow_ms(10_000))
        expect(page.locator("body")).to_have_class(re.compile(r"\brotor-down\b"))
        expect(page.locator("#bearing")).not_to_have_text(re.compile(r"\d"))
    finally:
        page.context.close()
    assert not errors, errors
