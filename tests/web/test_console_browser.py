"""The operator console as an operator uses it, in Debian's Chromium against a real bridge: a
click on the map turns the rotor there, STOP (button, Escape, Space) stops it mid-turn, the lock
and a keep-out sector refuse a click and the page says why, presets and a locator's path are
drawn, the page shows the bridge going away and coming back; without a station the map is a dial
that says what [station] adds, and with a password the page asks for it. What is judged is what
the user would notice: where the emulated rotor ends up, and the text and marks on the page."""

from __future__ import annotations

import json
import math
import os
import re
import signal
import time
from pathlib import Path
from typing import Any

import pytest
from playwright.sync_api import (
    APIResponse,
    Browser,
    Page,
    Request,
    Route,
    WebSocketRoute,
    expect,
)

from bridge.core import geo
from bridge.interfaces.web.commands import MAX_AGE_S, feed_clock
from bridge.interfaces.web.projection import RIM_KM
from tests.support import wait_until
from tests.support.console import web_section
from tests.support.rig import Rig, arrival_tol
from tests.support.sky import synthetic_tle
from tests.support.waiting import slow, slow_ms
from tests.web.conftest import (
    KEEP_OUT,
    PRESETS,
    STATION_LOCATOR,
    ConsoleBridge,
    angle_apart,
    click_map,
    open_console,
    page_bearing,
    wait_page_bearing,
)

TOL = arrival_tol("rotorez")
OFFLINE = re.compile(r"\boffline\b")


def _svg_angle(page: Page, selector: str) -> tuple[float, float]:
    """(bearing, radius) of the centre of an element of #map, in the map's own units."""
    doc = page.evaluate(
        """(sel) => {
          const b = document.querySelector(sel).getBBox();
          return [b.x + b.width / 2, b.y + b.height / 2];
        }""",
        selector,
    )
    x, y = doc
    return math.degrees(math.atan2(x, -y)) % 360.0, math.hypot(x, y)


CHOICES = (20.0, 130.0, 200.0, 330.0)  # outside the keep-out sector


def _far_from(az: float) -> float:
    """A bearing at least 90 degrees from az (a long way to turn)."""
    return next(c for c in CHOICES if angle_apart(c, az) >= 90.0)


def _farthest(az: float) -> float:
    """The bearing the longest turn away: a Rotor-EZ turns within 0..360, never across north,
    so the rotor is surely still turning when STOP comes."""
    return max(CHOICES, key=lambda c: abs(c - az % 360.0))


def test_a_click_on_the_map_turns_the_rotator_to_that_bearing(
    console_bridge: ConsoleBridge, console_page: Page
) -> None:
    page, rig = console_page, console_bridge.rig
    target = _far_from(rig.emu.state().az_deg)
    click_map(page, target, radius=0.4)
    expect(page.locator("#pointer")).to_contain_text("sent")
    rig.arrived("hf", target)
    wait_page_bearing(page, target, TOL)
    expect(page.locator("#state")).to_have_text("idle", timeout=slow_ms(10_000))
    expect(page.locator("#map .beam")).to_be_visible()
    # rotor health counted the move: its line shows the numbers, unmarked while all is well
    health = page.locator("#health-info")
    expect(health).to_have_text(re.compile(r"^cw .+ · ccw .+ · [1-9]\d* moves, \d+ stalls"))
    expect(page.locator("#health-label")).to_be_visible()
    expect(health).not_to_have_class(re.compile(r"\bwarn\b"))


