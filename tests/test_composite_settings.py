"""A composite rotator's configuration (settings/rotator.py rule 4), its check-config report,
and the pure parts that make one rotator of two boxes (protocols/axes.py, the split and the
merge of runtime/composite.py)."""

from __future__ import annotations

import os
import re
import tomllib
from pathlib import Path
from typing import Any

import pytest

from bridge.app import axis_configs, worker_config
from bridge.core.errors import Refused
from bridge.core.model import ErrorEvent, ErrorKind, MotionState, RotatorStatus, Stop, Target
from bridge.protocols import REGISTRY
from bridge.protocols.axes import Axis, ElevationOnly
from bridge.protocols.base import NotReady, PositionReply
from bridge.runtime.composite import CompositeWorker, Composition, merge, split
from bridge.session.actions import Write
from bridge.session.controller import Controller
from bridge.session.mailbox import Batch, Mailbox
from bridge.settings import ConfigError, settings_from
from tests.support import ROOT, cli

AZ = {"model": "rt21", "port": "/dev/ttyAZ"}
EL = {"model": "gs232b", "port": "/dev/ttyEL"}


def load(**rotator: Any) -> Any:
    return settings_from({"rotators": [{"id": "sky", **rotator}]}, environ={}).rotators[0]


def test_a_composite_rotator_is_az_from_one_box_and_el_from_the_other() -> None:
    r = load(azimuth=AZ, elevation=EL, el_max_deg=90)
    assert r.model == "rt21+gs232b" and r.ports == ["/dev/ttyAZ", "/dev/ttyEL"]
    spec = r.spec
    assert spec.has_elevation and spec.options == ()
    assert spec.tenths and spec.el_rounding == (True, False, False, 1)  # RT-21's az, GS-232B's el
    assert (spec.az_min_deg, spec.az_max_deg) == (0.0, 360.0)  # the RT-21's
    assert (spec.el_min_deg, spec.el_max_deg) == (0.0, 180.0)  # the GS-232B's
    assert r.pointing.el_max_deg == 90  # the rotator's keys apply to the whole
    again = type(r).model_validate(r.model_dump())  # what check-config --full prints loads
    assert (again.model, again.ports) == (r.model, r.ports)


def test_a_box_s_key_comes_from_the_environment_as_any_other_table_s() -> None:
    # As ROTOR_BRIDGE_MQTT__TLS__ENABLED reaches mqtt.tls: an adapter that came back under
    # another name is set without editing the file (it was refused: "did you mean azimuth?").
    document = {"rotators": [{"id": "sky", "azimuth": dict(AZ), "elevation": dict(EL)}]}
    environ = {
        "ROTOR_BRIDGE_ROTATORS__SKY__AZIMUTH__PORT": "/dev/ttyUSB3",
        "ROTOR_BRIDGE_ROTATORS__SKY__ELEVATION__BAUD": "4800",
    }
    r = settings_from(document, environ=environ).rotators[0]
    assert r.ports == ["/dev/ttyUSB3", "/dev/ttyEL"]
    assert r.elevation is not None and r.elevation.baud == 4800
    document = {"rotators": [{"id": "sky", "azimuth": dict(AZ), "elevation": dict(EL)}]}
    with pytest.raises(ConfigError) as err:
        settings_from(document, environ={"ROTOR_BRIDGE_ROTATORS__SKY__AZIMUTH__PROT": "/dev/x"})
    assert (
        "rotators[0].azimuth.prot (from ROTOR_BRIDGE_ROTATORS__SKY__AZIMUTH__PROT): unknown key: "
        "did you mean port?"
    ) in str(err.value)


def test_an_rt21_box_may_turn_the_elevation() -> None:
    r = load(azimuth=AZ, elevation={**EL, "model": "rt21"})
    assert (r.spec.el_min_deg, r.spec.el_max_deg) == (0.0, 180.0)


@pytest.mark.parametrize("model", ["prosistel-el", "prosistel-el-a"])  # unit E, or unit A
def test_a_prosistel_d_box_on_an_elevation_rotor_may_turn_the_elevation(model: str) -> None:
    r = load(azimuth=AZ, elevation={**EL, "model": model})
    assert (r.spec.el_min_deg, r.spec.el_max_deg) == (0.0, 90.0)  # the box's own 0..90


