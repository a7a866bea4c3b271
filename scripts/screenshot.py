"""The README's pictures, each of a real bridge turning an emulated rotor.

Run it through ``scripts/screenshot`` (which installs what it needs): ``scripts/screenshot``
makes both, ``scripts/screenshot console`` or ``scripts/screenshot node-red`` one. Each starts
a private mosquitto, an emulated Rotor-EZ and the bridge as the user runs it (a configuration
with a station and presets), in a temporary folder, and removes them afterwards.

- ``console``: the bridge's own console (``[web]``) in Chromium at a desktop size, with a keep-out
  sector and presets toward real DX; the locator of New York is typed into the locator box, and
  the picture is taken while the rotor turns toward it, the great-circle path and distance drawn.
  Written to ``docs/images/console.png``.
- ``node-red``: the page of ``deploy/node-red/rotor-flow.json``, its websocket fed what the flow's
  "to the web page" function sends it: one ``{"kind", "value"}`` text per MQTT message, the kind
  being the topic's last part; a locator target sent on MQTT, the picture taken while the rotor
  turns. Written to ``docs/images/node-red-page.png``.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import paho.mqtt.client as mqtt
from playwright.sync_api import ViewportSize, sync_playwright

from tests.support.mosquitto import Mosquitto, free_port, listens

ROOT = Path(__file__).resolve().parent.parent
FLOW = ROOT / "deploy" / "node-red" / "rotor-flow.json"
OUT = ROOT / "docs" / "images" / "node-red-page.png"
CONSOLE_OUT = ROOT / "docs" / "images" / "console.png"
KINDS = ("bridge", "bearing", "state", "availability", "status", "presets", "tracking")
JSON_KINDS = ("status", "presets")  # the flow's MQTT nodes parse these as JSON

# Replaces the browser's WebSocket: the page's socket opens at once, and the script hands it
# messages through window.deliver, as Node-RED's websocket node would.
FAKE_SOCKET = """
window.sockets = [];
window.WebSocket = function () {
  var self = this;
  window.sockets.push(self);
  self.send = function () {};
  self.close = function () {};
  setTimeout(function () { if (self.onopen) { self.onopen(); } }, 0);
};
window.deliver = function (text) {
  window.sockets.forEach(function (s) { if (s.onmessage) { s.onmessage({ data: text }); } });
};
"""

NODE_RED_CONFIG = """\
state_file = "{work}/state.json"
[mqtt]
host = "127.0.0.1"
port = {port}
[homeassistant]
enabled = false
[station]
locator = "JO62qm"
[[rotators]]
id = "tower"
name = "Tower"
model = "rotorez"
port = "{work}/rotor"
presets = {{ EU = 45, JA = 330, VK = 75, W = 300 }}
park_az_deg = 0
"""

# Berlin's station; presets toward real DX, their short-path bearings from JO62qm (JA: Tokyo,
# VK: Sydney, ZS: Johannesburg, PY: Rio, W6: San Francisco); a keep-out sector for the
# neighbour's roof
CONSOLE_CONFIG = """\
state_file = "{work}/state.json"
[mqtt]
host = "127.0.0.1"
port = {port}
[homeassistant]
enabled = false
[station]
locator = "JO62qm"
[web]
enabled = true
port = {web_port}
[[rotators]]
id = "tower"
name = "Tower"
model = "rotorez"
port = "{work}/rotor"
beamwidth_deg = 50
presets = {{ JA = 42, VK = 75, ZS = 168, PY = 233, W6 = 326 }}
keep_out = [[190, 215]]
park_az_deg = 0
"""
CONSOLE_SIZE: ViewportSize = {"width": 1280, "height": 800}
NEW_YORK = "FN31pr"  # 296 degrees, 6227 km from JO62qm


def page_html() -> str:
    flow = json.loads(FLOW.read_text())
    (template,) = [n["template"] for n in flow if n.get("type") == "template"]
    return str(template)


def kind_of(topic: str) -> str:
    return "bridge" if topic.endswith("/bridge/state") else topic.rsplit("/", 1)[-1]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "pictures",
        nargs="*",
        metavar="console|node-red",
        help="which pictures to make (default: both)",
    )
    parser.add_argument("--out-dir", type=Path, default=OUT.parent)
    parser.add_argument("--chromium", default="/usr/bin/chromium")
    args = parser.parse_args()
    unknown = set(args.pictures) - {"console", "node-red"}
    if unknown:
        parser.error(f"no picture named {', '.join(sorted(unknown))}: console or node-red")
    status = 0
    for picture in dict.fromkeys(args.pictures or ["console", "node-red"]):
        with tempfile.TemporaryDirectory(prefix="rotor-shot-") as tmp:
            if picture == "console":
                status |= shoot_console(Path(tmp), args.out_dir / CONSOLE_OUT.name, args.chromium)
            else:
                status |= shoot_node_red(Path(tmp), args.out_dir / OUT.name, args.chromium)
    return status


@contextlib.contextmanager
def running_bridge(
    work: Path, config: str, start_az_deg: float, web_port: int = 0
) -> Iterator[int]:
    """A private mosquitto, an emulated Rotor-EZ at ``start_az_deg`` and the bridge on it, as
    processes of their own; yields the broker's port."""
    broker = Mosquitto(work / "broker").start()
    procs: list[subprocess.Popen[bytes]] = []
    try:
        emulate = [sys.executable, "-m", "bridge", "emulate", "rotorez"]
        emulate += ["--link", str(work / "rotor"), "--start-az-deg", str(start_az_deg)]
        procs.append(subprocess.Popen(emulate, stdout=subprocess.DEVNULL))
        deadline = time.monotonic() + 10
        while not (work / "rotor").exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        path = work / "bridge.toml"
        path.write_text(config.format(work=work, port=broker.port, web_port=web_port))
        run = [sys.executable, "-m", "bridge", "run", "-c", str(path)]
        procs.append(subprocess.Popen(run, stderr=subprocess.DEVNULL))
        yield broker.port
    finally:
        for proc in reversed(procs):
            proc.terminate()
            proc.wait(10)
        broker.stop()


