"""The files under deploy/: the Node-RED example flow, the systemd unit, the udev rule and the
Docker recipe. They are not Python, so nothing else notices when they drift from the bridge:
these tests hold them to its topics, its command line and its settings."""

from __future__ import annotations

import json
import os
import posixpath
import re
import shlex
import shutil
import subprocess
import tomllib
from dataclasses import replace
from pathlib import Path

import pytest

from bridge.cli import EXIT_CONFIG, build_parser
from bridge.core.model import TrackingInfo
from bridge.features import tracking
from bridge.interfaces.mqtt import payloads
from bridge.interfaces.mqtt.topics import Topics
from bridge.protocols import REGISTRY
from bridge.settings import ConfigError, Settings, load_settings
from bridge.settings.report import SERVICE_STATE_FILE
from tests.support.waiting import slow

ROOT = Path(__file__).resolve().parent.parent
DEPLOY = ROOT / "deploy"
FLOW = DEPLOY / "node-red" / "rotor-flow.json"
UNIT = DEPLOY / "systemd" / "rotor-bridge.service"
SYSUSERS = DEPLOY / "systemd" / "rotor-bridge.sysusers.conf"
UDEV = DEPLOY / "udev" / "99-rotor-bridge.rules"
DOCKER = DEPLOY / "docker"

SHIPPED_EXEC = "/opt/rotor-bridge/bin/rotor-bridge"
SHIPPED_CONFIG = "/etc/rotor-bridge/rotor-bridge.toml"

# ---------------------------------------------------------------------------------------------
# Node-RED flow
# ---------------------------------------------------------------------------------------------

CORE_TYPES = frozenset(
    {
        "tab",
        "mqtt in",
        "mqtt out",
        "mqtt-broker",
        "inject",
        "debug",
        "function",
        "change",
        "switch",
        "template",
        "http in",
        "http response",
        "websocket in",
        "websocket out",
        "websocket-listener",
        "comment",
        "json",
    }
)
CONFIG_TYPES = frozenset({"mqtt-broker", "websocket-listener"})

# The single-rotator topics the flow is written for (README: R = "rotor" with one rotator).
_TOPICS = Topics("rotor", {"tower": "rotor"})
_R = _TOPICS.rotator("tower")
_OPTIONS = sorted({name for spec in REGISTRY.values() for name in spec.options})
DOCUMENTED_TOPICS = frozenset(
    {
        _R.target,
        _R.stop,
        _R.lock,
        _R.preset,
        _R.park,
        _R.nudge,
        _R.presets,
        _R.feature(tracking.COMMAND),
        _R.feature(tracking.STATE),
        _R.bearing,
        _R.state,
        _R.status,
        _R.version,
        _R.availability,
        _R.error,
        _R.lock_state,
        _TOPICS.bridge_state,
        *(_R.option(name) for name in _OPTIONS),
        *(_R.option_state(name) for name in _OPTIONS),
    }
)


@pytest.fixture(scope="module")
def flow() -> list[dict]:
    return json.loads(FLOW.read_text(encoding="utf-8"))


def _by_id(flow: list[dict]) -> dict[str, dict]:
    return {n["id"]: n for n in flow}


def _of_type(flow: list[dict], node_type: str) -> list[dict]:
    return [n for n in flow if n["type"] == node_type]


def _targets(flow: list[dict], node: dict) -> set[str]:
    return {t for port in node.get("wires", []) for t in port}


def _mqtt_out(flow: list[dict], topic: str) -> dict:
    found = [n for n in _of_type(flow, "mqtt out") if n["topic"] == topic]
    assert len(found) == 1, f"expected one mqtt out publishing {topic}, found {len(found)}"
    return found[0]


def test_flow_is_a_flat_array_of_node_objects(flow: list[dict]) -> None:
    assert isinstance(flow, list) and flow
    for node in flow:
        assert isinstance(node, dict), node
        assert isinstance(node.get("id"), str) and node["id"], node
        assert isinstance(node.get("type"), str) and node["type"], node
        assert "nodes" not in node and "flows" not in node, f"nested flow in {node['id']}"


def test_flow_node_ids_are_unique(flow: list[dict]) -> None:
    ids = [n["id"] for n in flow]
    assert len(ids) == len(set(ids)), sorted({i for i in ids if ids.count(i) > 1})


def test_flow_uses_core_node_types_only(flow: list[dict]) -> None:
    assert {n["type"] for n in flow} <= CORE_TYPES, {n["type"] for n in flow} - CORE_TYPES


def test_flow_has_one_tab_holding_every_flow_node(flow: list[dict]) -> None:
    tabs = _of_type(flow, "tab")
    assert len(tabs) == 1
    for node in flow:
        if node["type"] not in CONFIG_TYPES | {"tab"}:
            assert node.get("z") == tabs[0]["id"], f"{node['id']} is not on the tab"


def test_every_wire_leads_to_an_existing_flow_node(flow: list[dict]) -> None:
    nodes = _by_id(flow)
    for node in flow:
        if node["type"] in CONFIG_TYPES | {"tab"}:
            continue
        wires = node["wires"]
        assert isinstance(wires, list) and all(isinstance(p, list) for p in wires), node["id"]
        if node["type"] == "function":
            assert len(wires) == node["outputs"], f"{node['id']}: one wire list per output"
        for target in _targets(flow, node):
            assert target in nodes, f"{node['id']} is wired to missing node {target}"
            assert nodes[target]["type"] not in CONFIG_TYPES | {"tab"}, (node["id"], target)
            assert nodes[target]["type"] not in {"mqtt in", "inject", "http in", "websocket in"}


def test_config_nodes_have_no_position_wires_or_tab(flow: list[dict]) -> None:
    configs = [n for n in flow if n["type"] in CONFIG_TYPES]
    assert {n["type"] for n in configs} == CONFIG_TYPES
    for node in configs + _of_type(flow, "tab"):
        for key in ("x", "y", "wires"):
            assert key not in node, f"{node['type']} {node['id']} has {key}"
        assert not node.get("z"), f"{node['type']} {node['id']} must be global"


def test_nodes_point_at_existing_config_nodes(flow: list[dict]) -> None:
    nodes = _by_id(flow)
    for node in _of_type(flow, "mqtt in") + _of_type(flow, "mqtt out"):
        assert nodes[node["broker"]]["type"] == "mqtt-broker", node["id"]
    for node in _of_type(flow, "websocket in") + _of_type(flow, "websocket out"):
        assert nodes[node["server"]]["type"] == "websocket-listener", node["id"]
        assert not node.get("client"), node["id"]


def test_broker_is_local_and_carries_no_credentials(flow: list[dict]) -> None:
    (broker,) = _of_type(flow, "mqtt-broker")
    assert (broker["broker"], str(broker["port"])) == ("localhost", "1883")
    assert not {"user", "password", "credentials"} & set(broker)
    assert not any("credentials" in node for node in flow)


def test_tab_info_explains_the_single_rotator_topics(flow: list[dict]) -> None:
    (tab,) = _of_type(flow, "tab")
    info = tab["info"]
    assert "`rotor`" in info and "rotor/<id>" in info and "retain" in info
    assert "/rotor" in info  # where the web page is


def test_every_mqtt_topic_is_one_the_bridge_documents(flow: list[dict]) -> None:
    used = [n["topic"] for n in _of_type(flow, "mqtt in") + _of_type(flow, "mqtt out")]
    assert used
    assert set(used) <= DOCUMENTED_TOPICS, set(used) - DOCUMENTED_TOPICS