@pytest.mark.parametrize(
    ("rotator", "words"),
    [
        ({"azimuth": AZ, "elevation": {**EL, "model": "rotorez"}}, "elevation.model"),
        ({"azimuth": AZ, "elevation": {**EL, "model": "gs232b-az"}}, "elevation.model"),
        ({"azimuth": AZ, "elevation": {**EL, "model": "dcu1"}}, "elevation.model"),
        ({"azimuth": AZ, "elevation": {**EL, "port": "/dev/ttyAZ"}}, "elevation.port"),
        ({"model": "rt21", "azimuth": AZ, "elevation": EL}, "model is given"),
        ({"port": "/dev/x", "azimuth": AZ, "elevation": EL}, "port is given"),
        ({"azimuth": AZ}, "elevation"),
        ({"azimuth": {"model": "rt21"}, "elevation": EL}, "azimuth"),
        ({"azimuth": {**AZ, "model": "rt-21"}, "elevation": EL}, "unknown model"),
        ({"model": "rt21+gs232b", "port": "/dev/x"}, "unknown model"),
    ],
)
def test_nonsense_is_refused_naming_the_key(rotator: dict[str, Any], words: str) -> None:
    with pytest.raises(ConfigError) as err:
        load(**rotator)
    assert words in str(err.value), str(err.value)


@pytest.mark.parametrize(
    ("axis", "port", "said"),
    [
        ("azimuth", "", "must name the serial port"),
        ("elevation", " ", "must name the serial port"),
        ("elevation", "/dev/ttyEL\x00", "must not hold a NUL byte"),
        # (review 73: the port of both was read from the tables as written, and said it again)
        ("azimuth", "~no-such-user-rb/az", "~no-such-user-rb names no user on this system"),
    ],
)
def test_a_box_port_that_names_no_serial_port_is_refused_naming_the_key(
    axis: str, port: str, said: str
) -> None:
    """As a rotator's own port (an attack pass), on one line: not again as the port of both."""
    box = {**(AZ if axis == "azimuth" else EL), "port": port}
    with pytest.raises(ConfigError) as err:
        load(**({"azimuth": AZ, "elevation": EL} | {axis: box}))
    lines = str(err.value).splitlines()
    assert lines[0] == "invalid configuration:" and len(lines) == 2, lines
    assert lines[1].startswith(f"  rotators[0]: {axis}.port: {said}"), lines


def test_a_box_port_is_no_other_rotators() -> None:
    doc = {
        "rotators": [
            {"id": "sky", "azimuth": AZ, "elevation": EL},
            {"id": "hf", "model": "rotorez", "port": "/dev/ttyEL"},
        ]
    }
    with pytest.raises(ConfigError, match="/dev/ttyEL is given to two rotators"):
        settings_from(doc, environ={})


def test_check_config_names_both_boxes_and_warns_for_each_missing_port(tmp_path: Path) -> None:
    there = tmp_path / "az-box"
    there.touch()
    path = tmp_path / "c.toml"
    path.write_text(
        '[[rotators]]\nid = "sky"\n'
        f'azimuth = {{ model = "rt21", port = "{there}" }}\n'
        f'elevation = {{ model = "gs232b", port = "{tmp_path / "gone"}", baud = 4800 }}\n'
    )
    out = cli("check-config", "-c", str(path))
    assert out.returncode == 0, out.stderr
    assert f"azimuth by RT-21 (rt21) on {there} (found), 4800 baud" in out.stdout
    assert "elevation by GS-232B (gs232b) on" in out.stdout and "(NOT FOUND), 4800" in out.stdout
    warned = [line for line in out.stdout.splitlines() if line.startswith("warning: ")]
    assert [w.split(":")[1] for w in warned] == [" rotators[0].elevation.port"], warned


def test_a_target_is_split_by_axis_and_a_stop_goes_to_both() -> None:
    halves = split(Batch(stop=Stop(), target=Target(120.0, 30.0, true_az_deg=120.0)))
    az, el = halves[Axis.AZIMUTH], halves[Axis.ELEVATION]
    assert az.stop is not None and el.stop is not None
    assert az.target is not None and (az.target.az_deg, az.target.el_deg) == (120.0, None)
    assert el.target is not None and (el.target.az_deg, el.target.el_deg) == (None, 30.0)
    only_el = split(Batch(target=Target(None, 10.0)))
    assert only_el[Axis.AZIMUTH].target is None and only_el[Axis.ELEVATION].target is not None


