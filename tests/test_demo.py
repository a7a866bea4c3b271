"""The README's demo path: `rotor-bridge demo` with no broker running brings up its own, prints the
topics of its own (never the real bridge's `rotor`), turns its emulated rotators on a published or
typed target, and leaves nothing behind (no broker on the port, no temporary folder) however it
ends."""

from __future__ import annotations

import json
import os
import signal
import socket
import termios
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from bridge import demo, emulators
from bridge.cli import build_parser
from bridge.core import geo
from bridge.demo import sky as demo_sky
from bridge.demo.mosquitto import BrokerError
from bridge.demo.mosquitto import Mosquitto as PrivateBroker
from bridge.interfaces.homeassistant import Identity
from bridge.sky import parse_tles
from tests.demo_process import DemoProcess
from tests.support import Probe, retained_snapshot
from tests.support.mosquitto import answers, free_port
from tests.support.sky import sgp4_altaz
from tests.support.waiting import slow, wait_until

ALL_MODELS = ["rotorez", "rotorcard", "dcu1", "rot2prog", "rot1prog", "md01", "satel"]
ALL_MODELS += [
    "gs232a",
    "gs232b",
    "gs232a-az",
    "gs232b-az",
    "gs232a-450",
    "gs232b-450",
    "gs232a-az-450",
    "gs232b-az-450",
]
ALL_MODELS += [f"easycomm{v}{s}" for v in (2, 3) for s in ("", "-az", "-separate")]
ALL_MODELS += ["rt21", "prosistel", "prosistel-el", "prosistel-el-a", "prosistel-combi"]
ALL_MODELS += ["rc2800", "rc2800-az"]


def _left_behind(tmpdir: Path) -> list[str]:
    return sorted(p.name for p in tmpdir.iterdir())


def test_a_private_broker_whose_port_another_program_holds_is_not_taken_for_started(
    tmp_path: Path,
) -> None:
    """Another program listening on the port answered before mosquitto had tried to bind it:
    ``start`` returned, mosquitto exited ("Address already in use"), and every client reached
    the other program's broker (under two suites at once a test froze its own broker and its
    client, on another test's, never gave up). The start fails, in mosquitto's words."""
    with socket.socket() as other:
        other.bind(("127.0.0.1", 0))
        other.listen()
        broker = PrivateBroker(tmp_path, port=other.getsockname()[1])
        try:
            with pytest.raises(BrokerError, match="Address already in use"):
                broker.start(slow(10))
        finally:
            broker.stop()


def test_demo_turns_on_a_published_and_a_typed_target_and_q_ends_it_cleanly(
    tmp_path: Path,
) -> None:
    port = free_port()
    tmpdir = tmp_path / "tmp"
    proc = DemoProcess(["--mqtt-port", str(port), "--speed-deg-s", "60"], tmpdir, terminal=True)
    probe = None
    try:
        base = proc.base_topic()
        assert base.startswith("rotor-demo-") and len(base) == len("rotor-demo-") + 4, base
        proc.wait_line(rf"turn:  mosquitto_pub -h 127\.0\.0\.1 -p {port} -t {base}/target -m 120$")
        assert "private mosquitto" in proc.output
        probe = Probe(port, f"{base}/#")
        probe.wait_value(f"{base}/availability", "online", timeout_s=20)
        probe.wait_value(f"{base}/state", "idle", timeout_s=20)
        snap = retained_snapshot(port, f"{base}/#")
        for leaf in ("bearing", "state", "status", "version", "availability"):
            assert f"{base}/{leaf}" in snap, leaf
        assert snap[f"{base}/bridge/state"] == b"online"

        # as printed: mosquitto_pub -t <base>/target -m 120
        probe.publish(f"{base}/target", "120")
        probe.wait_for(f"{base}/state", lambda m: m.text == "moving")
        there = probe.wait_for(
            f"{base}/bearing", lambda m: abs(float(m.text) - 120) <= 3, timeout_s=20
        )
        msg = probe.wait_for(  # (the status that showed the target waiting was idle too)
            f"{base}/status",
            lambda m: (
                json.loads(m.payload)["state"] == "idle"
                and json.loads(m.payload)["last_command_source"] == "mqtt"
            ),
            timeout_s=20,
            after=there.t,
        )
        assert abs(json.loads(msg.payload)["bearing"] - 120) <= 3

        seen = proc.type("help")
        for what in (f"-> {base}/target", "s, stop", "lock on|off", "el 30", "q "):
            proc.wait_line(what.replace("|", r"\|"), start=seen, timeout_s=10)
        seen = proc.type("nonsense")
        proc.wait_line(r"unknown command 'nonsense'; type 'help'", start=seen, timeout_s=10)

        proc.type("200")  # a bearing typed into the demo goes over MQTT like any other
        probe.wait_for(f"{base}/bearing", lambda m: abs(float(m.text) - 200) <= 3, timeout_s=20)
        proc.type("q")
        assert proc.wait(slow(20)) == 0, proc.output
        assert "rotor-bridge demo: stopping (q typed)" in proc.output
    except AssertionError as exc:  # what the demo printed says why (it failed once under load)
        raise AssertionError(f"{exc}\nthe demo printed:\n{proc.output[-4000:]}") from None
    finally:
        if probe is not None:
            probe.close()
        proc.close()
    assert not answers("127.0.0.1", port), "the demo's private broker outlived it"
    assert _left_behind(tmpdir) == []