def test_every_mqtt_out_publishes_unretained_to_its_fixed_topic(flow: list[dict]) -> None:
    outs = _of_type(flow, "mqtt out")
    assert outs
    for node in outs:
        # A fixed topic overrides msg.topic: nothing upstream can redirect a publish. Node-RED
        # reads retain as a string; "false" forces false whatever msg.retain says.
        assert node["topic"], f"{node['id']} would publish to msg.topic"
        assert node["retain"] in ("false", False), f"{node['id']} retains"
        assert str(node["qos"]) == "1", node["id"]


def test_mqtt_subscriptions_are_plain_topics(flow: list[dict]) -> None:
    ins = _of_type(flow, "mqtt in")
    for node in ins:
        assert not set(node["topic"]) & {"+", "#"}, node["id"]
        assert node["datatype"] in ("utf8", "json", "auto-detect"), node["id"]
    datatypes = {n["topic"]: n["datatype"] for n in ins}
    assert datatypes[_R.status] == "json"
    assert datatypes[_R.presets] == "json"


def test_flow_subscribes_to_bearing_state_and_availability(flow: list[dict]) -> None:
    topics = {n["topic"] for n in _of_type(flow, "mqtt in")}
    assert {_R.bearing, _R.state, _R.availability, _R.status, _TOPICS.bridge_state} <= topics
    assert _R.feature(tracking.STATE) in topics
    nodes = _by_id(flow)
    for node in _of_type(flow, "mqtt in"):
        shown = [nodes[t] for t in _targets(flow, node) if nodes[t]["type"] == "debug"]
        if node["topic"] in (_R.bearing, _R.state, _R.availability, _R.feature(tracking.STATE)):
            assert shown and shown[0]["tostatus"] is True, f"{node['topic']} has no status"


def test_presets_publish_bearings_and_stop_publishes(flow: list[dict]) -> None:
    target = _mqtt_out(flow, _R.target)
    stop = _mqtt_out(flow, _R.stop)
    presets = [n for n in _of_type(flow, "inject") if target["id"] in _targets(flow, n)]
    values = set()
    for node in presets:
        assert node["payloadType"] == "num", node["name"]
        value = float(node["payload"])
        assert 0 <= value <= 360, node["name"]
        assert not node["once"] and not node["repeat"], f"{node['name']} fires by itself"
        values.add(value)
    assert values >= {0, 90, 180, 270}
    stoppers = [n for n in _of_type(flow, "inject") if stop["id"] in _targets(flow, n)]
    assert stoppers and all(not n["once"] and not n["repeat"] for n in stoppers)


def test_editor_injects_park_and_nudge(flow: list[dict]) -> None:
    park, nudge = _mqtt_out(flow, _R.park), _mqtt_out(flow, _R.nudge)
    parkers = [n for n in _of_type(flow, "inject") if park["id"] in _targets(flow, n)]
    nudgers = [n for n in _of_type(flow, "inject") if nudge["id"] in _targets(flow, n)]
    assert parkers and nudgers
    assert {n["payload"] for n in nudgers} == {"+10", "-10"}  # R/nudge: signed degrees
    for node in parkers + nudgers:
        assert node["payloadType"] == "str", node["name"]
        assert not node["once"] and not node["repeat"], f"{node['name']} fires by itself"


def test_editor_injects_start_and_end_tracking(flow: list[dict]) -> None:
    track = _mqtt_out(flow, _R.feature(tracking.COMMAND))
    trackers = [n for n in _of_type(flow, "inject") if track["id"] in _targets(flow, n)]
    assert {n["payload"] for n in trackers} == {"sun", "moon", "off"}
    for node in trackers:
        assert node["payloadType"] == "str", node["name"]
        assert not node["once"] and not node["repeat"], f"{node['name']} fires by itself"


def _page_chain(flow: list[dict]) -> tuple[dict, dict, dict]:
    nodes = _by_id(flow)
    (http_in,) = _of_type(flow, "http in")
    (template,) = [nodes[t] for t in _targets(flow, http_in)]
    (response,) = [nodes[t] for t in _targets(flow, template)]
    assert (template["type"], response["type"]) == ("template", "http response")
    return http_in, template, response


def test_web_page_is_served_with_gauge_input_presets_and_stop(flow: list[dict]) -> None:
    http_in, template, _ = _page_chain(flow)
    assert (http_in["url"], http_in["method"]) == ("/rotor", "get")
    assert template["syntax"] == "plain" and template["field"] == "payload"
    page = template["template"]
    assert page.lstrip().startswith("<!DOCTYPE html>") and page.rstrip().endswith("</html>")
    assert "<svg" in page and 'id="needle"' in page
    assert re.search(r'<input id="az" type="number" min="0" max="360"', page)
    presets = {int(v) for v in re.findall(r'data-az="(\d+)"', page)}
    assert presets >= {0, 90, 180, 270} and all(0 <= v <= 360 for v in presets)
    assert 'id="stop"' in page


def test_web_page_has_presets_locator_park_and_nudge(flow: list[dict]) -> None:
    page = _page_chain(flow)[1]["template"]
    assert '<div id="presets"' in page  # filled from rotor/presets
    assert re.search(r'<input id="locator" type="text" maxlength="8"', page)
    assert {"short", "long"} == set(re.findall(r'<option value="(\w+)"', page))
    assert 'id="park"' in page
    assert {float(v) for v in re.findall(r'data-nudge="([-+]?\d+)"', page)} == {-10, 10}
    assert 'id="aim-info"' in page and 'id="parked"' in page  # target_info and parked


def test_web_page_starts_and_ends_tracking_and_shows_it(flow: list[dict]) -> None:
    page = _page_chain(flow)[1]["template"]
    assert set(re.findall(r'data-track="(\w+)"', page)) == {"sun", "moon", "off"}
    assert re.search(r'<input id="satellite" type="text" maxlength="255"', page)
    assert 'id="tracking"' in page and 'id="track-info"' in page
    assert 'case "tracking": onTracking(v)' in page  # rotor/tracking
    # the status's tracking block as the bridge writes it (every key, a pass included) and
    # tracking_ended: the page reads each of them
    info = TrackingInfo("ISS", "waiting", 1.0, 2.0, 3.0, 4.0, 1e9, 1e9 + 600, 50.0, 180.0, True)
    info = replace(info, elements_epoch_unix=1e9 - 86400 * 30, elements_stale=True)
    keys = set(tracking.tracking_json(info)) - {"next"}  # where the body is in a minute
    assert keys >= {"body", "phase", "azimuth", "elevation", "aos", "los", "flip", "elements_stale"}
    for key in keys:
        assert f"t.{key}" in page, f"the page ignores tracking.{key}"
    assert "s.tracking, s.tracking_ended" in page


def test_web_page_never_parses_text_as_html(flow: list[dict]) -> None:
    # Preset names, error messages and the rest are the user's or the bridge's text: the page
    # builds nodes and sets textContent; any of these would let a name inject markup.
    page = _page_chain(flow)[1]["template"]
    script = page[page.index("<script>") :]
    for sink in ("innerHTML", "outerHTML", "insertAdjacentHTML", "document.write", "eval("):
        assert sink not in script, sink
    assert "textContent" in script and "createElement" in script


