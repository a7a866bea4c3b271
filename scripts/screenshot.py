"""The README's picture: the Node-RED example page showing a real bridge turning an emulated rotor.

Run it through ``scripts/screenshot`` (which installs what it needs). It starts a private
mosquitto, an emulated Rotor-EZ and the bridge (a configuration with a station and presets),
sends a locator target, and opens the page of ``deploy/node-red/rotor-flow.json`` in Chromium.
The page's websocket is fed what the flow's "to the web page" function sends it: one
``{"kind", "value"}`` text per MQTT message, the kind being the topic's last part. The picture is
taken while the rotor turns and written to ``docs/images/node-red-page.png``.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import paho.mqtt.client as mqtt
from playwright.sync_api import sync_playwright

from bridge.mosquitto import Mosquitto

ROOT = Path(__file__).resolve().parent.parent
FLOW = ROOT / "deploy" / "node-red" / "rotor-flow.json"
OUT = ROOT / "docs" / "images" / "node-red-page.png"
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

CONFIG = """\
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


def page_html() -> str:
    flow = json.loads(FLOW.read_text())
    (template,) = [n["template"] for n in flow if n.get("type") == "template"]
    return str(template)


def kind_of(topic: str) -> str:
    return "bridge" if topic.endswith("/bridge/state") else topic.rsplit("/", 1)[-1]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=OUT)
    parser.add_argument("--chromium", default="/usr/bin/chromium")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="rotor-shot-") as tmp:
        work = Path(tmp)
        broker = Mosquitto(work / "broker").start()
        procs: list[subprocess.Popen[bytes]] = []
        try:
            emulate = [sys.executable, "-m", "bridge", "emulate", "rotorez"]
            emulate += ["--link", str(work / "rotor"), "--start-az-deg", "20"]
            procs.append(subprocess.Popen(emulate, stdout=subprocess.DEVNULL))
            deadline = time.monotonic() + 10
            while not (work / "rotor").exists() and time.monotonic() < deadline:
                time.sleep(0.1)
            config = work / "bridge.toml"
            config.write_text(CONFIG.format(work=work, port=broker.port))
            run = [sys.executable, "-m", "bridge", "run", "-c", str(config)]
            procs.append(subprocess.Popen(run, stderr=subprocess.DEVNULL))
            return shoot(broker.port, args.out, args.chromium)
        finally:
            for proc in reversed(procs):
                proc.terminate()
                proc.wait(10)
            broker.stop()


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