def test_the_demo_prompt_turns_by_preset_locator_path_nudge_and_park(tmp_path: Path) -> None:
    port = free_port()
    args = ["--mqtt-port", str(port), "--speed-deg-s", "360", "--models", "rotorcard"]
    proc = DemoProcess(args, tmp_path / "tmp", terminal=True)
    probe = None
    try:
        base = proc.base_topic()
        probe = Probe(port, f"{base}/#")
        probe.wait_value(f"{base}/state", "idle", timeout_s=20)
        presets = json.loads(probe.wait_for(f"{base}/presets", lambda m: True).payload)
        assert set(presets) == {"EU", "JA", "VK", "W"}  # bearings from the default JO62qm

        def typed(line: str, pred: Callable[[dict[str, Any]], bool]) -> dict[str, Any]:
            """Type ``line``; the first idle status after it that satisfies ``pred``."""
            assert probe is not None
            mark = probe.mark()
            proc.type(line)

            def ok(m: Any) -> bool:
                if m.topic != f"{base}/status":
                    return False
                s = json.loads(m.payload)
                return bool(s["state"] == "idle" and pred(s))

            return json.loads(probe.wait(ok, 20, f"status after {line!r}", start=mark).payload)

        def near(az: float) -> Callable[[dict[str, Any]], bool]:
            return lambda s: abs((s["bearing"] - az + 180) % 360 - 180) <= 3

        def going(path: str) -> Callable[[dict[str, Any]], bool]:
            def there(s: dict[str, Any]) -> bool:
                info = s.get("target_info") or {}
                return info.get("path") == path and near(info[f"{path}_path_deg"])(s)

            return there

        seen = proc.type("help")
        for what in ("preset JA", "park", "locator PM95", "nudge -10", "EU, JA, VK, W"):
            proc.wait_line(what, start=seen, timeout_s=10)

        typed("preset W", near(presets["W"]))
        seen = len(proc.lines)
        info = typed("locator PM95vq", going("short"))["target_info"]
        assert info["locator"] == "PM95vq" and abs(info["short_path_deg"] - presets["JA"]) < 1
        proc.wait_line(r"PM95vq is [\d,]+ km away by the short path", start=seen, timeout_s=10)
        info = typed("long", going("long"))["target_info"]
        assert abs((info["long_path_deg"] - info["short_path_deg"]) % 360 - 180) < 0.2
        typed("nudge -10", near(info["long_path_deg"] - 10))
        assert typed("park", lambda s: s.get("parked") is True)["bearing"] == 0
        seen = proc.type("preset NOWHERE")  # the bridge refuses it, the console shows why
        proc.wait_line(r"/error = .*no preset 'NOWHERE'", start=seen, timeout_s=10)
        proc.type("q")
        assert proc.wait(slow(20)) == 0, proc.output
    finally:
        if probe is not None:
            probe.close()
        proc.close()