def test_web_page_finds_the_websocket_listener(flow: list[dict]) -> None:
    http_in, template, _ = _page_chain(flow)
    (listener,) = _of_type(flow, "websocket-listener")
    assert listener["wholemsg"] == "false"
    # The page opens "ws/" and its own name relative to its own directory (what it makes of
    # each path: test_a_second_page_opens_its_own_websocket).
    assert '"ws/$1"' in template["template"]
    page_dir, name = posixpath.split(http_in["url"])
    assert posixpath.join(page_dir, "ws", name) == listener["path"]


def test_a_second_page_opens_its_own_websocket(flow: list[dict]) -> None:
    # A station with two rotators imports the flow twice and serves the copy at /rotor-<id>
    # with a listener at /ws/rotor-<id> (docs/node-red.md): that page must open its own
    # listener, not the first page's, or it shows and turns the first rotator.
    page = _page_chain(flow)[1]["template"]
    (expression,) = re.findall(r"var wsUrl = ([^;]*);", page)
    script = f"""
        const out = {{}};
        for (const path of JSON.parse(process.argv[1])) {{
            const location = {{ protocol: "http:", host: "shack:1880", pathname: path }};
            out[path] = {expression};
        }}
        process.stdout.write(JSON.stringify(out));
    """
    paths = ["/rotor", "/rotor/", "/rotor-sat", "/red/rotor-sat", "/red/rotor"]
    proc = subprocess.run(
        [_node_js(), "-e", script, json.dumps(paths)],
        capture_output=True,
        text=True,
        timeout=slow(60),
    )
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout) == {
        "/rotor": "ws://shack:1880/ws/rotor",
        "/rotor/": "ws://shack:1880/ws/rotor",
        "/rotor-sat": "ws://shack:1880/ws/rotor-sat",
        "/red/rotor-sat": "ws://shack:1880/red/ws/rotor-sat",
        "/red/rotor": "ws://shack:1880/red/ws/rotor",
    }


def _relay(flow: list[dict]) -> dict:
    nodes = _by_id(flow)
    (ws_in,) = _of_type(flow, "websocket in")
    (relay,) = [nodes[t] for t in _targets(flow, ws_in)]
    assert relay["type"] == "function"
    return relay


def _topic_of(name: str) -> str:
    """A command's topic by its name in the relay (a registered feature's by its suffix)."""
    return getattr(_R, name) if hasattr(_R, name) else _R.feature(name)


def _relay_outputs(relay: dict) -> dict[str, int]:
    """The function's table of its outputs by name: const OUT = { target: 0, ... }."""
    table = re.search(r"const OUT = \{([^}]*)\};", relay["func"])
    assert table, "the page relay names its outputs in one table"
    return {name: int(i) for name, i in re.findall(r"(\w+): (\d+)", table.group(1))}


def test_page_commands_reach_the_target_and_stop_publishers(flow: list[dict]) -> None:
    nodes = _by_id(flow)
    target, stop = _mqtt_out(flow, _R.target), _mqtt_out(flow, _R.stop)
    relay = _relay(flow)
    reached = _targets(flow, relay)
    assert {target["id"], stop["id"]} <= reached
    publishers = {
        _mqtt_out(flow, t)["id"]
        for t in (_R.preset, _R.park, _R.nudge, _R.feature(tracking.COMMAND))
    }
    for node_id in reached - {target["id"], stop["id"]} - publishers:
        assert nodes[node_id]["type"] == "websocket out"  # the reply to that page only
    code = relay["func"]
    assert "retain: false" in code and "topic" not in code.replace("msg.topic", "")


def test_each_page_command_output_leads_to_its_own_publisher(flow: list[dict]) -> None:
    # A page message cannot pick a topic: each output of the relay is wired to exactly one
    # node, an mqtt out with a fixed topic named like the output (or the reply to the page).
    nodes = _by_id(flow)
    relay = _relay(flow)
    outputs = _relay_outputs(relay)
    assert sorted(outputs.values()) == list(range(relay["outputs"]))
    expected = {name: _mqtt_out(flow, _topic_of(name))["id"] for name in outputs if name != "reply"}
    assert set(expected) == {"target", "stop", "preset", "park", "nudge", "track"}
    for name, index in outputs.items():
        (wired,) = relay["wires"][index]
        if name == "reply":
            assert nodes[wired]["type"] == "websocket out", wired
        else:
            assert wired == expected[name], f"output {name} leads to {nodes[wired]['name']}"
            assert f'publish("{name}", ' in relay["func"], f"nothing is published on {name}"
    assert 'outputs("reply", ' in relay["func"]


def test_every_command_the_page_sends_is_one_the_relay_checks(flow: list[dict]) -> None:
    page = _page_chain(flow)[1]["template"]
    sent = set(re.findall(r'\{ cmd: "(\w+)"', page))
    checked = set(re.findall(r'cmd\.cmd === "(\w+)"', _relay(flow)["func"]))
    assert sent == {"target", "stop", "hello", "preset", "park", "nudge", "locator", "track"}
    assert sent == checked, sent ^ checked


def test_preset_and_locator_commands_are_validated_by_the_relay(flow: list[dict]) -> None:
    code = _relay(flow)["func"]
    # a preset only by a name the bridge listed on R/presets (kept by the page function)
    assert 'flow.get("rotorPresets")' in code and "names.includes(cmd.name)" in code
    to_page = [n for n in _of_type(flow, "function") if n["name"] == "to the web page"]
    assert 'flow.set("rotorPresets", ' in to_page[0]["func"]
    # a locator loosely (the bridge judges it) and the path, into the JSON R/target takes
    assert "LOCATOR.test(locator)" in code and 'path !== "short" && path !== "long"' in code
    assert "JSON.stringify({ locator: locator, path: path })" in code
    (relay_re,) = re.findall(r"const LOCATOR = /(.+)/;", code)
    (page_re,) = re.findall(r"var LOCATOR = /(.+)/;", _page_chain(flow)[1]["template"])
    assert relay_re == page_re  # the page says no only where the flow would drop it
    loose = re.compile(relay_re)  # same syntax in both; fullmatch as JS's $ (no final \n)
    for locator in ("JO62qm", "PM95VQ", "pm95vq12", "JO62", "JA", "ZZ00"):  # ZZ: the bridge's
        assert loose.fullmatch(locator), locator
    for locator in ("", "J", "JO6", "JO62q", "JO62qm1", "JO62qm123", "62JO", "JO62qm\n"):
        assert not loose.fullmatch(locator), locator


def _node_js() -> str:
    exe = shutil.which("node")
    assert exe, "node (Node.js, which Node-RED runs on) is not installed: apt-get install nodejs"
    return exe


def _run_relay(flow: list[dict], commands: list[object]) -> list[dict]:
    """Each command, as the page sends it (JSON text over the websocket), through the page
    relay's own code in Node.js, as a Node-RED function node runs it: what went out on which
    output, and the warnings."""
    harness = """
        const job = JSON.parse(require("fs").readFileSync(0, "utf8"));
        const store = {};
        let warnings = [];
        const note = (w) => warnings.push(String(w));
        const node = { warn: note, error: note };
        const flow = { get: (k) => store[k], set: (k, v) => { store[k] = v; } };
        const relay = new Function("msg", "node", "flow", job.func);
        const results = job.commands.map((cmd) => {
            warnings = [];
            const out = relay({ payload: JSON.stringify(cmd), _session: { id: "s1" } }, node, flow);
            return { out: out === undefined ? null : out, warnings: warnings };
        });
        process.stdout.write(JSON.stringify(results));
    """
    job = json.dumps({"func": _relay(flow)["func"], "commands": commands})
    proc = subprocess.run(
        [_node_js(), "-e", harness], input=job, capture_output=True, text=True, timeout=slow(60)
    )
    assert proc.returncode == 0, proc.stderr
    results = json.loads(proc.stdout)
    assert len(results) == len(commands)
    return results


