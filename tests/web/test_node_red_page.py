"""The Node-RED example's web page (deploy/node-red/rotor-flow.json) as its user sees it: the
flow's own functions run in Node.js as function nodes run them (the MQTT messages to the page,
the ``hello`` a page opened later sends), and the page itself in Chromium, its websocket to
Node-RED stood in for and fed what the flow sends it."""

from __future__ import annotations

import json
import subprocess
from collections.abc import Iterator
from contextlib import contextmanager

from playwright.sync_api import Browser, Page

from tests.support.waiting import slow
from tests.test_deploy import FLOW, _node_js, _relay, _relay_outputs

# the page's websocket to Node-RED, stood in for: the page's own code talks to it as to one
# that is open; the test hands it the flow's messages
FAKE_SOCKET = """
window.__sockets = [];
window.WebSocket = class {
    constructor(url) {
        this.url = url;
        this.readyState = 0;
        window.__sockets.push(this);
        setTimeout(() => { this.readyState = 1; if (this.onopen) { this.onopen(); } }, 0);
    }
    send(data) {}
    close() {}
};
window.WebSocket.OPEN = 1;
"""

URL = "http://node-red.invalid/rotor"  # (never asked: the test answers it)
HTML = "text/html; charset=utf-8"

# each MQTT message through "to the web page", then a page's hello through the relay, with one
# flow context, as Node-RED runs them
HARNESS = """
const job = JSON.parse(require("fs").readFileSync(0, "utf8"));
const store = {};
const node = { warn: () => {}, error: () => {} };
const flow = { get: (k) => store[k], set: (k, v) => { store[k] = v; } };
const toPage = new Function("msg", "node", "flow", job.toPage);
const relay = new Function("msg", "node", "flow", job.relay);
const sent = job.mqtt.map((m) => toPage({ topic: m[0], payload: m[1] }, node, flow).payload);
const out = relay({ payload: JSON.stringify({ cmd: "hello" }), _session: { id: "s" } }, node, flow);
const hello = out[job.reply].map((m) => m.payload);
process.stdout.write(JSON.stringify({ sent: sent, hello: hello }));
"""


def through_the_flow(mqtt: list[tuple[str, object]]) -> tuple[list[str], list[str]]:
    """What the flow sends the open pages for each MQTT message (topic, payload as its mqtt in
    nodes give it: text, or the parsed document where the node reads JSON), and what it then
    answers a page opened later."""
    flow = json.loads(FLOW.read_text(encoding="utf-8"))
    (to_page,) = [n for n in flow if n["type"] == "function" and n["name"] == "to the web page"]
    relay = _relay(flow)
    job = {
        "toPage": to_page["func"],
        "relay": relay["func"],
        "reply": _relay_outputs(relay)["reply"],
        "mqtt": mqtt,
    }
    proc = subprocess.run(
        [_node_js(), "-e", HARNESS],
        input=json.dumps(job),
        capture_output=True,
        text=True,
        timeout=slow(30),
    )
    assert proc.returncode == 0, proc.stderr
    done = json.loads(proc.stdout)
    return done["sent"], done["hello"]


@contextmanager
def opened(browser: Browser) -> Iterator[Page]:
    """The page as Node-RED serves it, connected (to the stand-in)."""
    flow = json.loads(FLOW.read_text(encoding="utf-8"))
    (template,) = [n for n in flow if n["type"] == "template"]
    page = browser.new_page()
    try:
        page.add_init_script(FAKE_SOCKET)
        page.route(URL, lambda route: route.fulfill(body=template["template"], content_type=HTML))
        page.goto(URL)
        page.wait_for_function("window.__sockets.length === 1 && !!window.__sockets[0].onmessage")
        yield page
    finally:
        page.close()


def show(page: Page, texts: list[str]) -> None:
    page.evaluate("texts => texts.forEach(t => window.__sockets[0].onmessage({ data: t }))", texts)