def test_a_terminals_ctrl_c_ends_the_private_broker_too_and_the_demo_says_so(
    tmp_path: Path,
) -> None:
    """A terminal's Ctrl-C reaches the demo's whole process group, its private mosquitto too:
    the demo then said it "removed its 0 retained messages" (it could reach no broker); it says
    the broker no longer answers, and ends cleanly."""
    port = free_port()
    tmpdir = tmp_path / "tmp"
    proc = DemoProcess(["--mqtt-port", str(port)], tmpdir, group=True)
    try:
        base = proc.base_topic()
        probe = Probe(port, f"{base}/#")
        probe.wait_value(f"{base}/availability", "online", timeout_s=20)
        probe.close()
        os.killpg(proc.proc.pid, signal.SIGINT)
        assert proc.wait(slow(20)) == 0, proc.output
        assert "the broker no longer answers, so its retained messages were not" in proc.output
        assert "removed its 0 retained messages" not in proc.output
    finally:
        proc.close()
    assert not answers("127.0.0.1", port)


def test_ctrl_c_stops_the_demo_and_its_private_broker(tmp_path: Path) -> None:
    port = free_port()
    tmpdir = tmp_path / "tmp"
    proc = DemoProcess(["--mqtt-port", str(port)], tmpdir)
    try:
        base = proc.base_topic()
        probe = Probe(port, f"{base}/#")
        probe.wait_value(f"{base}/availability", "online", timeout_s=20)
        probe.close()
        proc.proc.send_signal(signal.SIGINT)
        assert proc.wait(slow(20)) == 0, proc.output
        assert "rotor-bridge demo: stopping (SIGINT)" in proc.output  # what ended it is said
    finally:
        proc.close()
    assert not answers("127.0.0.1", port)
    assert _left_behind(tmpdir) == []


def test_a_second_demo_keeps_turning_after_the_first_and_its_private_broker_end(
    tmp_path: Path,
) -> None:
    """The README: a demo never gets in the way of another. A second demo found the first's
    private mosquitto answering, took it for the user's broker, and lost it for good when the
    first ended: its rotator no longer answered a target. It starts a broker of its own, and
    promises no Home Assistant devices there (review 46: none can see a broker on a free port)."""
    port = free_port()
    first = DemoProcess(["--mqtt-port", str(port)], tmp_path / "a")
    second = None
    probe = None
    try:
        first_base = first.base_topic()
        seen = Probe(port, f"{first_base}/#")
        seen.wait_value(f"{first_base}/availability", "online", timeout_s=20)
        seen.close()
        second = DemoProcess(["--mqtt-port", str(port), "--speed-deg-s", "60"], tmp_path / "b")
        base = second.base_topic()
        own = int(second.wait_line(r"turn:  mosquitto_pub -h 127\.0\.0\.1 -p (\d+) -t").group(1))
        assert own != port
        instance = first_base.removeprefix("rotor-demo-")
        second.wait_line(rf"private mosquitto on 127\.0\.0\.1:{own} .*demo {instance}'s")
        second.wait_line(r"A made-up satellite")  # (the line after the banner's)
        assert "Home Assistant" not in second.output
        assert "Home Assistant: the devices" in first.output  # (at the port asked for)
        first.proc.send_signal(signal.SIGINT)
        assert first.wait(slow(20)) == 0, first.output
        assert not answers("127.0.0.1", port)
        probe = Probe(own, f"{base}/#")
        probe.wait_value(f"{base}/availability", "online", timeout_s=20)
        probe.publish(f"{base}/target", "120")
        probe.wait_for(f"{base}/bearing", lambda m: abs(float(m.text) - 120) <= 3, timeout_s=20)
    finally:
        if probe is not None:
            probe.close()
        if second is not None:
            second.close()
        first.close()
    assert second is not None and not answers("127.0.0.1", own)