@pytest.mark.parametrize("how", ["button", "escape", "space on a focused park button"])
def test_stop_stops_a_turning_rotator_far_from_its_target(
    console_bridge: ConsoleBridge, console_page: Page, how: str
) -> None:
    page, rig = console_page, console_bridge.rig
    sent: list[dict[str, Any]] = []

    def record(request: Request) -> None:
        if request.method == "POST" and request.url.endswith("/command"):
            sent.append(json.loads(request.post_data or "{}"))

    page.on("request", record)
    start = rig.emu.state().az_deg
    target = _farthest(start)
    click_map(page, target)
    rig.emu.wait_for(lambda s: s.is_moving and angle_apart(s.az_deg, start) > 15.0, 10)
    expect(page.locator("#state")).to_have_text("moving")
    if how == "button":
        page.click("#stop")
    elif how == "escape":
        page.keyboard.press("Escape")
    else:
        page.focus("#park")
        page.keyboard.press("Space")
    stopped = rig.emu.wait_for(lambda s: not s.is_moving and not s.in_brake_delay, 10)
    assert angle_apart(stopped.az_deg, target) > 30.0, stopped
    expect(page.locator("#state")).to_have_text("idle", timeout=slow_ms(10_000))
    wait_page_bearing(page, stopped.az_deg, TOL)
    assert rig.emu.state().az_deg == stopped.az_deg  # it stays where it stopped
    assert [c["command"] for c in sent] == ["toward", "stop"]  # Space never parked


def test_stop_reaches_the_bridge_with_eight_tabs_open_in_one_browser(
    console_bridge: ConsoleBridge, browser: Browser
) -> None:
    """A browser keeps six HTTP connections per host: a feed that held one per tab left a
    sixth tab's STOP waiting for ever. The feed is a WebSocket, counted apart."""
    rig = console_bridge.rig
    context = browser.new_context(viewport={"width": 900, "height": 700})
    try:
        pages = [context.new_page() for _ in range(8)]
        for page in pages:
            page.goto(console_bridge.url)
        for page in pages:
            expect(page.locator("#connection")).to_have_text("live", timeout=slow_ms(15_000))
        start = rig.emu.state().az_deg
        target = _farthest(start)
        assert console_bridge.client().command("hf", command="target", az=target).status == 200
        rig.emu.wait_for(lambda s: s.is_moving and angle_apart(s.az_deg, start) > 15.0, 10)
        pages[-1].click("#stop")
        stopped = rig.emu.wait_for(lambda s: not s.is_moving and not s.in_brake_delay, 10)
        assert angle_apart(stopped.az_deg, target) > 30.0, stopped
    finally:
        context.close()


def test_stop_stays_on_screen_on_a_phone(console_bridge: ConsoleBridge, browser: Browser) -> None:
    page = open_console(browser, console_bridge.url, width=390, height=700)
    try:
        expect(page.locator("#stop")).to_be_in_viewport(ratio=1)
        page.locator("#locator").scroll_into_view_if_needed()  # far down the panel
        assert page.evaluate("window.scrollY") > 100
        expect(page.locator("#stop")).to_be_in_viewport(ratio=1)
    finally:
        page.context.close()


def test_the_lock_refuses_a_click_and_the_page_says_why(
    console_bridge: ConsoleBridge, console_page: Page
) -> None:
    page, rig = console_page, console_bridge.rig
    page.click("#lock")
    expect(page.locator("#lock")).to_have_attribute("aria-pressed", "true")
    before = rig.emu.state()
    click_map(page, _far_from(before.az_deg))
    expect(page.locator("#message")).to_contain_text("locked")
    after = rig.emu.state()
    assert not after.is_moving and after.az_deg == before.az_deg
    page.click("#lock")  # offers Release (console.js rule 10), which releases it
    page.click("#unlock")
    expect(page.locator("#lock")).to_have_attribute("aria-pressed", "false")


def test_a_keep_out_sector_is_drawn_and_a_click_in_it_is_refused(
    console_bridge: ConsoleBridge, console_page: Page
) -> None:
    page, rig = console_page, console_bridge.rig
    sectors = page.locator("#map .keepout")
    expect(sectors).to_have_count(1)
    expect(sectors).to_have_attribute("data-from", f"{KEEP_OUT[0]:g}")
    expect(sectors).to_have_attribute("data-to", f"{KEEP_OUT[1]:g}")
    middle, _ = _svg_angle(page, "#map .keepout")
    assert angle_apart(middle, sum(KEEP_OUT) / 2) < 1.0
    before = rig.emu.state()
    click_map(page, sum(KEEP_OUT) / 2, radius=0.6)
    expect(page.locator("#message")).to_contain_text("keep-out")
    after = rig.emu.state()
    assert not after.is_moving and after.az_deg == before.az_deg