def _published(relay: dict, result: dict) -> dict[str, object]:
    """Output name -> payload of what the relay sent on (and checks it is an unretained QoS 1
    message with nothing else that a publisher would read, a topic above all)."""
    out = result["out"]
    if out is None:
        return {}
    assert isinstance(out, list) and len(out) == relay["outputs"], out
    names = {i: name for name, i in _relay_outputs(relay).items()}
    sent = {}
    for index, msg in enumerate(out):
        if msg is not None:
            assert msg == {"payload": msg["payload"], "qos": 1, "retain": False}, msg
            sent[names[index]] = msg["payload"]
    return sent


# (what is typed on the page or a button sends, what goes out on R/track or None if dropped)
_TRACK_CASES: list[tuple[object, str | None]] = [
    ("sun", "sun"),
    ("moon", "moon"),
    ("off", "off"),
    (" Moon ", "moon"),
    ("OFF", "off"),
    ("ISS (ZARYA)", "ISS (ZARYA)"),
    ("  SO-50 ", "SO-50"),
    ("25544", "25544"),
    ("AO-7 [+]", "AO-7 [+]"),
    ("Åland-Sat ☀", "Åland-Sat ☀"),
    ("X" * 255, "X" * 255),  # R/track's longest name (payloads.py MAX_NAME_CHARS)
    ("X" * 256, None),
    ("", None),
    ("   ", None),
    ('{"tle": ["ISS", "1 25544U", "2 25544"]}', None),
    (" {x", None),
    ("ISS\nDROP", None),
    ("ISS\tZARYA", None),
    ("ISS\u200bZARYA", None),  # zero-width space: a format character
    ("ISS\u00a0ZARYA", None),  # no-break space: a separator but the plain space
    ("ISS\u2028ZARYA", None),  # a line separator
    ("\x7f", None),
    (None, None),
    (42, None),
    (["sun"], None),
    ({"tle": ["1 25544U", "2 25544"]}, None),
]


def test_the_relay_puts_only_checked_track_names_on_the_track_topic(flow: list[dict]) -> None:
    relay = _relay(flow)
    commands: list[object] = [{"cmd": "track", "name": name} for name, _ in _TRACK_CASES]
    results = _run_relay(flow, commands)
    for (typed, expected), result in zip(_TRACK_CASES, results, strict=True):
        sent = _published(relay, result)
        if expected is None:
            assert sent == {}, f"{typed!r} was published: {sent}"
            assert result["warnings"] and "track" in result["warnings"][0], typed
        else:
            assert sent == {"track": expected}, f"{typed!r}: {sent}"
            # what the bridge makes of it: that name, never a set of elements (JSON)
            assert payloads.parse_track(expected.encode()) == (expected, None)
    for typed, expected in _TRACK_CASES:
        if expected is None and isinstance(typed, str) and typed.strip():
            if typed.strip().startswith("{"):
                continue  # the bridge would read elements: the relay never sends JSON
            with pytest.raises(payloads.PayloadError):  # the bridge refuses it too
                payloads.parse_track(typed.encode())


def test_the_relay_sends_other_commands_to_their_own_outputs_only(flow: list[dict]) -> None:
    relay = _relay(flow)
    commands: list[object] = [
        {"cmd": "target", "value": 123},
        {"cmd": "stop"},
        {"cmd": "park"},
        {"cmd": "nudge", "value": -10},
        {"cmd": "track", "name": "sun", "topic": "rotor/target", "retain": True},
        {"cmd": "tracks", "name": "sun"},
        {"cmd": "TRACK", "name": "sun"},
    ]
    sent = [_published(relay, r) for r in _run_relay(flow, commands)]
    assert sent == [
        {"target": "123"},
        {"stop": "STOP"},
        {"park": "PARK"},
        {"nudge": "-10"},
        {"track": "sun"},  # a topic or retain flag from the page changes nothing
        {},
        {},
    ]


def test_the_page_checks_a_satellite_name_as_the_relay_does(flow: list[dict]) -> None:
    # the page says no only where the flow would drop it (a browser too old for \p{...} aside)
    (relay_re,) = re.findall(r"const TRACK_NAME = /(.+)/u;", _relay(flow)["func"])
    page = _page_chain(flow)[1]["template"]
    (page_re,) = re.findall(r'TRACK_NAME = new RegExp\("(.+)", "u"\)', page)
    assert page_re.replace("\\\\", "\\") == relay_re
    assert 'name.charAt(0) === "{"' in page and 'name.startsWith("{")' in _relay(flow)["func"]


def test_the_page_script_and_every_function_node_are_javascript_that_parses(
    flow: list[dict],
) -> None:
    # A slip in the page's script loses the whole page, its STOP button included; one in a
    # function node loses that node. Node.js compiles each without running it.
    page = _page_chain(flow)[1]["template"]
    script = page[page.index("<script>") + len("<script>") : page.index("</script>")]
    sources = {"the page": script} | {n["name"]: n["func"] for n in _of_type(flow, "function")}
    checker = """
        const sources = JSON.parse(require("fs").readFileSync(0, "utf8"));
        const Async = Object.getPrototypeOf(async function () {}).constructor;
        const bad = {};
        for (const [name, code] of Object.entries(sources)) {
            try {
                name === "the page" ? new Function(code) : new Async("msg", "node", "flow", code);
            } catch (e) {
                bad[name] = String(e);
            }
        }
        process.stdout.write(JSON.stringify(bad));
    """
    proc = subprocess.run(
        [_node_js(), "-e", checker],
        input=json.dumps(sources),
        capture_output=True,
        text=True,
        timeout=slow(60),
    )
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout) == {}


def test_presets_reach_the_web_page(flow: list[dict]) -> None:
    nodes = _by_id(flow)
    (presets,) = [n for n in _of_type(flow, "mqtt in") if n["topic"] == _R.presets]
    (to_page,) = [nodes[t] for t in _targets(flow, presets) if nodes[t]["type"] == "function"]
    kinds = re.search(r"const KINDS = \[([^\]]*)\]", to_page["func"])
    assert kinds and '"presets"' in kinds.group(1)
    page = _page_chain(flow)[1]["template"]
    assert 'case "presets": onPresets(v)' in page


def test_every_subscribed_kind_is_passed_on_and_shown(flow: list[dict]) -> None:
    (to_page,) = [n for n in _of_type(flow, "function") if n["name"] == "to the web page"]
    kinds = re.search(r"const KINDS = \[([^\]]*)\]", to_page["func"])
    assert kinds
    passed = set(re.findall(r'"(\w+)"', kinds.group(1)))
    page = _page_chain(flow)[1]["template"]
    for node in _of_type(flow, "mqtt in"):
        topic = node["topic"]
        kind = "bridge" if topic == _TOPICS.bridge_state else topic.rsplit("/", 1)[1]
        assert kind in passed, f"{topic} never reaches the page"
        assert f'case "{kind}":' in page, f"the page ignores {topic}"


