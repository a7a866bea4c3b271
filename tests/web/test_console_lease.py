"""The control lease as the console shows it, in Debian's Chromium against a real bridge: while
an operator holds the rotator the page says who and until when, a click on the map is refused
and the page names the holder; once released, the line goes and a click turns the rotor."""

from __future__ import annotations

import json
import re

from playwright.sync_api import Page, expect

from tests.support.rig import arrival_tol
from tests.web.conftest import ConsoleBridge, angle_apart, click_map, wait_page_bearing

TOL = arrival_tol("rotorez")


def test_the_page_shows_the_holder_and_a_click_is_refused_naming_them(
    console_bridge: ConsoleBridge, console_page: Page
) -> None:
    page, rig = console_page, console_bridge.rig
    claim = {"operator": "DL1ABC", "minutes": 30}
    rig.probe.publish("rotor/control/claim", json.dumps(claim))
    held = rig.probe.wait_for("rotor/control", lambda m: json.loads(m.text)["holder"] == "DL1ABC")
    until = json.loads(held.text)["until"][11:16]  # HH:MM of the ISO time, UTC
    expect(page.locator("#control")).to_have_text(f"DL1ABC until {until} UTC")
    before = rig.emu.state()
    target = 200.0 if angle_apart(200.0, before.az_deg) >= 90 else 20.0
    click_map(page, target, radius=0.4)
    expect(page.locator("#message")).to_contain_text(f"DL1ABC holds the rotator until {until}")
    after = rig.emu.state()
    assert not after.is_moving and after.az_deg == before.az_deg
    rig.probe.publish("rotor/control/release", "")
    expect(page.locator("#control")).to_be_hidden()
    click_map(page, target, radius=0.4)
    rig.arrived("hf", target)
    wait_page_bearing(page, target, TOL)
    expect(page.locator("#source")).to_have_text(re.compile(r"^web"))