def test_presets_are_drawn_and_a_locator_target_draws_its_path(
    console_bridge: ConsoleBridge, console_page: Page
) -> None:
    page, rig = console_page, console_bridge.rig
    for name, az in PRESETS.items():
        label = page.locator(f'#map .preset[data-preset="{name}"] text')
        expect(label).to_have_text(name)
        bearing, _ = _svg_angle(page, f'#map .preset[data-preset="{name}"] text')
        assert angle_apart(bearing, az) < 1.0, (name, bearing)
    page.locator('#map .preset[data-preset="EU"] text').click()  # a preset's tick sends it
    rig.arrived("hf", PRESETS["EU"])
    wait_page_bearing(page, PRESETS["EU"], TOL)

    page.fill("#locator", "FN31pr")
    page.press("#locator", "Enter")
    expect(page.locator("#map .gc-path")).to_be_visible()
    expect(page.locator("#map .target-point")).to_be_visible()
    expect(page.locator("#target")).to_contain_text("FN31pr")
    lat0, lon0 = geo.parse_locator(STATION_LOCATOR)
    path = geo.great_circle(lat0, lon0, *geo.parse_locator("FN31pr"))
    bearing, radius = _svg_angle(page, "#map .target-point")
    assert angle_apart(bearing, path.short_path_deg) < 0.5
    assert abs(radius - path.distance_km / RIM_KM) < 0.005
    expect(page.locator("#map .gc-label")).to_contain_text("km")
    page.click("#path-long")
    expect(page.locator("#map .gc-path")).to_have_attribute("data-path", "long")
    expect(page.locator("#path-long")).to_have_attribute("aria-pressed", "true")


def test_the_page_shows_the_bridge_going_away_and_coming_back(
    console_bridge: ConsoleBridge, console_page: Page
) -> None:
    page, rig = console_page, console_bridge.rig
    assert rig.bridge is not None
    rig.bridge.terminate()
    expect(page.locator("body")).to_have_class(OFFLINE, timeout=slow_ms(5_000))
    expect(page.locator("#connection")).to_contain_text("connection lost")
    restarted = rig.probe.caught_up()
    rig.start_process()
    rig.ready("hf", timeout_s=20, after=restarted)
    expect(page.locator("body")).not_to_have_class(OFFLINE, timeout=slow_ms(15_000))
    expect(page.locator("#connection")).to_have_text("live")
    # live again, on a new token: a click turns the rotor and #bearing follows it
    target = _far_from(page_bearing(page))
    click_map(page, target)
    rig.arrived("hf", target)
    wait_page_bearing(page, target, TOL)


def test_without_a_station_the_map_is_a_dial_that_says_what_a_station_adds(
    rig: Rig, browser: Browser
) -> None:
    web = rig.sections["web"] = web_section()
    rig.add("hf", "rotorez", emu={"start_az_deg": 100})
    rig.start_process()  # its own process: Playwright's sync API holds this thread's event loop
    rig.ready("hf", timeout_s=20)
    page = open_console(browser, f"http://127.0.0.1:{web['port']}/")
    try:
        expect(page.locator("#no-station")).to_be_visible()
        expect(page.locator("#no-station")).to_contain_text("[station]")
        expect(page.locator("#map .land")).to_have_count(0)
        expect(page.locator("#locator")).to_be_hidden()
        click_map(page, 200.0, radius=0.7)  # a dial: the click's angle is the bearing
        rig.arrived("hf", 200.0)
        wait_page_bearing(page, 200.0, TOL)
    finally:
        page.context.close()


