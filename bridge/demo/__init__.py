"""``rotor-bridge demo``: emulated rotators bridged to MQTT, no hardware and no broker needed.

If no MQTT broker answers at the MQTT address, a private mosquitto is started there
(bridge.demo.mosquitto; on a free port when another program holds that one, rules 6 and 7); a
broker that answers is used as it is. Everything the console shows and sends goes through the
broker, exactly as Home Assistant or Node-RED would see it.

Rules:
1. A demo is never mistaken for a real bridge on the same broker, nor for another demo: each run
   draws a short instance name (4 characters) and takes its own base topic
   ``rotor-demo-<instance>`` (``--base-topic`` overrides it), its own MQTT client ids
   (``rotor-demo-<instance>``, the console ``...-ui``: at most 23 characters, which every broker
   must accept; a real bridge's default has 6 hex digits there) and, from the base topic, its
   own Home Assistant node ids (``rotorbridge_rotor-demo-<instance>``; a real bridge on ``rotor``
   owns only ``rotorbridge_rotor`` and ``rotorbridge_rotor_r_*``, so neither clears the other's
   configs). Device names say "Demo".
2. Its settings come from its flags alone: a ``ROTOR_BRIDGE_*`` environment written for the real
   service (its base topic, its client id) must not turn the demo into that service's twin.
3. Everything it starts (private broker, emulators, bridge, console client) is stopped and its
   temporary folder removed on every way out: ``--duration-s`` over, ``q`` or ^D typed, ^C,
   SIGTERM, SIGHUP (terminal closed), a failure during start-up. Killed outright (SIGKILL, the
   out-of-memory killer) it runs no clean-up, but its private broker still ends with it
   (demo/mosquitto.py: the kernel's death signal), so the next demo never takes it for the
   user's own.
4. When it ends it removes what it left retained on the broker (its state topics and its Home
   Assistant configs), so runs do not pile up dead devices in Home Assistant. Not so under a
   ``--base-topic`` the user chose: that may hold someone else's retained state. A base topic
   that a bridge uses (``<base>/bridge/state`` retained, online or offline) is refused.
5. A broker that answers is used, unless it is another demo's private mosquitto (its retained
   mark, bridge/demo/console.py rule 5): that one ends with the other demo, and this one would
   be left without a broker, so it starts a private mosquitto of its own on a free port (the
   commands it prints name that port). A private broker it starts carries its mark.
6. A broker answers when a CONNECT gets a CONNACK (bridge/demo/mosquitto.py ``answers``, within
   the time the bridge gives one: a slow broker serves the bridge), not when a connection is
   taken: a program on the port that speaks no MQTT (a hung broker, an SSH
   tunnel whose far end is gone) would leave the demo running dead, saying it is bridged. The
   demo says so in one line and starts a private mosquitto on a free port (with
   ``--no-private-broker``: says so and ends).
7. Two demos started at once may both find nothing on the port: the one whose mosquitto loses
   the race for it starts its own on a free port (the port is taken now: rule 5's case), never
   fails for it.
8. A broker that refuses the demo's login (its CONNACK says "not authorized" or "bad user name
   or password": one set up with a password, as most for Home Assistant are) cannot be its
   broker: the demo has no login flags, and its bridge and console would be refused, running
   dead. Nor can one that bans it (MQTT 5's 0x8A "banned", demo/mosquitto.py BANNED). The demo
   says so in one line and starts a private mosquitto on a free port (with
   ``--no-private-broker``: says so and ends).
"""

from __future__ import annotations

import argparse
import contextlib
import inspect
import math
import secrets
import shutil
import signal
import socket
import string
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from pydantic import ValidationError
from pydantic_settings import BaseSettings, PydanticBaseSettingsSource