def _children(pid: int) -> dict[int, str]:
    """The live processes whose parent is ``pid`` (a zombie is no longer running), by command."""
    found: dict[int, str] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
            cmd = (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:  # gone meanwhile
            continue
        state, ppid = stat.rsplit(")", 1)[1].split()[:2]
        if int(ppid) == pid and state != "Z":
            found[int(entry.name)] = cmd
    return found


def _running(pid: int) -> bool:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


def test_a_demo_killed_outright_leaves_no_private_broker_behind(tmp_path: Path) -> None:
    """A demo killed with SIGKILL (or by the out-of-memory killer) cleans nothing up: its
    private mosquitto ran on for good, and the next demo on that port took it for the user's own
    broker. The broker dies with the demo, whether the demo runs as root (mosquitto would drop to
    its own user, which clears the kernel's death signal) or not."""
    port = free_port()
    proc = DemoProcess(["--mqtt-port", str(port)], tmp_path / "tmp")
    brokers: dict[int, str] = {}
    try:
        base = proc.base_topic()
        probe = Probe(port, f"{base}/#")
        probe.wait_value(f"{base}/availability", "online", timeout_s=20)
        probe.close()
        brokers = {p: c for p, c in _children(proc.proc.pid).items() if "mosquitto" in c}
        assert len(brokers) == 1, _children(proc.proc.pid)
        proc.proc.kill()
        proc.wait(slow(10))
        wait_until(lambda: not any(_running(p) for p in brokers), 10, "the private broker to end")
        assert not answers("127.0.0.1", port), "the next demo would take it for the user's broker"
    finally:
        for pid in brokers:  # (a broker left by a failed run must not outlive the test)
            if _running(pid):
                os.kill(pid, signal.SIGKILL)
        proc.close()


def test_every_model_runs_turns_and_ends_cleanly(tmp_path: Path) -> None:
    """rotor-bridge demo --models rotorez,rotorcard,dcu1,rot2prog,rot1prog,md01,satel,gs232a,..."""
    port = free_port()
    tmpdir = tmp_path / "tmp"
    args = ["--models", ",".join(ALL_MODELS), "--mqtt-port", str(port), "--duration-s", "25"]
    proc = DemoProcess([*args, "--speed-deg-s", "30"], tmpdir)
    try:
        base = proc.base_topic()
        roots = {m: proc.wait_line(rf"^    {m}: (\S+)/\.\.\.$").group(1) for m in ALL_MODELS}
        assert roots == {m: f"{base}/{m}" for m in ALL_MODELS}
        probe = Probe(port, f"{base}/#")
        for root in roots.values():
            probe.wait_value(f"{root}/availability", "online", timeout_s=20)
        for root in roots.values():
            probe.publish(f"{root}/target", "30")
        for model, root in roots.items():
            if model == "dcu1":  # reports no position: the estimate follows the command
                probe.wait_for(
                    f"{root}/status",
                    lambda m: (
                        json.loads(m.payload)["target"] == 30
                        and json.loads(m.payload)["last_command_source"] == "mqtt"
                    ),
                    timeout_s=15,
                )
            else:
                probe.wait_for(
                    f"{root}/bearing", lambda m: abs(float(m.text) - 30) <= 3, timeout_s=15
                )
        probe.close()
        assert proc.wait(slow(40)) == 0, proc.output
    finally:
        proc.close()
    assert "Traceback" not in proc.output, proc.output
    assert not answers("127.0.0.1", port), "the demo's private broker outlived it"
    assert _left_behind(tmpdir) == []


@pytest.mark.parametrize("failing", ["emulator", "bridge"])
def test_a_failure_during_start_up_leaves_no_broker_and_no_folder(
    failing: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture
) -> None:
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    port = free_port()
    started: list[str] = []
    closed: list[str] = []
    real_start = emulators.start

    def start_then_run_out_of_ptys(model: str, **kw: object) -> emulators.EmulatedPort:
        if started:
            raise OSError(24, "Too many open files")
        port = real_start(model, **kw)
        started.append(model)
        real_close = port.close

        def close() -> None:
            closed.append(model)
            real_close()

        port.close = close  # type: ignore[method-assign]
        return port

    def bridge_fails(self: object) -> None:
        assert answers("127.0.0.1", port), "the broker should be up by now"
        raise RuntimeError("provoked")

    if failing == "emulator":
        monkeypatch.setattr(emulators, "start", start_then_run_out_of_ptys)
    else:
        monkeypatch.setattr(demo.App, "start", bridge_fails)
    args = build_parser().parse_args(
        ["demo", "--models", "rotorez,rot2prog", "--mqtt-port", str(port), "--duration-s", "30"]
    )
    if failing == "emulator":
        assert demo.run(args) == 1
        assert "could not start: [Errno 24] Too many open files" in capsys.readouterr().err
        assert started == closed == ["rotorez"]
    else:
        with pytest.raises(RuntimeError, match="provoked"):
            demo.run(args)
    assert not answers("127.0.0.1", port), "the private broker outlived the failed start"
    assert _left_behind(tmp_path) == []


def test_bad_input_is_refused_before_anything_starts(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture
) -> None:
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    port = free_port()
    args = build_parser().parse_args(
        ["demo", "--models", "rotorez,rotorz", "--mqtt-port", str(port)]
    )
    assert demo.run(args) == 2
    assert "no emulator for rotorz" in capsys.readouterr().err
    args = build_parser().parse_args(["demo", "--base-topic", "rotor/#", "--mqtt-port", str(port)])
    assert demo.run(args) == 2
    assert "base_topic" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        build_parser().parse_args(["demo", "--speed-deg-s", "0.1"])
    assert exc.value.code == 2
    assert "0.1 is outside 0.5..360 deg/s" in capsys.readouterr().err
    assert not answers("127.0.0.1", port)
    assert _left_behind(tmp_path) == []


def test_a_demo_shares_no_client_id_topic_or_home_assistant_node_with_a_bridge_or_another_demo(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # what the real service would take from its environment must not leak into the demo
    monkeypatch.setenv("ROTOR_BRIDGE_MQTT__BASE_TOPIC", "rotor")
    monkeypatch.setenv("ROTOR_BRIDGE_MQTT__CLIENT_ID", "rotor-bridge-shack")
    args = build_parser().parse_args(["demo", "--models", "rotorez,satel"])
    demos = [demo.demo_settings(args, ["rotorez", "satel"], x, tmp_path) for x in ("ab12", "ab1r")]
    real = Identity("rotor")
    idents = [real, *(Identity(s.mqtt.base_topic) for s in demos)]
    nodes = {
        ident: [ident.bridge_node, *(ident.rotator_node(r) for r in ("rotorez", "satel", "r"))]
        for ident in idents
    }
    for owner in idents:
        for other in idents:
            if other is not owner:
                assert not any(owner.owns(n) for n in nodes[other]), (owner, other)
    assert [s.mqtt.base_topic for s in demos] == ["rotor-demo-ab12", "rotor-demo-ab1r"]
    client_ids = [s.mqtt.effective_client_id() for s in demos]
    assert client_ids == ["rotor-demo-ab12", "rotor-demo-ab1r"]
    assert all(r.name and r.name.startswith("Demo ") for s in demos for r in s.rotators)
    names = {demo.instance_name() for _ in range(50)}
    assert len(names) > 45 and all(len(n) == 4 and n.isalnum() for n in names)


def test_each_model_gets_its_speed_in_its_emulators_own_words() -> None:
    for model in ALL_MODELS:
        device = emulators.create(model, **demo.emulator_options(model, 30.0))
        assert device is not None
    # a Hy-Gain rotor as built, its stop at south (rotorez.py rule 12); a Yaesu's at north
    assert demo.emulator_options("rotorez", 30.0) == {"speed_deg_s": 30.0, "stop_at_south": True}
    assert demo.emulator_options("dcu1", 30.0) == {"speed_deg_s": 30.0, "stop_at_south": True}
    assert demo.emulator_options("rotorcard", 30.0) == {"speed_deg_s": 30.0, "stop_at_south": False}
    satel = {"az_speed_deg_s": 30.0, "el_speed_deg_s": 30.0, "step_deg": 10}  # satel.py rule 10
    assert demo.emulator_options("satel", 30.0) == satel
    assert demo.emulator_options("rot1prog", 30.0) == {
        "az_speed_deg_s": 30.0,
        "el_speed_deg_s": 30.0,
    }


def test_the_demo_tracks_its_own_satellite_from_the_prompt(tmp_path: Path) -> None:
    port = free_port()
    args = ["--mqtt-port", str(port), "--speed-deg-s", "360", "--models", "md01"]
    args += ["--satellite-rises-in-s", "300"]  # still below the horizon while the test looks
    proc = DemoProcess(args, tmp_path / "tmp", terminal=True)
    probe = None
    try:
        base = proc.base_topic()
        probe = Probe(port, f"{base}/#")
        probe.wait_value(f"{base}/state", "idle", timeout_s=20)
        proc.wait_line(r"DEMOSAT, rises over the station around [\d:]{8} UTC \(in 300 s\)", 10)
        seen = proc.type("track demosat")  # any case, as the TLE file's names
        probe.wait_value(f"{base}/tracking", "DEMOSAT", timeout_s=10)
        below = r"DEMOSAT is below the horizon .* waiting at az [\d.]+ for its rise"
        proc.wait_line(below, start=seen, timeout_s=10)

        def waiting_there(m: Any) -> bool:
            if m.topic != f"{base}/status":
                return False
            s = json.loads(m.payload)
            info = s.get("tracking") or {}
            if info.get("phase") != "waiting" or s["state"] != "idle":
                return False
            aos = info.get("aos_azimuth")  # (not there while the pass is still being searched)
            return aos is not None and abs((s["bearing"] - aos + 180) % 360 - 180) <= 1.0

        probe.wait(waiting_there, 20, "waiting where DEMOSAT rises")
        seen = proc.type("track off")
        probe.wait_value(f"{base}/tracking", "off", timeout_s=10)
        proc.wait_line(r"tracking ended \(off\)", start=seen, timeout_s=10)
        proc.type("q")
        assert proc.wait(slow(20)) == 0, proc.output
    finally:
        if probe is not None:
            probe.close()
        proc.close()


@pytest.mark.parametrize("locator", ["JO62qm", "PM95vq", "QF56", "FN31", "KP03", "RE78", "AA00"])
def test_the_demo_satellite_passes_over_any_station_when_the_banner_says(locator: str) -> None:
    """demo/sky.py's elements, checked by the tests' own SGP4 (sgp4 and our frame rotation):
    a pass peaking between 40 and 70 degrees within a minute of the time given."""
    lat, lon = geo.parse_locator(locator)
    closest = 1_795_000_000.0 + 3600 * len(locator)  # any time will do
    line1, line2 = demo_sky.elements(lat, lon, closest)
    assert parse_tles(f"{demo_sky.NAME}\n{line1}\n{line2}\n") == ({"DEMOSAT": (line1, line2)}, [])
    if abs(lat) > 82:  # beyond what a 97.5 degree orbit reaches overhead: still a pass
        return
    times = [closest + d for d in range(-600, 601, 5)]
    els = [sgp4_altaz(line1, line2, lat, lon, t)[1] for t in times]
    peak = max(range(len(els)), key=els.__getitem__)
    assert 40.0 <= els[peak] <= 70.0, els[peak]
    assert abs(times[peak] - closest) <= 60.0
    assert els[0] < 0.0 and els[-1] < 0.0  # it rises and sets within those 20 minutes
    rise = next(t for t, el in zip(times, els, strict=True) if el > 0.0)
    assert abs(rise - (closest - demo_sky.half_pass_s(lat))) <= 30.0  # when the demo says


def test_by_default_the_demo_satellite_rises_within_a_minute_of_the_start() -> None:
    args = build_parser().parse_args(["demo"])
    assert 0 < args.satellite_rises_in_s <= 60


def test_on_a_terminal_the_bearing_stays_on_one_status_line_below_what_is_typed(
    tmp_path: Path,
) -> None:
    """In a terminal window: a bearing changing every degree redraws one status line in place
    (carriage return, erase) instead of scrolling away the line being typed; answers and state
    changes are lines of their own above it; the terminal is as it was after the demo."""
    port = free_port()
    args = ["--mqtt-port", str(port), "--speed-deg-s", "60"]
    proc = DemoProcess(args, tmp_path / "tmp", screen=True)
    before = termios.tcgetattr(proc.tty)
    try:
        base = proc.base_topic()
        proc.wait_screen(rf"\r\x1b\[K{base} az \d+ idle > ", timeout_s=30)
        seen = proc.keys("12")  # half typed: still there after each redraw of the status line
        proc.wait_screen(rf"\r\x1b\[K{base} az \d+ idle > 12", start=seen)
        seen = proc.keys("0\r")
        proc.wait_screen(r"\r\x1b\[K> 120\r\n", start=seen)
        proc.wait_screen(rf"{base}/state = moving\r\n", start=seen)
        turning = proc.wait_screen(rf"{base} az 1[01]\d moving > ", start=seen)
        proc.wait_screen(rf"{base} az 1[12]\d idle > ", start=turning.end(), timeout_s=30)
        seen = proc.keys("nonsense\r")
        proc.wait_screen(r"unknown command 'nonsense'; type 'help'\r\n", start=seen)
        typed = proc.keys("30")
        proc.wait_screen(rf"{base} az \d+ idle > 30$", start=typed)
        assert f"{base}/bearing = " not in proc.screen_text  # no line per degree
        proc.keys("\x15q\r")  # ^U: the half-typed line forgotten, then quit
        assert proc.wait(slow(20)) == 0, proc.screen_text
    finally:
        after = termios.tcgetattr(proc.tty)
        proc.close()
    assert after[3] & termios.ECHO and after[3] & termios.ICANON  # echo and lines back on
    assert after == before