def test_with_a_password_the_page_asks_for_it_and_says_when_it_is_wrong(
    rig: Rig, browser: Browser, tmp_path: Path
) -> None:
    secret = tmp_path / "web-password"
    secret.write_text("correct horse battery\n")
    os.chmod(secret, 0o600)
    web = rig.sections["web"] = web_section(password_file=str(secret))
    rig.add("hf", "rotorez")
    rig.start_process()
    rig.ready("hf", timeout_s=20)
    page = browser.new_context().new_page()
    try:
        page.goto(f"http://127.0.0.1:{web['port']}/")
        expect(page.locator("#login")).to_be_visible()
        expect(page.locator("#connection")).to_have_text("log in to control the rotators")
        # the header stays one line: its note was drawn as a second login card above the card
        bar, card = page.locator("header.bar").bounding_box(), page.locator("#login").bounding_box()
        assert bar is not None and card is not None and bar["height"] < card["height"] / 2, bar
        expect(page.locator("#stop")).to_be_hidden()  # nothing to press before the login
        page.fill("#password", "wrong horse battery")
        page.press("#password", "Enter")
        expect(page.locator("#login-error")).to_have_text("wrong password")
        page.fill("#password", "correct horse battery")
        page.click("#login-go")
        expect(page.locator("#login")).to_be_hidden()
        expect(page.locator("#connection")).to_have_text("live")
        expect(page.locator("#bearing")).to_have_text(re.compile(r"\d"))
        expect(page.locator("#stop")).to_be_visible()
    finally:
        page.context.close()


def test_a_track_choice_that_could_not_be_sent_is_not_shown_as_chosen(
    console_bridge: ConsoleBridge, console_page: Page
) -> None:
    """The user picks the sun in *Track* while the bridge cannot be reached: nothing was sent,
    so the select goes back to what the bridge tracks (nothing), as it does for a refusal; it
    kept showing "Sun" beside a status that tracks nothing."""
    page = console_page
    expect(page.locator("#track-row")).to_be_visible()
    expect(page.locator("#track")).to_have_value("off")
    page.route("**/command", lambda route: route.abort())
    try:
        page.select_option("#track", "sun")
        expect(page.locator("#message")).to_contain_text("nothing was sent")
        expect(page.locator("#track")).to_have_value("off")
    finally:
        page.unroute("**/command")
    expect(page.locator("#tracking-info")).to_be_hidden()


def test_a_late_answer_to_an_older_click_does_not_hide_why_the_newer_one_was_refused(
    console_bridge: ConsoleBridge, console_page: Page
) -> None:
    """On a slow network the answer to a click comes after the next click's: the operator
    clicks a bearing (carried out, its answer slow), then a bearing in the keep-out sector
    (refused, the page says why). The first click's late "ok" wiped the refusal off the page
    and wrote "sent" for the first click under the map, so the page no longer said why the
    last click did nothing."""
    page, rig = console_page, console_bridge.rig
    held: list[tuple[Route, APIResponse]] = []

    def slow_first(route: Route) -> None:
        if held:
            route.continue_()
            return
        held.append((route, route.fetch()))  # carried out at once, its answer held back

    page.route("**/command", slow_first)
    try:
        first = _far_from(rig.emu.state().az_deg)
        click_map(page, first)
        expect(page.locator("#state")).to_have_text("moving")  # (the handler ran meanwhile)
        assert len(held) == 1
        expect(page.locator("#pointer")).to_contain_text("sending")  # no answer yet
        click_map(page, sum(KEEP_OUT) / 2, radius=0.6)
        expect(page.locator("#message")).to_contain_text("keep-out")
        expect(page.locator("#pointer")).to_contain_text("refused")
        route, answer = held[0]
        route.fulfill(response=answer)
        page.wait_for_function("() => window.rotorConsole.answered === 2")  # the late one read
        expect(page.locator("#message")).to_contain_text("keep-out")
        expect(page.locator("#pointer")).to_contain_text("refused")
    finally:
        page.unroute("**/command")