def offers_tracking(page: Page) -> bool:
    return bool(page.locator("#track-box").is_visible())


def test_tracking_deleted_by_the_bridge_is_offered_no_more(browser: Browser) -> None:
    """A rotator that could track left ``rotor/tracking`` retained; started without
    ``[station]`` the bridge deletes it (interfaces/mqtt/stale.py rule 5), which Node-RED hands
    on as an empty payload. The page offered Sun, Moon and a satellite still (it took the empty
    text for something tracked), and so did every page opened later (the flow kept it): each
    refused by the bridge."""
    before = [("rotor/bearing", "120"), ("rotor/tracking", "off")]
    sent, _ = through_the_flow(before)
    after, hello = through_the_flow([*before, ("rotor/tracking", "")])
    with opened(browser) as page:
        show(page, sent)
        assert offers_tracking(page)
        assert page.locator("#tracking").text_content() == "tracking off"
        show(page, after[len(sent) :])
        assert not offers_tracking(page)
        assert not page.locator("#tracking").is_visible()
    with opened(browser) as later:  # opened after the deletion: it asks the flow (hello)
        show(later, hello)
        assert later.locator("#bearing").text_content() == "120\u00b0"
        assert not offers_tracking(later)


def test_a_deleted_state_shows_as_not_known(browser: Browser) -> None:
    """The topics of a rotator taken out of the configuration are deleted at the bridge's next
    start (interfaces/mqtt/stale.py rule 1): a page still watching it shows them not known,
    as before anything came, not a blank or ``null``."""
    before = [("rotor/state", "idle"), ("rotor/availability", "online")]
    sent, _ = through_the_flow(before)
    after, _ = through_the_flow([*before, ("rotor/state", ""), ("rotor/availability", "")])
    with opened(browser) as page:
        show(page, sent)
        assert page.locator("#state").text_content() == "idle"
        assert page.locator("#availability").text_content() == "rotator online"
        show(page, after[len(sent) :])
        assert page.locator("#state").text_content() == "?"
        assert page.locator("#availability").text_content() == "rotator ?"


def test_stale_elements_or_elements_after_the_clock_are_shown_beside_the_pass(
    browser: Browser,
) -> None:
    """session/tracking.py rule 11: elements older than two weeks (a TLE file no cron job
    refreshes any more), or dated weeks after the bridge's clock (a clock that runs behind),
    were said only in the bridge's log, or not at all; the page says it under the pass."""
    block = {
        "body": "AO-7",
        "phase": "waiting",
        "azimuth": 10.0,
        "elevation": -5.0,
        "aos": "2026-03-01T10:00:00.000+00:00",
        "los": "2026-03-01T10:10:00.000+00:00",
        "flip": False,
    }
    fresh = {**block, "elements_epoch": "2026-02-27T06:00:00.000+00:00", "elements_stale": False}
    stale = {**fresh, "elements_epoch": "2025-11-01T06:00:00.000+00:00", "elements_stale": True}
    ahead = {**fresh, "elements_epoch": "2026-04-20T06:00:00.000+00:00", "elements_ahead": True}
    docs = (fresh, stale, ahead)
    sent, _ = through_the_flow([("rotor/status", {"tracking": doc}) for doc in docs])
    with opened(browser) as page:
        show(page, sent[:1])
        assert "AOS" in (page.locator("#track-info").text_content() or "")
        assert "elements of" not in (page.locator("#track-info").text_content() or "")
        show(page, sent[1:2])
        shown = page.locator("#track-info").text_content() or ""
        assert "elements of 2025-11-01: stale, is the TLE file refreshed?" in shown, shown
        assert "clock" not in shown, shown
        show(page, sent[2:])
        shown = page.locator("#track-info").text_content() or ""
        assert "elements of 2026-04-20, after the bridge's clock: is its clock set?" in shown
        assert "stale" not in shown, shown
