"""The console behind real reverse proxies: Debian's nginx and Caddy, each started by the test
as a process of its own (never the system's service) on a free loopback port, in front of a real
bridge under the path prefix ``/rotor/``, with the very block docs/console.md gives the user.

What a user behind a proxy relies on, each proved here: the page and everything it names load
under the prefix (its URLs are relative); a command posted through the proxy with the proxy's
address as its Origin, by IP or by a name, is accepted and turns the rotor (the bridge learns
that address from X-Forwarded-Host, and is addressed as 127.0.0.1 itself), while one from
another site's page is refused and moves nothing; the event stream reaches the page at once, not
when a proxy buffer fills; and in Chromium the page served through the proxy connects, shows
the bearing and turns the rotor with a click on the map. Framed as Home Assistant's Webpage card
frames it (its sandbox), from a dashboard of another origin, the console shows and obeys only
where ``frame_ancestors`` allows it.
"""

from __future__ import annotations

import http.client
import json
import math
import os
import re
import shutil
import subprocess
from abc import ABC, abstractmethod
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from playwright import sync_api

from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from tests.support import ROOT, free_port, wait_until
from tests.support.console import ConsoleClient, EventStream, web_section
from tests.support.mosquitto import listens
from tests.support.rig import Rig
from tests.support.waiting import slow, slow_ms

DOC = ROOT / "docs" / "console.md"
PREFIX = "/rotor/"
DOCUMENTED_BRIDGE = "127.0.0.1:8754"  # the bridge's default port, as the doc says
# a guard, not a measure: a proxy that buffers holds the first status (sent alone on connect;
# only 10 s pings of a few bytes follow while the rotor stands) far longer than this
FIRST_EVENT_S = 20.0
# what Home Assistant's Webpage card puts on its frame (its frontend, hui-iframe-card)
HA_SANDBOX = (
    "allow-forms allow-modals allow-popups allow-pointer-lock allow-same-origin allow-scripts"
)


def documented(fence: str) -> str:
    """The ``/rotor/`` block of docs/console.md fenced ``fence``: the test proves what users
    copy, on the bridge's port of the test."""
    blocks = re.findall(rf"^```{fence}\n(.*?)^```", DOC.read_text(), re.M | re.S)
    found = [block for block in blocks if "/rotor/" in block]
    assert len(found) == 1, f"docs/console.md should hold one ```{fence} block for /rotor/"
    assert DOCUMENTED_BRIDGE in found[0]
    return str(found[0])


def installed(name: str) -> str:
    found = shutil.which(name) or shutil.which(name, path="/usr/sbin:/sbin")
    if found is None:
        pytest.fail(
            f"{name} is not installed (Debian: apt-get install {name}; ./tests/run installs it): "
            "the reverse proxies docs/console.md shows users are tested for real"
        )
    return found


class Proxy(ABC):
    """A reverse proxy on a free loopback port, run as the user running the tests, everything
    it writes in ``folder``; the bridge's ``/rotor/`` block as docs/console.md gives it."""

    fence = ""

    def __init__(self, folder: Path, bridge_port: int, port: int | None = None) -> None:
        self.folder = folder
        self.port = port or free_port()
        self.hosts = ["127.0.0.1"]  # the addresses it listens on
        self.also = ""  # more of its server's configuration
        folder.mkdir()
        self.block = documented(self.fence).replace(DOCUMENTED_BRIDGE, f"127.0.0.1:{bridge_port}")
        self.log = folder / "stderr.log"
        self.process: subprocess.Popen[bytes] | None = None

    @abstractmethod
    def command(self) -> list[str]:
        """The proxy's command line, its configuration written into ``folder``."""

    def start(self) -> Proxy:
        env = {**os.environ, "XDG_CONFIG_HOME": str(self.folder), "XDG_DATA_HOME": str(self.folder)}
        with self.log.open("wb") as log:
            process = self.process = subprocess.Popen(
                self.command(), stdout=log, stderr=subprocess.STDOUT, env=env
            )
        up = wait_until(
            lambda: "up" if listens("127.0.0.1", self.port) else process.poll() is not None,
            10.0,
            f"{self.fence} to listen",
        )
        if up != "up":
            raise AssertionError(f"{self.fence} did not start:\n{self.log.read_text()}")
        return self

    def stop(self) -> None:
        if self.process is not None and self.process.poll() is None:
            self.process.terminate()
            self.process.wait(slow(10))

    @property
    def origin(self) -> str:
        return f"http://127.0.0.1:{self.port}"