def test_a_refusal_said_again_after_a_command_went_through_is_shown_again(
    console_bridge: ConsoleBridge, console_page: Page
) -> None:
    """A click in the keep-out sector is refused and the page says why; the next click goes
    through and the message goes; a second click in the sector at once is refused again, and
    the page must say so again. The same refusal within 2 s was taken for the first one's
    copy (its error event) and not shown: the message line stayed empty under a refused click."""
    page, rig = console_page, console_bridge.rig
    message = page.locator("#message")
    click_map(page, sum(KEEP_OUT) / 2, radius=0.6)
    expect(message).to_contain_text("keep-out")
    click_map(page, _far_from(rig.emu.state().az_deg))
    expect(page.locator("#pointer")).to_contain_text("sent")
    expect(message).to_have_text("")
    click_map(page, sum(KEEP_OUT) / 2, radius=0.6)
    expect(page.locator("#pointer")).to_contain_text("refused")
    expect(message).to_contain_text("keep-out")


def test_a_stop_carried_by_the_live_feed_alone_is_not_said_to_be_unsent(
    console_bridge: ConsoleBridge, console_page: Page
) -> None:
    """The page sends STOP over its live feed as well as by a request: when the request fails
    (the bridge's connections full, a proxy refusing it) the feed's copy still stops the
    rotor, and the page must not tell the operator that nothing was sent."""
    page, rig = console_page, console_bridge.rig
    start = rig.emu.state().az_deg
    target = _farthest(start)
    click_map(page, target)
    rig.emu.wait_for(lambda s: s.is_moving and angle_apart(s.az_deg, start) > 15.0, 10)
    page.route("**/command", lambda route: route.abort())
    try:
        page.click("#stop")
        stopped = rig.emu.wait_for(lambda s: not s.is_moving and not s.in_brake_delay, 10)
        assert angle_apart(stopped.az_deg, target) > 30.0, stopped
        expect(page.locator("#message")).to_contain_text("live connection")
        expect(page.locator("#message")).not_to_contain_text("nothing was sent")
    finally:
        page.unroute("**/command")


def test_arrow_keys_on_the_track_select_track_nothing_until_enter(
    console_bridge: ConsoleBridge, console_page: Page
) -> None:
    """A keyboard user arrows through *Track* from "off" to "Moon": Chromium changes a closed
    select's choice at each key, and each change was a track command, so the sun was tracked
    on the way and the rotor turned toward it. The keys choose; Enter sends the choice; a
    choice left unsent goes back to what the bridge tracks when the select loses the focus."""
    page, rig = console_page, console_bridge.rig
    sent: list[dict[str, Any]] = []

    def record(request: Request) -> None:
        if request.method == "POST" and request.url.endswith("/command"):
            sent.append(json.loads(request.post_data or "{}"))

    page.on("request", record)
    select = page.locator("#track")
    expect(select).to_have_value("off")
    select.focus()
    page.keyboard.press("ArrowDown")
    page.keyboard.press("ArrowDown")
    expect(select).to_have_value("moon")
    expect(page.locator("#message")).to_contain_text("Enter tracks moon")
    page.locator("#nudge-cw").focus()  # the choice left unsent: back to what is tracked
    expect(select).to_have_value("off")
    expect(page.locator("#message")).to_have_text("")
    assert sent == []
    assert not rig.emu.state().is_moving
    expect(page.locator("#tracking-info")).to_be_hidden()
    select.focus()
    page.keyboard.press("ArrowDown")
    page.keyboard.press("ArrowDown")
    page.keyboard.press("Enter")
    page.wait_for_function("() => window.rotorConsole.answered === 1")
    assert [(c["command"], c["body"]) for c in sent] == [("track", "moon")]