def test_the_status_is_offline_while_either_box_is() -> None:
    az = RotatorStatus("a", MotionState.IDLE, 120.0, None, connected=True, available=True)
    el = RotatorStatus("e", MotionState.OFFLINE, 0.0, 30.0)
    merged = merge("sky", az, el)
    assert (merged.rotator_id, merged.bearing_deg, merged.elevation_deg) == ("sky", 120.0, 30.0)
    assert merged.state is MotionState.OFFLINE and not merged.available
    el = RotatorStatus("e", MotionState.MOVING, 0.0, 31.0, connected=True, available=True)
    merged = merge("sky", az, el)
    assert merged.state is MotionState.MOVING and merged.available


def test_the_newer_error_of_the_two_is_shown() -> None:
    c = Composition("sky")
    c.seen(Axis.AZIMUTH, RotatorStatus("a", last_error="az trouble"))
    shown = c.seen(Axis.ELEVATION, RotatorStatus("e", last_error="el trouble"))
    assert shown is not None and shown.last_error == "el trouble"


def test_the_version_is_both_boxes_once_each_box_that_reports_one_has() -> None:
    """Rule 3: never one box's version alone as the pair's (the elevation box's ``SatEL`` read
    as the azimuth's; at each restart the pair kept gave way to the first box's alone and came
    back, each a round of Home Assistant discovery); a box whose model reports none is not
    waited for."""
    c = Composition("sky", versioned=(True, True))
    first = c.seen(Axis.ELEVATION, RotatorStatus("e", version="SatEL"))
    assert first is not None and first.version is None
    c.seen(Axis.AZIMUTH, RotatorStatus("a", connected=True))
    assert c.status.version is None
    c.seen(Axis.AZIMUTH, RotatorStatus("a", connected=True, version="1.4S"))
    assert c.status.version == "1.4S / SatEL"
    alone = Composition("sky", versioned=(True, False))  # a Rotor-EZ and a GS-232B
    alone.seen(Axis.AZIMUTH, RotatorStatus("a", version="1.4S"))
    assert alone.status.version == "1.4S"
    none = merge("sky", RotatorStatus("a"), RotatorStatus("e"), versioned=(False, False))
    assert none.version is None


def said_twice(codec: ElevationOnly, line: bytes) -> None:
    """Two readings of ``line`` taken (link.py rule 9): the box's own azimuth counts from the
    second (protocols/axes.py rule 5)."""
    for n in range(2):
        codec.encode_query()
        [reply] = codec.feed(line)
        assert isinstance(reply, PositionReply)
        codec.taken(reply)
        if n == 0:
            with pytest.raises(NotReady):  # said once: no target counted yet
                codec.encode_target(200.0, 45.0)


def test_the_elevation_box_is_sent_its_own_azimuth() -> None:
    codec = ElevationOnly(REGISTRY["gs232b"].codec_factory())
    said_twice(codec, b"AZ=087  EL=010\r")
    assert codec.encode_target(200.0, 45.0) == [b"W087 045\r"]
    codec.encode_query()
    [reply] = codec.feed(b"AZ=087  EL=020\r")  # what the session asked for, as if there
    assert isinstance(reply, PositionReply) and (reply.az_deg, reply.el_deg) == (200.0, 20.0)


def test_a_position_the_engine_did_not_take_is_not_sent_back() -> None:
    codec = ElevationOnly(REGISTRY["gs232b"].codec_factory())
    said_twice(codec, b"AZ=087  EL=010\r")
    codec.encode_query()
    [glitch] = codec.feed(b"AZ=359  EL=010\r")  # dropped: a second reply spoiled it
    assert isinstance(glitch, PositionReply)
    assert codec.encode_target(200.0, 45.0) == [b"W087 045\r"]


