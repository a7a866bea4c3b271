"""``rotor-bridge demo``: emulated rotators bridged to MQTT, no hardware and no broker needed.

If nothing answers at the MQTT address, a private mosquitto is started there (bridge.mosquitto);
a broker that answers is used as it is. Everything the console shows and
sends goes through the broker, exactly as Home Assistant or Node-RED would see it.
"""

from __future__ import annotations

import argparse
import signal
import sys
import tempfile
import threading
import time
from pathlib import Path

import paho.mqtt.client as paho
from paho.mqtt.enums import CallbackAPIVersion

from bridge import emulators
from bridge.app import App
from bridge.mosquitto import BrokerError, Mosquitto, answers
from bridge.settings import Settings


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--mqtt-host", default="127.0.0.1")
    p.add_argument("--mqtt-port", type=int, default=1883)
    p.add_argument("--base-topic", default="rotor")
    p.add_argument(
        "--models",
        default="rotorez",
        help="comma-separated emulated controllers, e.g. rotorez,rotorcard,dcu1 (default rotorez)",
    )
    p.add_argument("--speed-deg-s", type=float, default=6.0, help="rotor speed (HAM-IV: ~6)")
    p.add_argument(
        "--no-private-broker",
        action="store_true",
        help="fail instead of starting a private mosquitto when no broker answers",
    )
    p.add_argument("--duration-s", type=float, help="stop after this long (default: until ^C)")


class Console:
    """Shows what arrives on the broker and turns typed lines into MQTT commands."""

    def __init__(self, host: str, port: int, base: str, roots: dict[str, str]) -> None:
        self._roots = roots
        self._last: dict[str, str] = {}
        self._client = paho.Client(CallbackAPIVersion.VERSION2, client_id="rotor-bridge-demo-ui")
        self._client.on_connect = lambda c, *_: c.subscribe(f"{base}/#", qos=1)
        self._client.on_message = self._on_message
        self._client.connect_async(host, port)
        self._client.loop_start()

    def _on_message(self, client, userdata, msg) -> None:  # noqa: ANN001
        leaf = msg.topic.rsplit("/", 1)[-1]
        if leaf in ("status",):
            return
        text = msg.payload.decode("utf-8", "replace")
        if self._last.get(msg.topic) == text and leaf != "error":
            return
        self._last[msg.topic] = text
        if (
            leaf in ("bearing", "state", "availability", "version", "error")
            or "/option/" in msg.topic
        ):
            print(f"  {msg.topic} = {text}", flush=True)

    def command(self, line: str) -> bool:
        """Handle one typed line; False to quit."""
        words = line.split()
        if not words:
            return True
        rid = next(iter(self._roots))
        if words[0] in self._roots and len(words) > 1:
            rid, words = words[0], words[1:]
        root = self._roots[rid]
        head = words[0].lower()
        if head in ("q", "quit", "exit"):
            return False
        if head in ("s", "stop"):
            self._client.publish(f"{root}/stop", "STOP", qos=1)
        elif head == "lock" and len(words) == 2:
            self._client.publish(f"{root}/lock", words[1].upper(), qos=1)
        elif head in ("endpoint", "jam", "overshoot", "unstick") and len(words) == 2:
            self._client.publish(f"{root}/option/{head}", words[1].upper(), qos=1)
        else:
            self._client.publish(f"{root}/target", " ".join(words), qos=1)
        return True

    def close(self) -> None:
        self._client.disconnect()
        self._client.loop_stop()


def run(args: argparse.Namespace) -> int:
    models = [m.strip() for m in args.models.split(",") if m.strip()]
    unknown = [m for m in models if m not in emulators.EMULATORS]
    if unknown:
        print(f"rotor-bridge demo: no emulator for {', '.join(unknown)}", file=sys.stderr)
        return 2
    workdir = Path(tempfile.mkdtemp(prefix="rotor-bridge-demo-"))
    broker: Mosquitto | None = None
    if not answers(args.mqtt_host, args.mqtt_port):
        if args.no_private_broker:
            print(f"no MQTT broker at {args.mqtt_host}:{args.mqtt_port}", file=sys.stderr)
            return 1
        try:
            broker = Mosquitto(workdir / "broker", port=args.mqtt_port, host=args.mqtt_host).start()
        except BrokerError as exc:
            print(f"rotor-bridge demo: no MQTT broker answers and {exc}", file=sys.stderr)
            return 1
        where = f"a private mosquitto on {args.mqtt_host}:{args.mqtt_port}"
    else:
        where = f"the MQTT broker already running at {args.mqtt_host}:{args.mqtt_port}"
    ports = []
    rotators = []
    for i, model in enumerate(models):
        rid = model if models.count(model) == 1 else f"{model}{i + 1}"
        link = workdir / f"tty-{rid}"
        ports.append(emulators.start(model, link=str(link), speed_deg_s=args.speed_deg_s))
        rotators.append({"id": rid, "name": f"Demo {model}", "model": model, "port": str(link)})
    settings = Settings(
        mqtt={"host": args.mqtt_host, "port": args.mqtt_port, "base_topic": args.base_topic},
        rotators=rotators,
        state_file=workdir / "state.json",
    )
    roots = {r.id: settings.rotator_topic(r) for r in settings.rotators}
    app = App(settings)
    app.start()
    console = Console(args.mqtt_host, args.mqtt_port, args.base_topic, roots)
    first = next(iter(roots.values()))
    hp = f"-h {args.mqtt_host} -p {args.mqtt_port}"
    print(
        f"\nrotor-bridge demo: {len(models)} emulated rotator(s) bridged to {where}.\n"
        f"  watch:   mosquitto_sub {hp} -t '{args.base_topic}/#' -v\n"
        f"  turn:    mosquitto_pub {hp} -t {first}/target -m 120\n"
        "  or type here: a bearing (120), 's' to stop, 'lock on|off', 'q' to quit"
        + (f" (prefix a rotator id: {', '.join(roots)})" if len(roots) > 1 else "")
        + "\n",
        flush=True,
    )
    done = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: done.set())
    signal.signal(signal.SIGINT, lambda *_: done.set())
    deadline = None if args.duration_s is None else time.monotonic() + args.duration_s
    if sys.stdin.isatty() and deadline is None:
        threading.Thread(target=_read_stdin, args=(console, done), daemon=True).start()
    try:
        while not done.wait(0.2):
            if deadline is not None and time.monotonic() >= deadline:
                break
    finally:
        console.close()
        app.stop()
        for port in ports:
            port.close()
        if broker is not None:
            broker.stop()
    return 0


def _read_stdin(console: Console, done: threading.Event) -> None:
    for line in sys.stdin:
        if not console.command(line):
            break
    done.set()