def shoot_console(work: Path, out: Path, chromium: str) -> int:
    web_port = free_port()
    # from 340 to New York's 296 the rotor turns anticlockwise, the beam sweeping toward it
    with running_bridge(work, CONSOLE_CONFIG, 340, web_port):
        deadline = time.monotonic() + 20
        while not listens("127.0.0.1", web_port):  # an HTTP server: it sends no CONNACK
            if time.monotonic() > deadline:
                print("screenshot: the console did not answer", file=sys.stderr)
                return 1
            time.sleep(0.1)
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=chromium)
            page = browser.new_page(viewport=CONSOLE_SIZE, device_scale_factor=1)
            page.goto(f"http://127.0.0.1:{web_port}/")
            # the bridge has read the rotor (near 340, still) and the coastlines are drawn
            page.wait_for_function(
                "() => { const v = parseFloat(document.querySelector('#bearing').textContent);"
                " return v > 330 && document.querySelector('#map .land') !== null; }",
                timeout=20_000,
            )
            page.fill("#locator", NEW_YORK)
            page.click("#locator-go")
            # under way: the beam between where it started and the target
            page.wait_for_function(
                "() => { const v = parseFloat(document.querySelector('#bearing').textContent);"
                " return v > 300 && v < 318; }",
                timeout=30_000,
            )
            page.mouse.move(CONSOLE_SIZE["width"] - 1, CONSOLE_SIZE["height"] - 1)
            out.parent.mkdir(parents=True, exist_ok=True)
            page.screenshot(path=str(out))
            browser.close()
    print(f"screenshot: {out} ({out.stat().st_size // 1024} KB)")
    return 0


def shoot_node_red(work: Path, out: Path, chromium: str) -> int:
    with running_bridge(work, NODE_RED_CONFIG, 20) as port:
        return shoot(port, out, chromium)


def shoot(port: int, out: Path, chromium: str) -> int:
    latest: dict[str, str] = {}
    lock = threading.Lock()

    def on_message(_c: object, _u: object, msg: mqtt.MQTTMessage) -> None:
        kind = kind_of(msg.topic)
        if kind not in KINDS:
            return
        text = msg.payload.decode()
        value: object = json.loads(text) if kind in JSON_KINDS else text
        if kind == "bearing":
            value = float(text)
        with lock:
            latest[kind] = json.dumps({"kind": kind, "value": value})

    client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id="rotor-shot")
    client.on_message = on_message
    client.connect("127.0.0.1", port)
    client.subscribe("rotor/#")
    client.loop_start()
    try:
        deadline = time.monotonic() + 20
        while latest.get("availability") != '{"kind": "availability", "value": "online"}':
            if time.monotonic() > deadline:
                print("screenshot: the bridge did not come online", file=sys.stderr)
                return 1
            time.sleep(0.1)
        # New York from the station: 295 degrees, clockwise from 20 (a Rotor-EZ stops at north)
        client.publish("rotor/target", "FN30")
        time.sleep(8)  # under way: the needle between where it started and the target
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=chromium)
            page = browser.new_page(viewport={"width": 460, "height": 1400})
            page.add_init_script(FAKE_SOCKET)
            html = page_html()
            page.route(
                "http://node-red.invalid/rotor",
                lambda r: r.fulfill(body=html, content_type="text/html"),
            )
            page.goto("http://node-red.invalid/rotor")
            with lock:
                messages = [latest[k] for k in KINDS if k in latest]
            for text in messages:
                page.evaluate("text => window.deliver(text)", text)
            out.parent.mkdir(parents=True, exist_ok=True)
            height = page.evaluate("() => document.body.scrollHeight")
            page.screenshot(path=str(out), clip={"x": 0, "y": 0, "width": 460, "height": height})
            browser.close()
    finally:
        client.loop_stop()
        client.disconnect()
    print(f"screenshot: {out} ({out.stat().st_size // 1024} KB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