def test_the_two_boxes_example_loads() -> None:
    text = (ROOT / "config" / "two-boxes.toml").read_text()
    text = re.sub(r"^# ((?:[a-z_]+ = |\[))", r"\1", text, flags=re.M)  # uncommented too
    [sky] = settings_from(tomllib.loads(text), environ={}).rotators
    assert sky.model == "rt21+gs232b" and sky.pointing.el_max_deg == 90


def test_a_stop_is_on_both_lines_before_either_status_goes_out() -> None:
    """CompositeWorker (runtime/composite.py rule 1): the two sessions decide, then both stop
    frames are written, then the statuses go to the listeners."""
    r = load(azimuth=AZ, elevation=EL)
    boxes = axis_configs(r)
    assert boxes is not None
    worker = CompositeWorker(worker_config(r), boxes, Mailbox(), lambda s: None, lambda e: None)
    done: list[tuple[Axis, str]] = []
    for axis, box in worker.boxes.items():
        box.session.start(0.0)
        box.session.link_up(0.0, 1e9)
        box.carry_out = lambda now, actions, a=axis: done.extend(  # type: ignore[method-assign]
            (a, type(x).__name__ if not isinstance(x, Write) else repr(x.data)) for x in actions
        )
    worker._hand(split(Batch(stop=Stop(), notes=["shown"])), 0.0)
    kinds = [k for _, k in done]
    assert done[:2] == [(Axis.AZIMUTH, "b';'"), (Axis.ELEVATION, "b'S\\r'")], done
    assert "Publish" in kinds and kinds.index("Publish") > 1


def test_an_elevation_the_gs232b_would_round_past_the_limit_is_refused() -> None:
    judge = load(azimuth=AZ, elevation=EL, el_max_deg=89.5).pointing
    assert judge.judge(Target(100.0, 89.4), None).el_deg == 89.4
    with pytest.raises(Refused, match="whole degrees"):
        judge.judge(Target(100.0, 89.5), None)  # the box would be sent 90


class _Port:
    """A port that is a pipe: what is written to it is read at ``out``."""

    def __init__(self) -> None:
        self.out, self._w = os.pipe()
        os.set_blocking(self.out, False)

    def drain(self) -> bytes:
        try:
            return os.read(self.out, 4096)
        except BlockingIOError:
            return b""

    def fileno(self) -> int:
        return self._w

    def unplug(self) -> None:
        os.close(self.out)  # a write now fails as on a USB adapter that was pulled out

    def close(self) -> None:
        os.close(self._w)


def test_a_box_unplugged_as_a_stop_is_written_is_a_lost_link_and_owes_that_stop() -> None:
    """A box's port that fails while the rotator's command is written to it (composite.py
    ``_hand``) is that box's serial link lost, as worker.py rule 1 says (not an internal error
    with a traceback); the other box got its stop, and the failed one gets the stop first when
    its port is back."""
    r = load(azimuth=AZ, elevation=EL)
    boxes = axis_configs(r)
    assert boxes is not None
    events: list[ErrorEvent] = []
    worker = CompositeWorker(worker_config(r), boxes, Mailbox(), lambda s: None, events.append)
    ports = {axis: _Port() for axis in Axis}
    for axis, box in worker.boxes.items():
        box._do(box.session.start(0.0))
        box._port = ports[axis]  # type: ignore[assignment]
        box._do(box.session.link_up(0.0, 1e9))
    ports[Axis.AZIMUTH].drain()  # what each box is sent on connecting
    ports[Axis.ELEVATION].unplug()
    worker._hand(split(Batch(stop=Stop())), 0.5)
    assert ports[Axis.AZIMUTH].drain() == b";"  # the other box stopped
    kinds = [(e.kind, e.message) for e in events]
    assert kinds and all(k is ErrorKind.SERIAL for k, _ in kinds), kinds
    assert "serial link to /dev/ttyEL lost" in kinds[-1][1], kinds
    back = _Port()
    el = worker.boxes[Axis.ELEVATION]
    el._port = back  # type: ignore[assignment]
    el._do(el.session.link_up(5.0, 1e9))
    assert back.drain().startswith(b"S\r")  # the stop it was owed, first