def test_enter_held_on_the_lock_button_locks_once_and_stays_locked(
    console_bridge: ConsoleBridge, console_page: Page
) -> None:
    """Enter held a moment too long on the focused Lock button: Chromium repeats the key, and
    each repeat clicked the button again, which toggles, so the lock went ON, then OFF at the
    next repeat. A key held down is one press."""
    page = console_page
    sent: list[dict[str, Any]] = []

    def record(request: Request) -> None:
        if request.method == "POST" and request.url.endswith("/command"):
            sent.append(json.loads(request.post_data or "{}"))

    page.on("request", record)
    cdp = page.context.new_cdp_session(page)

    def enter(kind: str, repeat: bool = False) -> None:
        cdp.send(
            "Input.dispatchKeyEvent",
            {
                "type": kind,
                "key": "Enter",
                "code": "Enter",
                "windowsVirtualKeyCode": 13,
                "text": "" if kind == "keyUp" else "\r",
                "autoRepeat": repeat,
            },
        )

    lock = page.locator("#lock")
    expect(lock).to_have_text("Lock OFF")
    lock.focus()
    enter("keyDown")
    expect(lock).to_have_text("Lock ON")  # the press carried out; the key still down
    enter("keyDown", repeat=True)
    enter("keyDown", repeat=True)
    enter("keyDown", repeat=True)
    enter("keyUp")
    page.click("#stop")  # sent after whatever the repeats sent
    wait_until(lambda: any(c["command"] == "stop" for c in sent), slow(10))
    assert [(c["command"], c.get("on")) for c in sent] == [("lock", True), ("stop", None)]
    expect(lock).to_have_text("Lock ON")


def test_a_bridge_gone_silent_is_said_at_once_after_the_silence_not_a_minute_later(
    console_bridge: ConsoleBridge, browser: Browser
) -> None:
    """The bridge hangs (a stalled host, a network that drops packets without a word): no
    ping for 25 s and the page gives the live feed up. It closed the socket and waited for
    the close to be answered, which a silent bridge never does, and Chromium waits a minute
    for it: the page said "live" over the old bearing for 85 s. It is lost at once now."""
    rig = console_bridge.rig
    assert rig.bridge is not None
    context = browser.new_context(viewport={"width": 1100, "height": 800})
    page = context.new_page()
    page.clock.install()  # the page's timers: the 25 s of silence are fast-forwarded
    paused = False
    try:
        page.goto(console_bridge.url)
        expect(page.locator("#connection")).to_have_text("live", timeout=slow_ms(15_000))
        os.kill(rig.bridge.pid, signal.SIGSTOP)
        paused = True
        page.clock.fast_forward(26_000)
        expect(page.locator("#connection")).to_contain_text("connection lost")
        expect(page.locator("body")).to_have_class(OFFLINE)
        os.kill(rig.bridge.pid, signal.SIGCONT)
        paused = False
        expect(page.locator("#connection")).to_have_text("live", timeout=slow_ms(15_000))
    finally:
        if paused:
            os.kill(rig.bridge.pid, signal.SIGCONT)
        context.close()


def _posted(page: Page) -> list[dict[str, Any]]:
    """Every command the page posts, as it posted it (its body)."""
    sent: list[dict[str, Any]] = []

    def record(request: Request) -> None:
        if request.method == "POST" and request.url.endswith("/command"):
            sent.append(json.loads(request.post_data or "{}"))

    page.on("request", record)
    return sent


def test_a_click_held_up_on_a_bad_link_past_its_age_limit_turns_nothing(
    console_bridge: ConsoleBridge, console_page: Page
) -> None:
    """A phone on a bad mobile link: the operator clicks a bearing, the request is held up on
    the way for seconds, then delivered. Nothing came after it (no STOP, no newer click), so
    the bridge carried it out whenever it came. Each move carries its send time on the
    bridge's clock as the page reckons it from its live feed (commands.py rule 6): one older
    than MAX_AGE_S turns nothing, and the page says why."""
    page, rig = console_page, console_bridge.rig
    held: list[Route] = []
    page.route("**/command", lambda route: held.append(route))
    try:
        before = rig.emu.state()
        target = _far_from(before.az_deg)
        clicked = feed_clock()  # the bridge's steady clock (commands.py rule 6)
        click_map(page, target)
        wait_until(lambda: page.evaluate("1") == 1 and bool(held), slow(10))  # (evaluate: the
        # handler's turn to run) held up on the way until the click is too old
        wait_until(lambda: feed_clock() > clicked + MAX_AGE_S + 1.0, slow(20))
        held[0].continue_()
        message = page.locator("#message")
        expect(message).to_contain_text(re.compile(r"not carried out: sent \d+ s ago"))
        expect(page.locator("#pointer")).to_contain_text("refused")
    finally:
        page.unroute("**/command")
    after = rig.emu.state()
    assert not after.is_moving and after.az_deg == before.az_deg, (before, after)
    # its send time: the page's reckoning of the bridge's clock, never ahead of the truth
    sent = json.loads(held[0].request.post_data or "{}")["sent"]
    assert clicked - slow(1.0) <= sent <= feed_clock()
    click_map(page, target)  # the same click made now is carried out
    rig.arrived("hf", target)