def test_state_reaches_the_web_page(flow: list[dict]) -> None:
    nodes = _by_id(flow)
    for node in _of_type(flow, "mqtt in"):
        kinds = {nodes[t]["type"] for t in _targets(flow, node)}
        assert "function" in kinds, f"{node['topic']} does not reach the page"
        for t in _targets(flow, node):
            if nodes[t]["type"] == "function":
                assert {nodes[x]["type"] for x in _targets(flow, nodes[t])} == {"websocket out"}


# ---------------------------------------------------------------------------------------------
# systemd
# ---------------------------------------------------------------------------------------------


def _unit_settings(text: str) -> dict[str, dict[str, list[str]]]:
    sections: dict[str, dict[str, list[str]]] = {}
    current = None
    for raw in text.splitlines():
        line = raw.strip()
        if not line or line.startswith(("#", ";")):
            continue
        if line.startswith("["):
            current = sections.setdefault(line.strip("[]"), {})
            continue
        assert current is not None and "=" in line, f"not a setting: {raw!r}"
        key, value = line.split("=", 1)
        current.setdefault(key.strip(), []).append(value.strip())
    return sections


@pytest.fixture(scope="module")
def unit() -> dict[str, dict[str, list[str]]]:
    return _unit_settings(UNIT.read_text())


def _one(unit: dict, section: str, key: str) -> str:
    values = unit[section].get(key)
    assert values and len(values) == 1, f"[{section}] {key}= expected once, got {values}"
    return values[0]


def test_unit_runs_the_bridge_with_its_config(unit: dict) -> None:
    argv = shlex.split(_one(unit, "Service", "ExecStart"))
    assert argv[0] == SHIPPED_EXEC
    args = build_parser().parse_args(argv[1:])
    assert (args.command, args.config) == ("run", SHIPPED_CONFIG)


def test_unit_restarts_on_failure_but_not_on_a_config_error(unit: dict) -> None:
    assert _one(unit, "Service", "Restart") == "on-failure"
    assert 1 <= float(_one(unit, "Service", "RestartSec")) <= 60
    assert str(EXIT_CONFIG) in _one(unit, "Service", "RestartPreventExitStatus").split()
    assert 5 <= float(_one(unit, "Service", "TimeoutStopSec")) <= 60


def test_unit_runs_unprivileged_in_dialout(unit: dict) -> None:
    user = _one(unit, "Service", "User")
    assert user == "rotor-bridge"
    assert "dialout" in _one(unit, "Service", "SupplementaryGroups").split()
    assert not unit["Service"].get("AmbientCapabilities", [""])[0]
    sysusers = [line.split() for line in SYSUSERS.read_text().splitlines()]
    sysusers = [f for f in sysusers if f and not f[0].startswith("#")]
    assert ["u", user] == sysusers[0][:2]
    assert ["m", user, "dialout"] in sysusers


def test_every_useradd_for_the_service_makes_the_group_the_unit_runs_in(unit: dict) -> None:
    # Group=rotor-bridge and `chown root:rotor-bridge` need that group; plain `useradd --system`
    # makes it only where login.defs says USERGROUPS_ENAB yes, else the user lands in `users`
    group = _one(unit, "Service", "Group")
    assert group == _one(unit, "Service", "User")
    found = 0
    for path in (ROOT / "README.md", ROOT / "docs" / "deployment.md", UNIT):
        text = path.read_text().replace("\\\n", " ").replace("#  ", " ")
        for line in text.splitlines():
            if "useradd " in line and line.rstrip().endswith(f" {group}"):
                found += 1
                assert "--user-group" in line.split(), (path.name, line)
    assert found == 3


def test_unit_orders_after_the_network(unit: dict) -> None:
    assert "network-online.target" in _one(unit, "Unit", "After").split()
    assert "network-online.target" in _one(unit, "Unit", "Wants").split()
    assert _one(unit, "Install", "WantedBy") == "multi-user.target"


def test_unit_state_directory_is_where_the_bridge_keeps_state(
    unit: dict, monkeypatch: pytest.MonkeyPatch
) -> None:
    name = _one(unit, "Service", "StateDirectory")
    assert name == "rotor-bridge"
    # systemd exports StateDirectory= as $STATE_DIRECTORY=/var/lib/<name>.
    monkeypatch.setenv("STATE_DIRECTORY", f"/var/lib/{name}")
    settings = load_settings(ROOT / "config" / "example.toml", environ={})
    assert settings.state_file == Path(f"/var/lib/{name}/state.json")
    # what check-config, run by hand, says the unit's state file is
    assert Path(SERVICE_STATE_FILE) == settings.state_file


def test_unit_is_hardened_without_hiding_serial_ports(unit: dict) -> None:
    service = unit["Service"]
    assert _one(unit, "Service", "NoNewPrivileges") == "yes"
    assert _one(unit, "Service", "ProtectSystem") == "strict"
    assert _one(unit, "Service", "ProtectHome") == "yes"
    assert _one(unit, "Service", "PrivateTmp") == "yes"
    # Each of these would cut off /dev/ttyUSB* (and so /dev/serial/by-id): PrivateDevices hides
    # real devices; any DeviceAllow, also the one ProtectClock implies, makes the device policy
    # an allow-list resolved when the service starts, before a late-plugged adapter exists.
    for key in ("PrivateDevices", "ProtectClock"):
        assert service.get(key, ["no"]) == ["no"], f"{key}= would block the serial port"
    assert "DeviceAllow" not in service and "DevicePolicy" not in service
    assert "InaccessiblePaths" not in service and "TemporaryFileSystem" not in service


def _systemd_analyze() -> str:
    exe = shutil.which("systemd-analyze")
    assert exe, (
        "systemd-analyze is not installed; it comes with the Debian package 'systemd' "
        "(apt-get install systemd)"
    )
    return exe


def _verify(unit_text: str, tmp_path: Path) -> subprocess.CompletedProcess[str]:
    # verify insists that ExecStart's program exists: point it at a stand-in executable.
    fake = tmp_path / "bin" / "rotor-bridge"
    fake.parent.mkdir()
    fake.write_text("#!/bin/sh\nexit 0\n")
    fake.chmod(0o755)
    assert SHIPPED_EXEC in unit_text
    path = tmp_path / "rotor-bridge.service"
    path.write_text(unit_text.replace(SHIPPED_EXEC, str(fake)))
    env = {k: v for k, v in os.environ.items() if not k.startswith("SYSTEMD_")}
    return subprocess.run(
        [_systemd_analyze(), "verify", str(path)],
        capture_output=True,
        text=True,
        timeout=slow(120),
        env=env,
        cwd=tmp_path,
    )


def test_unit_passes_systemd_analyze_verify(tmp_path: Path) -> None:
    proc = _verify(UNIT.read_text(), tmp_path)
    output = (proc.stdout + proc.stderr).strip()
    assert proc.returncode == 0 and not output, output


def test_systemd_analyze_verify_reports_a_broken_unit(tmp_path: Path) -> None:
    # The check above relies on verify printing what it dislikes; make sure it does here.
    broken = UNIT.read_text().replace("Restart=on-failure", "Restart=on-failure\nRestartz=1")
    proc = _verify(broken, tmp_path)
    assert "Restartz" in proc.stdout + proc.stderr


# ---------------------------------------------------------------------------------------------
# udev
# ---------------------------------------------------------------------------------------------

_UDEV_TOKEN = re.compile(r'^([A-Z_]+(?:\{[^}]+\})?)(==|!=|\+=|-=|:=|=)"([^"]*)"$')
_UDEV_MATCH_ONLY = ("SUBSYSTEM", "ATTRS{", "KERNEL", "ACTION", "DRIVERS", "SUBSYSTEMS")


