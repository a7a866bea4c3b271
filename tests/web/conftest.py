"""The operator console in a real browser: Debian's Chromium (driven by Playwright) against a real
bridge process, its emulated Rotor-EZ on a pty and a real mosquitto, one of each per test module.

Rules:
1. The bridge is its own process (``Rig.start_process``) so a test can stop it and start it
   again on the same port, as a user's bridge goes away and comes back.
2. Each test gets a fresh page (``console_page``): loaded, live, the rotator idle. After it, the
   rotator is unlocked and stopped through the plain HTTP client, so no test inherits another's
   lock or motion; the next page waits until it is idle again.
3. A test waits with Playwright's expect/wait_for_function and the emulator's wait_for, never
   with a sleep.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from playwright.sync_api import Browser, Page, expect, sync_playwright

from tests.support.console import ConsoleClient, web_section
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt import Probe
from tests.support.rig import Rig
from tests.support.waiting import slow, slow_ms

CHROMIUM = "/usr/bin/chromium"
STATION_LOCATOR = "JO62qm"
KEEP_OUT = (250.0, 290.0)
PRESETS = {"EU": 45, "W6": 320}
PARK_AZ = 180.0
START_AZ = 100.0
VIEWBOX_HALF = 1.1  # #map's viewBox runs -1.1..1.1: the rim (radius 1) leaves room for labels
# every expect() without a timeout of its own waits Playwright's 5 s, scaled (waiting.py rule 1)
expect.set_options(timeout=slow_ms(5_000))


@dataclass
class ConsoleBridge:
    rig: Rig
    port: int

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.port}/"

    def client(self) -> ConsoleClient:
        """A plain HTTP client with its own token (the bridge's restart voids old ones)."""
        client = ConsoleClient(self.port)
        client.session()
        return client

    def calm(self) -> None:
        """Rule 2: unlocked and stopped, whatever the test left."""
        if self.rig.bridge is None or not self.rig.bridge.alive():
            return
        client = self.client()
        assert client.command("hf", command="lock", on=False).status == 200
        assert client.command("hf", command="stop").status == 200


PASSWORD = "correct horse battery"  # the console's password where a test gives it one


@pytest.fixture
def guarded(rig: Rig, tmp_path: Path) -> Iterator[tuple[Rig, ConsoleClient]]:
    """A console with a password, as one on the LAN has, and one rotator, ``hf``."""
    secret = tmp_path / "web-password"
    secret.write_text(PASSWORD + "\n")
    secret.chmod(0o600)
    web = rig.sections["web"] = web_section(password_file=str(secret))
    rig.add("hf")
    rig.start()
    rig.ready("hf")
    yield rig, ConsoleClient(web["port"])


@pytest.fixture(scope="module")
def console_bridge(tmp_path_factory: pytest.TempPathFactory) -> Iterator[ConsoleBridge]:
    tmp: Path = tmp_path_factory.mktemp("console")
    broker = Mosquitto(tmp).start()
    probe = Probe(broker.port)
    try:
        with Rig(tmp, broker, probe) as rig:
            rig.sections["station"] = {"locator": STATION_LOCATOR}
            web = rig.sections["web"] = web_section()
            rig.add(
                "hf",
                "rotorez",
                emu={"start_az_deg": START_AZ},
                keep_out=[list(KEEP_OUT)],
                presets=PRESETS,
                park_az_deg=PARK_AZ,
                # the rig's 1 s is for the tests of silence; here a loaded host that holds the
                # emulated controller (in this process, beside Playwright) a second took it for
                # silent: a target waiting out the brake was dropped ("target dropped:
                # controller not answering") or a command refused as offline, and the page
                # kept showing the target before it (the likely cause of a CI run at load 23
                # where "path" never showed long)
                silence_timeout_s=slow(3.0),
            )
            rig.start_process()
            rig.ready("hf", timeout_s=20)
            yield ConsoleBridge(rig, web["port"])
    finally:
        probe.close()
        broker.stop()


@pytest.fixture(scope="module")
def browser() -> Iterator[Browser]:
    with sync_playwright() as pw:
        chromium = pw.chromium.launch(executable_path=CHROMIUM, headless=True)
        try:
            yield chromium
        finally:
            chromium.close()


def open_console(browser: Browser, url: str, width: int = 1100, height: int = 800) -> Page:
    """A new page on the console, live, the rotator's bearing shown."""
    page = browser.new_context(viewport={"width": width, "height": height}).new_page()
    page.goto(url)
    expect(page.locator("#connection")).to_have_text("live", timeout=slow_ms(15_000))
    expect(page.locator("#bearing")).to_have_text(re.compile(r"\d"))
    return page


@pytest.fixture
def console_page(console_bridge: ConsoleBridge, browser: Browser) -> Iterator[Page]:
    page = open_console(browser, console_bridge.url)
    errors: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    expect(page.locator("#state")).to_have_text("idle", timeout=slow_ms(15_000))
    try:
        yield page
    finally:
        page.context.close()
        console_bridge.calm()
    assert not errors, errors


def map_point(page: Page, bearing_deg: float, radius: float) -> dict[str, float]:
    """The pixel of #map (from its top left corner) at a bearing and a radius (1 = the rim)
    from the station: the centre of its box plus r * (sin b, -cos b)."""
    box = page.locator("#map").bounding_box()
    assert box is not None
    half = box["width"] / 2
    r = radius * half / VIEWBOX_HALF
    b = math.radians(bearing_deg)
    return {"x": half + r * math.sin(b), "y": box["height"] / 2 - r * math.cos(b)}


def click_map(page: Page, bearing_deg: float, radius: float = 0.5, shift: bool = False) -> None:
    where = map_point(page, bearing_deg, radius)
    page.locator("#map").click(position=where, modifiers=["Shift"] if shift else [])


def angle_apart(a: float, b: float) -> float:
    return abs((a - b + 180.0) % 360.0 - 180.0)


def wait_page_bearing(
    page: Page, bearing_deg: float, tol_deg: float, timeout_ms: int = 20_000
) -> None:
    """Until #bearing shows a bearing within tol_deg of bearing_deg."""
    page.wait_for_function(
        """([want, tol]) => {
          const v = parseFloat(document.querySelector('#bearing').textContent);
          return Number.isFinite(v) && Math.abs(((v - want + 540) % 360) - 180) <= tol;
        }""",
        arg=[bearing_deg, tol_deg],
        timeout=slow_ms(timeout_ms),
    )


def page_bearing(page: Page) -> float:
    text = page.locator("#bearing").text_content() or ""
    return float(text.rstrip("\u00b0"))