def test_a_double_click_on_lock_locks_and_does_not_release_it(
    console_bridge: ConsoleBridge, console_page: Page
) -> None:
    """Lock toggled: a double click (the second click 300 ms after the first, the bridge's
    status in between) locked and released at once. A click on Lock while it is ON offers
    Release, usable only after a second: releasing is a deliberate act (console.js rule 10)."""
    page = console_page
    sent = _posted(page)
    lock, release = page.locator("#lock"), page.locator("#unlock")
    lock.click()
    expect(lock).to_have_attribute("aria-pressed", "true")
    lock.click()  # the double click's second
    expect(release).to_be_visible()
    expect(release).to_be_disabled()
    expect(release).to_be_enabled()  # a second later: anything the clicks sent has come
    assert [(c["command"], c.get("on")) for c in sent] == [("lock", True)]
    expect(lock).to_have_text("Lock ON")
    assert console_bridge.client().command("hf", command="target", az=10).status == 409
    release.click()
    expect(lock).to_have_attribute("aria-pressed", "false")
    expect(release).to_be_hidden()
    assert [(c["command"], c.get("on")) for c in sent] == [("lock", True), ("lock", False)]
    assert "sent" in sent[1] and "sent" not in sent[0]  # a lock ON goes unstamped, always


def test_stop_stays_usable_and_ungreyed_on_a_phone_while_the_live_feed_is_lost(
    console_bridge: ConsoleBridge, browser: Browser
) -> None:
    """Offline (the live feed lost, the bridge still reachable by POST) the whole console was
    greyed, STOP with it, as if it could not be used. STOP stays as it was, pinned where it
    is, and stops the rotor by its POST."""
    rig = console_bridge.rig
    feeds: list[WebSocketRoute] = []
    cut = False

    def feed(ws: WebSocketRoute) -> None:  # the page's live feed, passed on until it is cut
        if cut:
            return  # opened, never answered: no hello (its close would wait in this handler)
        feeds.append(ws)
        ws.connect_to_server()

    page = browser.new_context(viewport={"width": 390, "height": 700}).new_page()
    try:
        page.route_web_socket("**/api/live", feed)
        page.goto(console_bridge.url)
        expect(page.locator("#connection")).to_have_text("live", timeout=slow_ms(15_000))
        page.locator("#locator").scroll_into_view_if_needed()  # far down the panel
        start = rig.emu.state().az_deg
        target = _farthest(start)
        assert console_bridge.client().command("hf", command="target", az=target).status == 200
        rig.emu.wait_for(lambda s: s.is_moving and angle_apart(s.az_deg, start) > 15.0, 10)
        cut = True  # the mobile link loses the feed (and every reconnect); POSTs still pass
        feeds[-1].close()
        expect(page.locator("body")).to_have_class(OFFLINE)
        stop = page.locator("#stop")
        expect(stop).to_be_in_viewport(ratio=1)
        greyed = page.evaluate(
            """() => {
              const out = [];
              for (let e = document.querySelector('#stop'); e; e = e.parentElement) {
                const s = getComputedStyle(e);
                if (s.filter !== 'none' || s.opacity !== '1') out.push(e.id || e.className);
              }
              return out;
            }"""
        )
        assert greyed == [], greyed
        expect(page.locator(".controls")).to_have_css("opacity", "0.5")  # the rest is greyed
        stop.click()
        stopped = rig.emu.wait_for(lambda s: not s.is_moving and not s.in_brake_delay, 10)
        assert angle_apart(stopped.az_deg, target) > 30.0, stopped
    finally:
        page.context.close()