class Nginx(Proxy):
    fence = "nginx"

    def command(self) -> list[str]:
        # root runs the workers as root too: nginx's default user could not enter pytest's tmp
        user = "user root;\n" if os.geteuid() == 0 else ""
        temp = "".join(
            f"    {kind}_temp_path {self.folder / kind};\n"
            for kind in ("client_body", "proxy", "fastcgi", "uwsgi", "scgi")
        )
        listen = "".join(f"        listen {host}:{self.port};\n" for host in self.hosts)
        conf = self.folder / "nginx.conf"
        conf.write_text(
            f"{user}worker_processes 1;\nevents {{ worker_connections 64; }}\n"
            f"http {{\n    access_log off;\n{temp}"
            f"    server {{\n{listen}{self.also}{self.block}    }}\n}}\n"
        )
        pid = self.folder / "nginx.pid"
        return [
            *(installed("nginx"), "-e", "stderr", "-p", str(self.folder), "-c", str(conf)),
            *("-g", f"daemon off; pid {pid}; error_log stderr;"),
        ]


class Caddy(Proxy):
    fence = "caddyfile"

    def command(self) -> list[str]:
        conf = self.folder / "Caddyfile"
        # no admin endpoint (its fixed port would collide between tests), no certificates
        conf.write_text(
            "{\n    admin off\n    auto_https off\n}\n"
            f"http://:{self.port} {{\n    bind 127.0.0.1\n{self.block}}}\n"
        )
        return [installed("caddy"), "run", "--adapter", "caddyfile", "--config", str(conf)]


@pytest.fixture(params=[Nginx, Caddy], ids=["nginx", "caddy"])
def proxied(
    request: pytest.FixtureRequest, rig: Rig, tmp_path: Path
) -> Iterator[tuple[Rig, Proxy]]:
    rig.sections["station"] = {"locator": "JO62qm"}
    # the proxy's name, as a user behind one names it (without a password the bridge answers
    # only to addresses and the names listed)
    web = rig.sections["web"] = web_section(host_names=["rotor.example.org"])
    rig.add("hf")
    rig.start()
    rig.ready("hf")
    proxy = request.param(tmp_path / "proxy", web["port"]).start()
    try:
        yield rig, proxy
    finally:
        proxy.stop()


def _client(proxy: Proxy) -> ConsoleClient:
    """A client of the proxy whose token came through it, as the page's does."""
    client = ConsoleClient(proxy.port)
    answer = client.post(PREFIX + "api/session", {}, token=False)
    assert answer.status == 200, answer
    client.token = answer.doc["token"]
    return client


def _command(client: ConsoleClient, origin: str, **doc: Any) -> int:
    headers = {
        "Content-Type": "application/json",
        "Origin": origin,
        "X-Rotor-Token": client.token or "",
    }
    body = json.dumps(doc).encode()
    return client.request("POST", PREFIX + "api/rotators/hf/command", body, headers).status


class ProxiedEvents(EventStream):
    """``api/events`` through the proxy (EventStream reads it; only the URL differs)."""

    def __init__(self, client: ConsoleClient, timeout_s: float) -> None:
        self.conn = http.client.HTTPConnection(client.host, client.port, timeout=slow(timeout_s))
        headers = {"X-Rotor-Token": client.token or ""}
        self.conn.request("GET", PREFIX + "api/events", headers=headers)
        self.resp = self.conn.getresponse()
        assert self.resp.status == 200, self.resp.status
        assert self.resp.getheader("Content-Type", "").startswith("text/event-stream")


def _names(text: str) -> set[str]:
    """The files a page or module names: src/href attributes and module imports."""
    found = re.findall(r"""(?:src|href)="([^"]+)"|from\s+'([^']+)'""", text)
    return {a or b for a, b in found if not (a or b).startswith("data:")}


def _click_bearing(map_: sync_api.Locator, page: sync_api.Page, bearing_deg: float) -> None:
    """A click on the map halfway out at ``bearing_deg`` (north up, clockwise)."""
    box = map_.bounding_box()
    assert box is not None
    radius = min(box["width"], box["height"]) / 2 * 0.5
    x = box["x"] + box["width"] / 2 + radius * math.sin(math.radians(bearing_deg))
    y = box["y"] + box["height"] / 2 - radius * math.cos(math.radians(bearing_deg))
    page.mouse.click(x, y)


def test_the_page_and_every_file_it_names_load_under_the_prefix(
    proxied: tuple[Rig, Proxy],
) -> None:
    _rig, proxy = proxied
    client = ConsoleClient(proxy.port)
    bare = client.request("GET", PREFIX.rstrip("/"))
    assert bare.status in (301, 302, 307, 308) and bare.headers["location"].endswith(PREFIX)
    page = client.request("GET", PREFIX)
    assert page.status == 200 and page.headers["content-type"].startswith("text/html")
    assert "script-src 'self'" in page.headers["content-security-policy"]
    seen, todo = set(), _names(page.doc.decode())
    assert todo, "the page names no script or style"
    while todo:
        name = todo.pop()
        assert not name.startswith(("/", "http:", "https:")), f"{name}: not relative"
        answer = client.request("GET", PREFIX + name.removeprefix("./"))
        assert answer.status == 200, f"{PREFIX}{name}: {answer.status}"
        seen.add(name)
        todo |= _names(answer.doc.decode()) - seen
    assert {"console.css", "console.js"} <= {name.removeprefix("./") for name in seen}
    hello = client.request("GET", PREFIX + "api/hello")
    assert hello.status == 200 and hello.doc["password"] is False