def _unasked(az_model: str, el_model: str, **rotator: object) -> tuple[list[str], str]:
    """What each box of a composite does with a turn nobody asked for, and what check-config
    says of it."""
    from bridge.settings.report import masked

    doc = {
        "rotators": [
            {
                "id": "sky",
                "azimuth": {"model": az_model, "port": "/dev/ttyAZ"},
                "elevation": {"model": el_model, "port": "/dev/ttyEL"},
                **rotator,
            }
        ]
    }
    s = settings_from(doc, environ={})
    boxes = axis_configs(s.rotators[0])
    assert boxes is not None
    return [b.unasked_moves for b in boxes], masked(s)["rotators"][0]["unasked_moves"]


def test_each_box_stops_or_follows_a_turn_nobody_asked_for_by_its_own_model() -> None:
    """controller.py rule 10: an Easycomm az/el box that turns only the elevation follows such
    turns (no flipped bit of its poll turns an elevation; a review: its own azimuth channel,
    jogged, turns nothing, and a hand at the elevation panel was stopped); beside it an Easycomm
    azimuth box stops them; check-config says so per box."""
    assert _unasked("rt21", "easycomm2") == (
        ["follow", "follow"],
        "azimuth box: follow, elevation box: follow",
    )
    assert _unasked("easycomm2", "easycomm2") == (
        ["stop", "follow"],
        "azimuth box: stop, elevation box: follow",
    )
    assert _unasked("easycomm2", "easycomm2", unasked_moves="stop")[0] == ["stop", "stop"]


def test_an_rc2800_elevation_box_stops_turns_nobody_asked_for() -> None:
    """rc2800.py rule 8: an RC2800's elevation poll, ``E`` CR, is one stray byte from a target
    (``E5`` CR), so an RC2800 that turns a composite's elevation stops a turn nobody asked for,
    where other elevation boxes follow; ``unasked_moves = "follow"`` lets it be."""
    assert _unasked("rt21", "rc2800") == (
        ["follow", "stop"],
        "azimuth box: follow, elevation box: stop",
    )
    assert _unasked("rt21", "rc2800", unasked_moves="follow")[0] == ["follow", "follow"]


@pytest.mark.parametrize(("speed", "settle_s"), [("1", 5.0), ("3", 1.8), ("4", 1.5)])
def test_a_slowed_elevation_box_settles_by_its_own_speed_not_the_azimuths(
    speed: str, settle_s: float
) -> None:
    """motion.py rule 2 (a review): a GS-232 turning a composite's elevation beside an RT-21,
    the azimuth configured slow (0.5 degrees a second): at X3 it waited 8.2 s, where its own
    1.875 degrees a second need 1.8."""
    doc = {
        "rotators": [
            {
                "id": "sky",
                "azimuth": {"model": "rt21", "port": "/dev/ttyAZ"},
                "elevation": {"model": "gs232b", "port": "/dev/ttyEL"},
                "az_speed_deg_s": 0.5,
            }
        ]
    }
    boxes = axis_configs(settings_from(doc, environ={}).rotators[0])
    assert boxes is not None
    box = Controller(boxes[1], {"speed": speed})
    box.options.all_due()  # (the box answers: what is set is owed)
    assert box.options.take(True, True, 0.0) == [("speed", speed)]  # written: in effect
    box._retune()  # (what the step does after writing a setting: controller.py rule 7)
    assert box.cfg.motion.settle_s == pytest.approx(settle_s)


def test_a_stall_timeout_the_elevation_box_cannot_show_a_turn_in_is_refused() -> None:
    """settings/rotator.py rule 2 (attack 12): the RT-21's azimuth, noise 0.5 at 6 degrees a
    second, shows a turn within 0.48 s; the GS-232B elevation box's own noise, 2 degrees at
    its 2.5 a second, needs 1.2 s: stall_timeout_s 1 would call every elevation turn stalled.
    Refused naming the key, the axis and the time it needs; 1.3 is taken."""
    with pytest.raises(ConfigError) as refused:
        load(azimuth=AZ, elevation=EL, stall_timeout_s=1.0)
    said = str(refused.value)
    assert "stall_timeout_s 1 must be longer" in said and "in elevation (1.2 s" in said, said
    assert "el_speed_deg_s 2.5" in said, said
    assert load(azimuth=AZ, elevation=EL, stall_timeout_s=1.3).stall_timeout_s == 1.3