def _udev_rules() -> list[dict[str, tuple[str, str]]]:
    rules = []
    for line in UDEV.read_text().splitlines():
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        rule: dict[str, tuple[str, str]] = {}
        for token in (t.strip() for t in line.split(",")):
            m = _UDEV_TOKEN.match(token)
            assert m, f"not a udev key=value: {token!r}"
            key, op, value = m.groups()
            if key.startswith(_UDEV_MATCH_ONLY):
                assert op in ("==", "!="), f"{key} is a match key: use =="
            else:
                assert op in ("=", "+=", ":="), f"{key}{op}: an assignment needs = or +="
            rule[key] = (op, value)
        rules.append(rule)
    return rules


@pytest.mark.parametrize("path", [UNIT, SYSUSERS, UDEV], ids=lambda p: p.name)
def test_install_commands_in_a_deploy_file_work_from_the_top_of_the_repository(
    path: Path,
) -> None:
    """Each file says where its commands run, and each file they copy is there."""
    text = path.read_text()
    assert "from the top of the rotor-bridge repository" in text
    copies = 0
    for line in (line for line in text.splitlines() if "cp " in line):
        for command in line.lstrip("# (").removeprefix("or: ").split("&&"):
            argv = shlex.split(command.split("#")[0].rstrip(") "))
            argv = argv[1:] if argv[:1] == ["sudo"] else argv
            if argv[:1] == ["cp"]:
                copies += 1
                assert (ROOT / argv[1]).is_file(), f"{path.name}: {command.strip()}"
    assert copies


def test_udev_rule_gives_the_adapter_a_stable_name_for_group_dialout() -> None:
    (rule,) = _udev_rules()
    assert rule["SUBSYSTEM"] == ("==", "tty")
    assert rule["ATTRS{idVendor}"] == ("==", "0403")
    assert rule["ATTRS{idProduct}"] == ("==", "6001")
    assert rule["ATTRS{serial}"][0] == "=="
    assert rule["SYMLINK"] == ("+=", "rotor-tower")
    assert rule["GROUP"] == ("=", "dialout")
    assert rule["MODE"] == ("=", "0660")


def test_udev_rule_explains_how_to_find_the_values() -> None:
    text = UDEV.read_text()
    for hint in ("udevadm info -a -n /dev/ttyUSB0", "rotor-bridge ports", "/dev/serial/by-id/"):
        assert hint in text, hint
    assert UDEV.name.endswith(".rules")


# ---------------------------------------------------------------------------------------------
# Docker
# ---------------------------------------------------------------------------------------------


def _scalar(text: str) -> str:
    text = text.strip()
    if len(text) >= 2 and text[0] == text[-1] and text[0] in "\"'":
        return text[1:-1]
    return text


def read_block_yaml(text: str) -> object:
    """The YAML subset compose.yaml is written in: block mappings, block lists of scalars,
    quoted or plain scalars, comments. Anything else is refused, so the file stays readable
    by this and by every YAML parser alike."""
    lines = []
    for raw in text.splitlines():
        stripped = raw.split(" #", 1)[0].rstrip() if not raw.lstrip().startswith("#") else ""
        if stripped:
            assert "\t" not in raw[: len(raw) - len(raw.lstrip())], "tab indentation"
            assert not stripped.lstrip().startswith(("{", "[", "&", "*", "|", ">")), raw
            lines.append((len(stripped) - len(stripped.lstrip()), stripped.strip()))

    def block(i: int, indent: int) -> tuple[object, int]:
        if lines[i][1].startswith("- "):
            items = []
            while i < len(lines) and lines[i][0] == indent and lines[i][1].startswith("- "):
                items.append(_scalar(lines[i][1][2:]))
                i += 1
            return items, i
        mapping: dict[str, object] = {}
        while i < len(lines) and lines[i][0] == indent:
            key, sep, rest = lines[i][1].partition(":")
            assert sep and (not rest or rest.startswith(" ")), f"not 'key: value': {lines[i]}"
            assert key not in mapping, f"duplicate key {key}"
            i += 1
            if rest.strip():
                mapping[key] = _scalar(rest)
            elif i < len(lines) and lines[i][0] > indent:
                mapping[key], i = block(i, lines[i][0])
            else:
                mapping[key] = None
        return mapping, i

    doc, end = block(0, 0)
    assert end == len(lines), f"unexpected indentation at {lines[end]}"
    return doc


@pytest.fixture(scope="module")
def compose() -> dict:
    doc = read_block_yaml((DOCKER / "compose.yaml").read_text())
    assert isinstance(doc, dict)
    return doc


@pytest.fixture(scope="module")
def docker_settings():
    return load_settings(DOCKER / "rotor-bridge.toml", environ={})


def _dockerfile() -> list[tuple[str, str]]:
    text = (DOCKER / "Dockerfile").read_text().replace("\\\n", " ")
    out = []
    for line in text.splitlines():
        if line.strip() and not line.lstrip().startswith("#"):
            word, _, rest = line.strip().partition(" ")
            out.append((word.upper(), rest.strip()))
    return out


def _instructions(name: str) -> list[str]:
    return [rest for word, rest in _dockerfile() if word == name]


def test_compose_reads_the_same_with_a_yaml_parser(compose: dict) -> None:
    try:
        import yaml
    except ImportError:  # not a dependency; the subset reader above is then the only judge
        return
    assert yaml.safe_load((DOCKER / "compose.yaml").read_text()) == compose


def interpolate(value: str, env: dict[str, str]) -> str:
    """Compose's ${VAR}, ${VAR:-default} and ${VAR:?error} in ``value``, from ``env``."""

    def one(m: re.Match[str]) -> str:
        name, op, arg = m.group(1), m.group(2), m.group(3)
        if env.get(name):
            return env[name]
        if op == ":?":
            raise ValueError(f"{name}: {arg}")
        return arg if op == ":-" else ""

    return re.sub(r"\$\{(\w+)(?:(:-|:\?)([^}]*))?\}", one, value)


def bridge_environment(compose: dict, **shell: str) -> dict[str, str]:
    """The bridge container's environment as compose makes it from ``shell``."""
    env = compose["services"]["rotor-bridge"]["environment"]
    return {key: interpolate(value, shell) for key, value in env.items()}


def settings_in_container(env: dict[str, str], monkeypatch: pytest.MonkeyPatch) -> Settings:
    """rotor-bridge.toml read as the bridge reads it in the container, with ``env`` set."""
    for key, value in env.items():
        monkeypatch.setenv(key, value)
    return load_settings(DOCKER / "rotor-bridge.toml", environ=env)


def test_compose_runs_the_bridge_alone_against_the_broker_the_user_names(
    compose: dict, monkeypatch: pytest.MonkeyPatch
) -> None:
    services = compose["services"]
    assert "profiles" not in services["rotor-bridge"]
    default = [name for name, svc in services.items() if "profiles" not in svc]
    assert default == ["rotor-bridge"]  # no broker of its own unless asked for
    assert "depends_on" not in services["rotor-bridge"]  # it retries until the broker answers
    with pytest.raises(ValueError, match="MQTT_HOST"):  # compose refuses to start without it
        bridge_environment(compose)
    env = bridge_environment(compose, MQTT_HOST="192.168.1.10")
    s = settings_in_container(env, monkeypatch)
    assert (s.mqtt.host, s.mqtt.port) == ("192.168.1.10", 1883)
    env = bridge_environment(compose, MQTT_HOST="ha.lan", MQTT_PORT="1884")
    s = settings_in_container(env, monkeypatch)
    assert (s.mqtt.host, s.mqtt.port) == ("ha.lan", 1884)