from bridge import emulators
from bridge.app import App
from bridge.core import geo
from bridge.core.ending import Ending
from bridge.demo import sky as demo_sky
from bridge.demo.console import Console, private_broker_of
from bridge.demo.mosquitto import (
    BANNED,
    LOGIN_REFUSED,
    BrokerError,
    Mosquitto,
    answers,
    connack_of,
    free_port,
    listens,
)
from bridge.demo.screen import Screen
from bridge.interfaces.homeassistant import Identity
from bridge.interfaces.mqtt.topics import DiscoveryTopics, Topics
from bridge.protocols import REGISTRY
from bridge.settings import ConfigError, Settings, format_validation_error

MIN_SPEED_DEG_S, MAX_SPEED_DEG_S = 0.5, 360.0  # the settings' range for a rotor's speed
LOOK_AGAIN_S = 1.0  # rule 6: the second look at the broker's port, for one that just came up
DEMOSAT_RISES_IN_S = 40.0  # the demo's satellite rises this long after the start (default)


def _speed(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not MIN_SPEED_DEG_S <= value <= MAX_SPEED_DEG_S:
        raise argparse.ArgumentTypeError(
            f"{value:g} is outside {MIN_SPEED_DEG_S:g}..{MAX_SPEED_DEG_S:g} deg/s"
        )
    return value


MAX_DURATION_S = 7 * 86400.0  # --duration-s: a week at most (without it: until q)
MAX_RISES_IN_S = 7 * 86400.0  # --satellite-rises-in-s: within a week (the TLE's epoch then)
MAX_PORT = 65535


def _number(text: str) -> float:
    """A finite number: nan and inf are no duration, time or port (argparse names the flag)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"not a finite number: {text!r}")
    return value


def _duration(text: str) -> float:
    value = _number(text)
    if not 0 < value <= MAX_DURATION_S:
        raise argparse.ArgumentTypeError(
            f"{value:g} is outside 0..{MAX_DURATION_S:g} s (a week; without it the demo runs "
            "until q)"
        )
    return value


def _rises_in(text: str) -> float:
    value = _number(text)
    if not 0 <= value <= MAX_RISES_IN_S:
        raise argparse.ArgumentTypeError(f"{value:g} is outside 0..{MAX_RISES_IN_S:g} s (a week)")
    return value


def _port(lowest: int) -> Callable[[str], int]:
    """A TCP port, ``lowest``..65535 (the console's 0: none)."""

    def port(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a port number: {text!r}") from None
        if not lowest <= value <= MAX_PORT:
            raise argparse.ArgumentTypeError(f"{value} is outside {lowest}..{MAX_PORT}")
        return value

    return port


def _locator(text: str) -> str:
    try:
        geo.parse_locator(text)
    except geo.LocatorError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


# The demo's presets: where a few well-known places lie from its station (the bearings are
# worked out at start-up, so they stay right for any --locator).
PRESET_PLACES = {"EU": "JN18eu", "JA": "PM95vq", "VK": "QF56od", "W": "FN30as"}


def demo_presets(station: str) -> dict[str, float]:
    here = geo.parse_locator(station)
    return {
        name: round(geo.great_circle(*here, *geo.parse_locator(place)).short_path_deg) % 360
        for name, place in PRESET_PLACES.items()
    }


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--mqtt-host",
        default="127.0.0.1",
        help="the MQTT broker's address (default 127.0.0.1); if no broker answers there, a "
        "private mosquitto is started on it (see --no-private-broker)",
    )
    p.add_argument(
        "--mqtt-port",
        type=_port(1),
        default=1883,
        help="the MQTT broker's port (default 1883), or the private mosquitto's (a free one "
        "when the broker there is another demo's, which ends with it, or when what is there "
        "answers no MQTT)",
    )
    p.add_argument(
        "--base-topic", help="base topic (default rotor-demo-<instance>, new for every run)"
    )
    p.add_argument(
        "--models",
        default="rotorez",
        help="comma-separated emulated controllers, e.g. rotorez,rotorcard,dcu1 (default "
        f"rotorez; known: {','.join(emulators.EMULATORS)})",
    )
    p.add_argument(
        "--speed-deg-s", type=_speed, default=6.0, help="rotor speed, both axes (HAM-IV: ~6)"
    )
    p.add_argument(
        "--locator",
        type=_locator,
        default="JO62qm",
        help="the emulated station's Maidenhead locator, for `locator` targets and the presets "
        "(default JO62qm, Berlin)",
    )
    p.add_argument(
        "--no-private-broker",
        action="store_true",
        help="fail instead of starting a private mosquitto when no broker answers",
    )
    p.add_argument(
        "--web-port",
        type=_port(0),
        default=8754,
        help="the operator console's port on 127.0.0.1 (default 8754; another free one if that "
        "is taken; 0: no console)",
    )
    p.add_argument(
        "--duration-s",
        type=_duration,
        help="stop after this many seconds, at most a week (default: until q/^C)",
    )
    p.add_argument(
        "--satellite-rises-in-s",
        type=_rises_in,
        default=DEMOSAT_RISES_IN_S,
        help=f"when the made-up satellite {demo_sky.NAME} rises over the station, in seconds "
        f"from the start (default {DEMOSAT_RISES_IN_S:g})",
    )


def instance_name() -> str:
    """Four lower-case letters or digits: short to type, 1.7 million to choose from."""
    return "".join(secrets.choice(string.ascii_lowercase + string.digits) for _ in range(4))


class DemoSettings(Settings):
    """Settings from the demo's flags only, never from the environment (rule 2)."""

    @classmethod
    def settings_customise_sources(
        cls,
        settings_cls: type[BaseSettings],
        init_settings: PydanticBaseSettingsSource,
        env_settings: PydanticBaseSettingsSource,
        dotenv_settings: PydanticBaseSettingsSource,
        file_secret_settings: PydanticBaseSettingsSource,
    ) -> tuple[PydanticBaseSettingsSource, ...]:
        return (init_settings,)


def demo_settings(
    args: argparse.Namespace, models: list[str], instance: str, workdir: Path
) -> DemoSettings:
    rotators = []
    for i, model in enumerate(models):
        rid = model if models.count(model) == 1 else f"{model}{i + 1}"
        speeds = {"az_speed_deg_s": args.speed_deg_s}
        park: dict[str, float] = {"park_az_deg": 0}
        if REGISTRY[model].has_elevation:
            speeds["el_speed_deg_s"] = args.speed_deg_s
            park["park_el_deg"] = 0
        # compass presets fit a rotator that turns all round (not an elevation box's 0..90)
        compass = REGISTRY[model].az_max_deg >= 360
        rotators.append(
            {
                "id": rid,
                "name": f"Demo {model} ({instance})",
                "model": model,
                "port": str(workdir / f"tty-{rid}"),
                **speeds,
                "presets": demo_presets(args.locator) if compass else {},
                **park,
            }
        )
    return DemoSettings(
        mqtt={
            "host": args.mqtt_host,
            "port": args.mqtt_port,
            "base_topic": args.base_topic or f"rotor-demo-{instance}",
            "client_id": f"rotor-demo-{instance}",
        },
        rotators=rotators,
        station={"locator": args.locator},
        tracking={"tle_file": workdir / "demo.tle"},  # demo/sky.py writes it before the start
        state_file=workdir / "state.json",
        web={"enabled": args.web_port != 0, "port": _free_port(args.web_port) or 8754},
    )


def _free_port(wanted: int) -> int:
    """``wanted`` if nothing listens there on loopback, else one the system picks (two demos
    at once each get a console)."""
    if wanted == 0:
        return 0
    with socket.socket() as probe:
        try:
            probe.bind(("127.0.0.1", wanted))
        except OSError:
            probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


def emulator_options(model: str, speed_deg_s: float) -> dict[str, Any]:
    """The demo's one speed in the words of this model's emulator (families name it apart), and
    its rotor as built (emulators rule 3: a Rotor-EZ's Hy-Gain rotor stops at south): the
    keyword arguments for emulators.start, whose options are typed Any."""
    params = inspect.signature(emulators.EMULATORS[model]).parameters
    if "speed_deg_s" in params:
        return {"speed_deg_s": speed_deg_s, **emulators.as_built(model)}
    speeds = {k: speed_deg_s for k in ("az_speed_deg_s", "el_speed_deg_s") if k in params}
    return {**speeds, **emulators.as_built(model)}


def run(args: argparse.Namespace) -> int:
    models = [m.strip() for m in args.models.split(",") if m.strip()]
    unknown = [m for m in models if m not in emulators.EMULATORS]
    if unknown or not models:
        print(
            f"rotor-bridge demo: no emulator for {', '.join(unknown) or 'nothing'}; "
            f"known: {', '.join(emulators.EMULATORS)}",
            file=sys.stderr,
        )
        return 2
    # the demo's end, and what ended it first (said as it stops: a demo that ends on its own is
    # otherwise a mystery); its handlers take no lock (core/ending.py)
    done = Ending()
    try:
        # ^C during start-up: start, then clean up at once; a second ^C while cleaning up
        # changes nothing (core/ending.py rule 3)
        with (
            done.on_signals(signal.SIGINT, signal.SIGTERM, signal.SIGHUP),
            contextlib.ExitStack() as stack,  # undone in reverse on every way out (rule 3)
        ):
            workdir = Path(tempfile.mkdtemp(prefix="rotor-bridge-demo-"))
            stack.callback(shutil.rmtree, workdir, ignore_errors=True)
            return _run(args, models, workdir, stack, done)
    except (BrokerError, ConfigError, OSError) as exc:
        print(f"rotor-bridge demo: could not start: {exc}", file=sys.stderr)
        return 1
    finally:
        done.close()


def _run(
    args: argparse.Namespace,
    models: list[str],
    workdir: Path,
    stack: contextlib.ExitStack,
    done: Ending,
) -> int:
    instance = instance_name()
    try:
        settings = demo_settings(args, models, instance, workdir)
    except ValidationError as exc:
        print(f"rotor-bridge demo: {format_validation_error(exc)}", file=sys.stderr)
        return 2
    host, port = asked = args.mqtt_host, args.mqtt_port
    # the look can take the bridge's whole wait for a CONNACK and more (rule 6): said first, so a
    # silent port or a slow broker is not taken for a demo that hangs (review 127)
    print(
        f"rotor-bridge demo: looking for an MQTT broker on {host}:{port} ...",
        file=sys.stderr,
        flush=True,
    )
    # one CONNECT: whether a broker answers (rule 6) and whether it lets the demo in (rule 8),
    # from the same CONNACK (asking twice made a slow broker's wait twice as long). Each wait of
    # the look ends with the demo (^C, SIGTERM): nothing is started then (rule 3)
    answer = connack_of(host, port, ended=done.is_set)
    code, mqtt5 = (None, True) if answer is None else answer
    refused = None if code is None else LOGIN_REFUSED.get(code)
    banned = None if code is None else BANNED.get(code)
    there = code is not None and refused is None and banned is None
    other = (
        private_broker_of(host, port)  # (a demo's private mosquitto speaks MQTT 5)
        if there and mqtt5 and not args.no_private_broker and not done.is_set()
        else None
    )
    # rule 6: a program there, but no broker (asked again: one may have come up meanwhile, and
    # answers at once; a program that took the first look's connection was given its full wait)
    mute = (
        code is None
        and not done.is_set()
        and listens(host, port)
        and not answers(host, port, LOOK_AGAIN_S, ended=done.is_set)
    )
    if done.is_set():
        print(
            f"rotor-bridge demo: stopping ({done.reason}) while it looked for a broker; "
            "nothing was started",
            file=sys.stderr,
            flush=True,
        )
        return 0
    private = not there or other is not None
    instead = "" if args.no_private_broker else "; a private mosquitto on a free port instead"
    for why in (
        refused
        and f"the MQTT broker at {host}:{port} refuses the demo's login ({refused}), and the "
        "demo has none to give it",
        banned
        and f"the MQTT broker at {host}:{port} refuses the demo ({banned}): it cannot be the "
        "demo's broker",
        mute and f"{host}:{port} takes connections but answers no MQTT (no CONNACK): not a broker",
    ):
        if why:  # (rules 6, 8: why the broker there is not the demo's)
            print(f"rotor-bridge demo: {why}{instead}", file=sys.stderr, flush=True)
    if there and other is None:
        where = f"the MQTT broker already running at {host}:{port}"
        if not mqtt5:
            where += " (it speaks MQTT 3.1.1, not 5)"
    elif args.no_private_broker:
        if not mute and not refused and not banned:
            print(f"rotor-bridge demo: no MQTT broker at {host}:{port}", file=sys.stderr)
        return 1
    else:
        taken = other is not None or mute or bool(refused or banned)  # rules 5, 6, 8: not there
        port = _start_private_broker(host, free_port() if taken else port, workdir, stack)
        mqtt5 = True  # (mosquitto)
        where = f"a private mosquitto on {host}:{port}"
        if other is not None:
            where += f" (the one on {host}:{asked[1]} is demo {other}'s, and ends with it)"
        elif mute:
            where += f" (what is on {host}:{asked[1]} speaks no MQTT)"
        elif refused:
            where += f" (the broker on {host}:{asked[1]} refuses the demo's login)"
        elif banned:
            where += f" (the broker on {host}:{asked[1]} bans the demo)"
        elif port != asked[1]:  # rule 7
            where += f" ({host}:{asked[1]} was taken as it started: another demo's?)"
        if port != asked[1]:
            args.mqtt_port = port
            settings = demo_settings(args, models, instance, workdir)
    roots = {r.id: settings.rotator_topic(r) for r in settings.rotators}
    topics = Topics(settings.mqtt.base_topic, roots)
    ident = Identity(topics.base)
    discovery = DiscoveryTopics(settings.homeassistant.discovery_prefix)
    nodes = [ident.bridge_node, *(ident.rotator_node(rid) for rid in roots)]
    screen = Screen.for_terminal()
    stack.callback(screen.close)  # the terminal as it was, whatever happens next
    console = Console(
        host,
        port,
        client_id=f"{settings.mqtt.effective_client_id()}-ui",
        topics=topics,
        rotator_ids=list(roots),
        discovery_filters=[discovery.config("+", node, "+") for node in nodes],
        screen=screen,
        mqtt5=mqtt5,
    )
    # a base topic of its own making is the demo's alone to clean up; one given with --base-topic
    # may hold someone else's retained state, which is not the demo's to delete
    stack.callback(console.close, remove_retained=args.base_topic is None)
    console.sync()
    if private:
        console.mark_private_broker(instance)
    # a bridge that uses this base topic, running or stopped, owns its Home Assistant devices:
    # the demo's discovery would clear them as stale
    held = console.look(topics.bridge_state) if args.base_topic is not None else None
    if held is not None:
        print(
            f"rotor-bridge demo: base topic {topics.base!r} belongs to a bridge "
            f"({topics.bridge_state} is {held.decode(errors='replace')!r}); choose another "
            "--base-topic or none",
            file=sys.stderr,
        )
        return 2
    for r in settings.rotators:
        emu = emulators.start(r.model, link=r.port, **emulator_options(r.model, args.speed_deg_s))
        stack.callback(emu.close)
    position = settings.station.position
    assert position is not None and settings.tracking.tle_file is not None
    rise = demo_sky.write_tle_file(settings.tracking.tle_file, *position, args.satellite_rises_in_s)
    app = App(settings)
    stack.callback(app.stop)  # before the console's clean-up: the bridge's "offline" goes first
    app.start()
    web_url = app.web.url if app.web else None
    _print_banner(args, settings, topics, where, instance, web_url, port == asked[1])
    print(
        f"  A made-up satellite, {demo_sky.NAME}, rises over the station around "
        f"{time.strftime('%H:%M:%S', time.gmtime(rise))} UTC (in {args.satellite_rises_in_s:g} s):"
        f" type 'track {demo_sky.NAME}' (or 'track sun', 'track moon').\n",
        flush=True,
    )
    deadline = None if args.duration_s is None else time.monotonic() + args.duration_s
    if sys.stdin.isatty():
        print(
            "  Or type here: a bearing (120), 's' to stop, 'help' for more, 'q' to quit\n",
            flush=True,
        )
    screen.start()  # on a terminal: from here one status line, log lines above it
    if sys.stdin.isatty():
        threading.Thread(target=_read_stdin, args=(screen, console, done), daemon=True).start()
    if not done.wait(None if deadline is None else max(0.0, deadline - time.monotonic())):
        done.end("--duration-s is over")
    screen.log(f"rotor-bridge demo: stopping ({done.reason})")
    return 0


def _start_private_broker(
    host: str, port: int, workdir: Path, stack: contextlib.ExitStack, tries: int = 3
) -> int:
    """A private mosquitto on host:port, or on a free port when another program took that one
    as it started (rule 7): the port it listens on."""
    for tried in range(1, tries + 1):
        broker = Mosquitto(workdir / "broker", port=port, host=host, dies_with_parent=True)
        stack.callback(broker.stop)
        try:
            broker.start()
        except BrokerError as exc:
            if tried == tries or not listens(host, port):  # not taken: mosquitto's own failure
                raise BrokerError(f"no MQTT broker answers and {exc}") from None
            port = free_port()
        else:
            return port
    raise AssertionError("unreachable")


def _print_banner(
    args: argparse.Namespace,
    settings: Settings,
    topics: Topics,
    where: str,
    instance: str,
    app_url: str | None,
    seen: bool = True,
) -> None:
    """``seen``: the broker is at the address asked for, where a Home Assistant may listen (not
    a private one on a free port, rule 5: none can see that)."""
    hp = (
        ""
        if (args.mqtt_host, args.mqtt_port) == ("127.0.0.1", 1883)
        else (f"-h {args.mqtt_host} -p {args.mqtt_port} ")
    )
    first = topics.rotator(settings.rotators[0].id)
    lines = [
        "",
        f"rotor-bridge demo {instance}: {len(settings.rotators)} emulated rotator(s) bridged "
        f"to {where}.",
        f"  its own topics: {topics.base}/...  (a real bridge's are not touched)",
    ]
    if len(settings.rotators) > 1:
        lines += [f"    {r.id}: {topics.rotator(r.id).root}/..." for r in settings.rotators]
    lines += [
        f"  watch: mosquitto_sub {hp}-t '{topics.base}/#' -v",
        f"  turn:  mosquitto_pub {hp}-t {first.target} -m 120",
        f"  stop:  mosquitto_pub {hp}-t {first.stop} -m STOP",
        *([f"  console: {app_url}  (the beam on a map, in any browser)"] if app_url else []),
        *(
            [
                f'  Home Assistant: the devices "Demo ... ({instance})"'
                + (", removed again when the demo ends" if args.base_topic is None else "")
            ]
            if seen
            else []
        ),
        "",
    ]
    print("\n".join(lines), flush=True)


def _read_stdin(screen: Screen, console: Console, done: Ending) -> None:
    quit_typed = False

    def handle(line: str) -> bool:
        nonlocal quit_typed
        going_on = console.command(line)
        quit_typed = not going_on
        return going_on

    screen.read_lines(handle)
    done.end("q typed" if quit_typed else "the terminal's input ended")