def test_a_command_from_the_proxys_page_turns_the_rotor_and_another_sites_is_refused(
    proxied: tuple[Rig, Proxy],
) -> None:
    rig, proxy = proxied
    client = _client(proxy)
    assert _command(client, "http://evil.example", command="target", az=200) == 403
    assert _command(client, "null", command="target", az=200) == 403  # a sandboxed page
    assert rig.emu.frames(*BEARING_OUTCOMES) == []
    assert _command(client, proxy.origin, command="target", az=200) == 200
    rig.arrived("hf", 200)
    # the proxy reached by a name: its Origin is the name, and X-Forwarded-Host says so
    named = "rotor.example.org:" + str(proxy.port)
    headers = {
        "Host": named,
        "Origin": f"http://{named}",
        "Content-Type": "application/json",
        "X-Rotor-Token": client.token or "",
    }
    body = b'{"command": "target", "az": 150}'
    answer = client.request("POST", PREFIX + "api/rotators/hf/command", body, headers)
    assert answer.status == 200, answer
    rig.arrived("hf", 150)
    # a name the user never listed, pointed at the proxy (DNS rebinding): refused
    rebound = "evil.example:" + str(proxy.port)
    headers.update({"Host": rebound, "Origin": f"http://{rebound}"})
    answer = client.request("POST", PREFIX + "api/rotators/hf/command", body, headers)
    assert answer.status == 403, answer


def test_the_event_stream_comes_through_at_once(proxied: tuple[Rig, Proxy]) -> None:
    _rig, proxy = proxied
    client = _client(proxy)
    stream = ProxiedEvents(client, FIRST_EVENT_S)
    try:
        name, data = stream.next()  # the newest status, sent on connect: nothing follows it
        assert name == "status" and data["rotator"] == "hf"
        assert data["status"]["state"] == "idle"
        assert _command(client, proxy.origin, command="target", az=90) == 200
        while not stream.next()[1]["status"]["moving"]:
            pass
    finally:
        stream.close()


def test_the_page_through_the_proxy_connects_and_a_click_turns_the_rotor(
    proxied: tuple[Rig, Proxy],
) -> None:
    rig, proxy = proxied
    with sync_api.sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path="/usr/bin/chromium")
        try:
            page = browser.new_page(viewport={"width": 1100, "height": 800})
            page.goto(proxy.origin + PREFIX)
            bearing = page.locator("#bearing")
            sync_api.expect(bearing).to_have_text(re.compile(r"\d"), timeout=slow_ms(10_000))
            _click_bearing(page.locator("#map"), page, 90)
            rig.arrived("hf", 90)
            sync_api.expect(bearing).to_have_text(re.compile(r"^(8[6-9]|9[0-4])"))
        finally:
            browser.close()


def test_in_a_webpage_card_the_console_works_where_frame_ancestors_allow_it(
    rig: Rig, tmp_path: Path
) -> None:
    """Home Assistant's Webpage card: a dashboard of another origin frames the proxied console.
    The dashboard named in frame_ancestors shows it and drives it; another one gets nothing."""
    port = free_port()
    dashboard, stranger = f"http://127.0.0.2:{port}", f"http://127.0.0.3:{port}"
    rig.sections["station"] = {"locator": "JO62qm"}
    web = rig.sections["web"] = web_section(frame_ancestors=[dashboard])
    rig.add("hf")
    rig.start()
    rig.ready("hf")
    www = tmp_path / "www"
    www.mkdir()
    console = f"http://127.0.0.1:{port}{PREFIX}"
    (www / "card.html").write_text(
        f'<!doctype html><title>dashboard</title><iframe src="{console}" sandbox="{HA_SANDBOX}" '
        'width="1000" height="700"></iframe>'
    )
    nginx = Nginx(tmp_path / "proxy", web["port"], port)
    nginx.hosts = ["127.0.0.1", "127.0.0.2", "127.0.0.3"]
    nginx.also = f"        location = /card.html {{ root {www}; }}\n"
    nginx.start()
    try:
        with sync_api.sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path="/usr/bin/chromium")
            try:
                page = browser.new_page(viewport={"width": 1100, "height": 800})
                page.goto(stranger + "/card.html")
                sync_api.expect(page.locator("iframe")).to_be_attached()
                frame = page.frame_locator("iframe")
                page.wait_for_load_state("load")
                assert frame.locator("#bearing").count() == 0  # refused: the frame is empty
                page.goto(dashboard + "/card.html")
                frame = page.frame_locator("iframe")
                bearing = frame.locator("#bearing")
                sync_api.expect(bearing).to_have_text(re.compile(r"\d"), timeout=slow_ms(10_000))
                _click_bearing(frame.locator("#map"), page, 90)
                rig.arrived("hf", 90)
            finally:
                browser.close()
    finally:
        nginx.stop()