# the page's steady clock (performance.now) held back by window.sleptMs: what a phone's or a
# laptop's suspend does to it (Chromium's steady clock stands still while the system sleeps,
# on Linux, Android and macOS), while the bridge's clock and the wall clock go on
_SUSPENDABLE = """(() => {
  const real = performance.now.bind(performance);
  window.sleptMs = 0;
  Object.defineProperty(performance, 'now', { value: () => real() - window.sleptMs });
})();"""


def test_a_click_made_as_soon_as_the_page_wakes_from_sleep_turns_the_rotor(
    console_bridge: ConsoleBridge, browser: Browser
) -> None:
    """A phone put away a minute with the console open, then woken: the page's steady clock
    stood still while it slept, so its reckoning of the bridge's clock (live.js rule 3) was a
    minute behind, and every click until the next ping or reconnect was refused, 'not carried
    out: sent 60 s ago', a click just made. The page sees that its steady clock fell behind
    the wall clock since it last heard the bridge's, and hears the clock again before it
    stamps the move (live.js rule 3)."""
    rig = console_bridge.rig
    context = browser.new_context(viewport={"width": 1100, "height": 800})
    context.add_init_script(_SUSPENDABLE)
    page = context.new_page()
    try:
        page.goto(console_bridge.url)
        expect(page.locator("#connection")).to_have_text("live", timeout=slow_ms(15_000))
        expect(page.locator("#state")).to_have_text("idle", timeout=slow_ms(15_000))
        target = _far_from(rig.emu.state().az_deg)
        page.evaluate("window.sleptMs = 60000")  # woken after a minute asleep
        click_map(page, target)
        rig.arrived("hf", target)
        expect(page.locator("#message")).not_to_contain_text("not carried out")
    finally:
        context.close()


@pytest.mark.parametrize(
    ("days_after_clock", "said"),
    [(-60.0, ": stale"), (60.0, ", after the bridge's clock: is its clock set?")],
)
def test_a_satellite_tracked_by_stale_or_future_elements_is_said_so_beside_its_pass(
    console_bridge: ConsoleBridge, console_page: Page, days_after_clock: float, said: str
) -> None:
    """session/tracking.py rule 11: elements two months old (a TLE file no cron job refreshes
    any more) were said only in the bridge's log, where nobody at the radio looks, and
    elements dated two months after the bridge's clock (a station clock that runs behind)
    were flown without a word, every position for the wrong time; the page says either where
    it shows the pass."""
    page, rig = console_page, console_bridge.rig
    epoch = time.time() + days_after_clock * 86400  # (the bridge judges them on its own clock)
    line1, line2 = synthetic_tle("", epoch, inclination_deg=51.6, raan_deg=0, mean_anomaly_deg=0)
    rig.probe.publish(rig.topic("hf", "track"), json.dumps({"tle": ["ODDSAT", line1, line2]}))
    try:
        info = page.locator("#tracking-info")
        expect(info).to_contain_text("ODDSAT", timeout=slow_ms(20_000))
        day = time.strftime("%Y-%m-%d", time.gmtime(epoch))
        expect(info).to_contain_text(f"elements of {day}{said}", timeout=slow_ms(20_000))
    finally:
        rig.probe.publish(rig.topic("hf", "track"), "off")
        rig.probe.publish(rig.topic("hf", "stop"), "")
        expect(page.locator("#tracking-info")).to_be_hidden(timeout=slow_ms(10_000))
        rig.probe.wait_value(rig.topic("hf", "state"), "idle", slow(30))