def test_the_private_broker_profile_runs_mosquitto_where_the_bridge_looks(
    compose: dict, monkeypatch: pytest.MonkeyPatch
) -> None:
    mosquitto = compose["services"]["mosquitto"]
    assert mosquitto["profiles"] == ["private-broker"]
    env = bridge_environment(compose, MQTT_HOST="mosquitto")  # as compose.yaml's comment says
    s = settings_in_container(env, monkeypatch)
    assert s.mqtt.host in compose["services"]
    conf = (DOCKER / "mosquitto.conf").read_text()
    assert re.search(rf"^listener {s.mqtt.port}\b", conf, re.M)
    if s.mqtt.username is None:
        assert re.search(r"^allow_anonymous true$", conf, re.M)
    assert "MQTT_HOST=mosquitto docker compose --profile private-broker up" in " ".join(
        (DOCKER / "compose.yaml").read_text().split()
    )


def test_docker_config_validates_without_the_environment(docker_settings) -> None:
    (rotator,) = docker_settings.rotators
    assert isinstance(rotator.port, str) and rotator.port == "/dev/rotor"


def test_the_docker_config_reaches_a_broker_without_mqtt_5(docker_settings) -> None:
    """The container runs against whatever broker the station has (NATS, aedes, RabbitMQ 3
    speak MQTT 3.1.1 alone): its configuration forces no protocol, and the docs say so."""
    assert docker_settings.mqtt.protocol == "auto"
    assert type(docker_settings.mqtt).model_fields["protocol"].default == "auto"
    docker = (
        (ROOT / "docs" / "deployment.md").read_text().split("## Docker", 1)[1].split("\n## ", 1)[0]
    )
    assert '`mqtt.protocol` at its default, `"auto"`' in " ".join(docker.split())


def test_compose_passes_the_serial_device_to_the_bridge(compose: dict, docker_settings) -> None:
    bridge = compose["services"]["rotor-bridge"]
    (device,) = bridge["devices"]
    host, container = device.split(":")
    assert host.startswith("/dev/serial/by-id/usb-")
    assert container == docker_settings.rotators[0].port
    assert "dialout" in bridge["group_add"]
    assert bridge["restart"] == "unless-stopped"


def test_compose_mounts_config_and_state_where_the_image_expects_them(
    compose: dict, docker_settings
) -> None:
    bridge = compose["services"]["rotor-bridge"]
    mounts = [v.split(":") for v in bridge["volumes"]]
    config_arg = json.loads(_instructions("CMD")[-1])
    config_path = build_parser().parse_args(config_arg).config
    config_mounts = [m for m in mounts if m[1] == config_path]
    assert config_mounts and (DOCKER / config_mounts[0][0]).resolve() == (
        DOCKER / "rotor-bridge.toml"
    )
    state_dir = str(docker_settings.state_file.parent)
    state_mounts = [m for m in mounts if m[1] == state_dir]
    assert state_mounts and state_mounts[0][0] in compose["volumes"]
    assert f"STATE_DIRECTORY={state_dir}" in _instructions("ENV")


def test_compose_builds_from_the_repository_root(compose: dict) -> None:
    build = compose["services"]["rotor-bridge"]["build"]
    context = (DOCKER / build["context"]).resolve()
    assert context == ROOT
    assert (context / build["dockerfile"]).resolve() == DOCKER / "Dockerfile"


def test_compose_runs_mosquitto_with_the_mounted_config(compose: dict) -> None:
    mosquitto = compose["services"]["mosquitto"]
    assert mosquitto["image"].startswith("eclipse-mosquitto:")
    mounts = [v.split(":") for v in mosquitto["volumes"]]
    assert ["./mosquitto.conf", "/mosquitto/config/mosquitto.conf", "ro"] in mounts
    assert mosquitto["restart"] == "unless-stopped"


def test_dockerfile_installs_the_project_and_runs_unprivileged() -> None:
    assert _instructions("FROM") == ["${PYTHON_IMAGE}"]
    assert "PYTHON_IMAGE=python:3.11-slim-bookworm" in _instructions("ARG")
    readme = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["readme"]
    copied = [src for rest in _instructions("COPY") for src in rest.split()[:-1]]
    assert readme in copied and "pyproject.toml" in copied and "bridge" in copied
    for src in copied:
        assert (ROOT / src).exists(), f"COPY {src}: not in the build context"
    (user,) = _instructions("USER")
    assert user.split(":")[0] not in ("root", "0")
    assert any("--groups dialout" in run for run in _instructions("RUN"))
    assert json.loads(_instructions("ENTRYPOINT")[-1]) == ["rotor-bridge"]
    args = build_parser().parse_args(json.loads(_instructions("CMD")[-1]))
    assert args.command == "run"


def test_dockerfile_says_where_32_bit_arm_gets_numpy() -> None:
    """PyPI has no numpy wheels for linux/arm/v7: piwheels' (built for Raspberry Pi OS Bookworm,
    the image's Debian, and its Python 3.11), with the OpenBLAS they link."""
    args = _instructions("ARG")
    assert "TARGETARCH" in args and "ARM32_INDEX_URL=https://www.piwheels.org/simple" in args
    runs = " ".join(_instructions("RUN"))
    assert '[ "$TARGETARCH" = "arm" ]' in runs and "libopenblas0" in runs
    assert 'PIP_EXTRA_INDEX_URL="$ARM32_INDEX_URL" PIP_PREFER_BINARY=1' in runs
    python = re.search(r"python:(\d+\.\d+)-slim-(\w+)", " ".join(args))
    assert python is not None and python.groups() == ("3.11", "bookworm")
    assert "linux/arm/v7" in (DOCKER / "Dockerfile").read_text()


# ---------------------------------------------------------------------------------------------
# Documentation and licence: they describe this code, and a clone has everything they name
# ---------------------------------------------------------------------------------------------
README = ROOT / "README.md"
EXAMPLE = ROOT / "config" / "example.toml"
DOCS = [README, *sorted((ROOT / "docs").glob("*.md"))]


def _section(text: str, heading: str) -> str:
    start = text.index(f"\n{heading}\n")
    end = text.find("\n## ", start + len(heading) + 2)
    return text[start : end if end != -1 else len(text)]


def _shell_commands(markdown: str) -> list[list[str]]:
    """The commands of every ```sh block, continuation lines joined, comments dropped."""
    commands = []
    for block in re.findall(r"```sh\n(.*?)```", markdown, re.S):
        for line in block.replace("\\\n", " ").splitlines():
            for command in re.split(r"&&|;", line):
                argv = shlex.split(command, comments=True)
                if argv:
                    commands.append(argv)
    return commands


def test_the_licence_file_is_the_mit_licence_pyproject_names() -> None:
    licence = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["license"]
    assert licence == {"text": "MIT"}
    text = (ROOT / "LICENSE").read_text()
    assert text.splitlines()[:3] == [
        "MIT License",
        "",
        "Copyright (c) 2026 rotor-bridge contributors",
    ]
    words = " ".join(text.split())
    assert "Permission is hereby granted, free of charge, to any person obtaining a copy" in words
    assert 'THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND' in words
    assert "[LICENSE](LICENSE)" in README.read_text()


@pytest.mark.parametrize("path", sorted((ROOT / "config").glob("*.toml")), ids=lambda p: p.name)
def test_a_configuration_files_check_command_runs_as_typed(path: Path) -> None:
    """The README's install puts the bridge in a venv whose bin/ is not on PATH: the plain
    `rotor-bridge check-config -c rotor-bridge.toml` these files said was "command not found"
    (and named a file in no folder the README puts one)."""
    lines = [line.removeprefix("#").strip() for line in path.read_text().splitlines()]
    commands = [shlex.split(line) for line in lines if "check-config" in line.split()]
    assert commands
    for argv in commands:
        assert argv[0] == SHIPPED_EXEC, argv
        args = build_parser().parse_args(argv[1:])
        assert args.command == "check-config"
        assert args.config == SHIPPED_CONFIG or (ROOT / args.config).resolve() == path, argv


@pytest.mark.parametrize("path", [EXAMPLE, DOCKER / "rotor-bridge.toml"], ids=["example", "docker"])
def test_configuration_files_name_every_model(path: Path) -> None:
    (comment,) = re.findall(r'^model = "[\w-]+"\s*#(.*)$', path.read_text(), re.M)
    assert [m.strip() for m in comment.split("|")] == list(REGISTRY), comment


def test_the_readme_names_every_model_wherever_it_lists_them(tmp_path: Path) -> None:
    text = README.read_text()
    # the error example is what the bridge really prints for a misspelt model
    bad = tmp_path / "bad.toml"
    bad.write_text('[[rotators]]\nid = "tower"\nmodel = "rotorz"\nport = "/dev/ttyUSB0"\n')
    with pytest.raises(ConfigError) as exc:
        load_settings(bad, environ={})
    assert f"```\nrotor-bridge: {exc.value}\n```" in text
    # every run of three or more model names in backticks is the whole list
    name = "|".join(REGISTRY)
    runs = re.finditer(rf"`(?:{name})`(?:(?:,|, or| or|, and| and)\s+`(?:{name})`)+", text)
    lists = [set(re.findall(r"`([\w-]+)`", m.group(0))) for m in runs]  # gs232b-az
    lists = [found for found in lists if len(found) >= 3]
    assert lists and all(found == set(REGISTRY) for found in lists), lists


def test_the_password_file_mode_is_one_answer_everywhere(tmp_path: Path) -> None:
    """The service user must read it, every other user must not: group rotor-bridge, 640."""
    for path in (README, EXAMPLE, UNIT):
        text = path.read_text()
        assert set(re.findall(r"chmod (\d+)", text)) == {"640"}, path
        assert "chown root:rotor-bridge" in text, path
    pw = tmp_path / "pw"
    pw.write_text("S3cret\n")
    config = tmp_path / "c.toml"
    config.write_text(
        f'[mqtt]\nusername = "u"\npassword_file = "{pw}"\n'
        '[[rotators]]\nid = "tower"\nmodel = "rotorez"\nport = "/dev/ttyUSB0"\n'
    )
    os.chmod(pw, 0o644)
    with pytest.raises(ConfigError) as exc:
        load_settings(config, environ={})
    assert "readable by every user" in str(exc.value)
    assert "chown root:rotor-bridge, chmod 640" in str(exc.value)  # the same answer
    os.chmod(pw, 0o640)
    password = load_settings(config, environ={}).mqtt.password
    assert password is not None and password.get_secret_value() == "S3cret"


@pytest.mark.parametrize("heading", ["## Install for real", "### systemd"])
def test_the_readme_install_commands_work_as_typed(heading: str) -> None:
    """From the top of a clone; the venv's bin/ is not on PATH, so its programs by full path."""
    commands = _shell_commands(_section(README.read_text(), heading))
    assert commands
    venv = posixpath.dirname(posixpath.dirname(SHIPPED_EXEC))
    for argv in commands:
        if argv[0] == "sudo":
            argv = argv[1:]
        assert argv[0] not in ("rotor-bridge", "pip", "python", "pip3"), argv
        if argv[0] == SHIPPED_EXEC:
            build_parser().parse_args(argv[1:])  # a real subcommand with real options
        elif argv[0] == f"{venv}/bin/pip":
            assert argv[1:] == ["install", "."]  # this repository
        elif argv[0] in ("cp", "install") and not argv[1].startswith("-"):
            assert (ROOT / argv[1]).exists(), argv
    assert any(argv[-2:] == ["-c", SHIPPED_CONFIG] for argv in commands)


@pytest.mark.parametrize(
    ("doc", "heading"),
    [
        ("README.md", "## Install for real"),
        ("docs/deployment.md", "## Install into a virtual environment"),
        ("docs/deployment.md", "## systemd"),
        ("docs/deployment.md", "## Upgrading"),
    ],
)
def test_installing_as_root_leaves_the_clone_to_its_user(doc: str, heading: str) -> None:
    """pip builds in the clone: as root it leaves build/ and the egg-info there owned by root,
    and the user's ./demo and ./tests/run (an editable install) then fail: "Cannot update
    time stamp of directory 'rotor_bridge.egg-info'". The commands remove them again."""
    name = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["name"]
    leftovers = {"build", name.replace("-", "_") + ".egg-info"}
    commands = _shell_commands(_section((ROOT / doc).read_text(), heading))
    installs = [i for i, argv in enumerate(commands) if argv[-2:] == ["install", "."]]
    assert installs, "no pip install . here"
    for i in installs:
        removed = set()
        for argv in commands[i + 1 :]:
            argv = argv[1:] if argv[:1] == ["sudo"] else argv
            if argv[:2] == ["rm", "-rf"]:
                removed |= set(argv[2:])
        assert leftovers <= removed, (doc, heading, commands[i])


def test_upgrading_installs_into_the_units_venv_checks_the_file_then_restarts(unit: dict) -> None:
    """A user upgrading finds the steps: the same venv and configuration the unit runs, the
    file checked before the restart (a refused value would end the restart with exit code 2,
    which the unit does not retry), then the unit restarted."""
    commands = _shell_commands(
        _section((ROOT / "docs" / "deployment.md").read_text(), "## Upgrading")
    )
    venv = posixpath.dirname(posixpath.dirname(SHIPPED_EXEC))
    service = UNIT.name.removesuffix(".service")
    steps = [argv[1:] if argv[:1] == ["sudo"] else argv for argv in commands]
    install = steps.index([f"{venv}/bin/pip", "install", "."])
    check = steps.index([SHIPPED_EXEC, "check-config", "-c", SHIPPED_CONFIG])
    restart = steps.index(["systemctl", "restart", service])
    assert install < check < restart
    assert shlex.split(_one(unit, "Service", "ExecStart"))[-2:] == ["-c", SHIPPED_CONFIG]


def test_docs_name_only_files_a_clone_has() -> None:
    for doc in DOCS:
        text = doc.read_text()
        assert "../" not in text and "shared/" not in text, doc
        targets = re.findall(r"\]\(([^)\s]+)\)", text)
        paths = re.findall(r"`((?:deploy|config|docs|tests|bridge|benchmarks)/[^`\s]*)`", text)
        files = [t.partition("#")[0] for t in targets if not re.match(r"[a-z]+:|#", t)]
        for target in files + paths:  # anchors: tests/test_docs.py
            path = (doc.parent / target).resolve()
            if not path.exists():
                path = (ROOT / target).resolve()
            assert path.exists() and path.is_relative_to(ROOT), (doc.name, target)
