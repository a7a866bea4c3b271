"""Controller settings as data (protocols/base.py rule 6): what a declaration accepts and
refuses, what the engine owes the controller and when (session/options.py), and the Home
Assistant entity each kind becomes. Pure: no port, no broker."""

from __future__ import annotations

import dataclasses
import json

import pytest

from bridge.core.model import SetOption, describe_command, setting_text
from bridge.interfaces.homeassistant import Identity, RotatorInfo, all_configs
from bridge.interfaces.mqtt.topics import Topics
from bridge.protocols import REGISTRY
from bridge.protocols.base import SendWhen, Setting, SettingKind
from bridge.session.options import OPTIONS_REFRESH_S, Options
from tests.ha_rules import validate

RAMP = Setting(
    "ramp",
    "Ramp",
    lambda v: b"R%d\r" % int(v),
    kind=SettingKind.NUMBER,
    minimum=0.0,
    maximum=10.0,
    step=0.5,
    unit="s",
    when=SendWhen.AT_REST,
    resend=False,
)
GEAR = Setting(
    "gear",
    "Gear",
    lambda v: b"G" + str(v).encode(),
    kind=SettingKind.CHOICE,
    choices=("low", "high"),
    when=SendWhen.ANYTIME,
    speed_factors={"low": 0.5},
)


def test_a_bool_setting_reads_on_and_off_as_options_always_did() -> None:
    jam = REGISTRY["rotorez"].setting("jam")
    assert jam is not None and jam.kind is SettingKind.BOOL
    assert [jam.read(v) for v in ("ON", "off", "1", "false", True)] == [
        True,
        False,
        True,
        False,
        True,
    ]
    assert [jam.encode(True), jam.encode(False)] == [b"J", b"j"]  # byte for byte as before
    with pytest.raises(ValueError, match="expected ON or OFF, got '2'"):
        jam.read("2")


def test_a_number_setting_takes_its_range_and_step_and_refuses_the_rest() -> None:
    assert RAMP.read("2.5") == 2.5 and RAMP.read(10) == 10.0
    for bad, words in [
        ("11", "11 is outside 0..10 s"),
        ("-1", "-1 is outside 0..10 s"),
        ("0.3", "0.3 is not on a step of 0.5 in 0..10 s"),
        ("fast", "expected a number, got 'fast'"),
        ("nan", "nan is outside"),
        ("10.0000001", "10.0000001 is outside 0..10 s"),  # (attack 28: not "10 is outside")
        (True, "expected a number"),
    ]:
        with pytest.raises(ValueError, match=words):
            RAMP.read(bad)


def test_a_choice_setting_takes_its_names_in_any_case_and_refuses_others() -> None:
    assert GEAR.read("HIGH") == "high" and GEAR.read(" low ") == "low"
    with pytest.raises(ValueError, match="gear: 'medium' is not one of low, high"):
        GEAR.read("medium")


def test_the_speed_factor_is_the_declared_one_of_the_value_in_effect() -> None:
    assert GEAR.speed_factor("low") == 0.5 and GEAR.speed_factor("high") == 1.0
    options = Options({"gear": "low"}, (GEAR,))
    assert options.speed_factor() == 1.0  # not sent yet: the controller's own speed
    options.connected(answering=True)
    assert options.take(idle=False, free=False, now=1.0, line_free=True) == [("gear", "low")]
    assert options.speed_factor() == 0.5
    options.all_due()  # a power-on: it forgot; its own speed until sent again
    assert options.speed_factor() == 1.0


def test_at_rest_settings_wait_for_rest_and_anytime_ones_only_for_a_free_line() -> None:
    options = Options({"ramp": 1.0, "gear": "high"}, (RAMP, GEAR))
    options.connected(answering=True)
    # turning (not idle): only the ANYTIME one, and only on a free line
    assert options.take(idle=False, free=False, now=0.0, line_free=False) == []
    assert options.take(idle=False, free=False, now=0.0, line_free=True) == [("gear", "high")]
    assert options.take(idle=True, free=False, now=0.1, line_free=True) == []  # a target waits
    assert options.take(idle=True, free=True, now=0.2) == [("ramp", 1.0)]


def test_only_settings_the_controller_forgets_are_sent_again() -> None:
    options = Options({"ramp": 1.0, "gear": "high"}, (RAMP, GEAR))
    options.connected(answering=True)
    assert options.take(idle=True, free=True, now=0.0) == [("gear", "high"), ("ramp", 1.0)]
    options.all_due()  # a power-on byte
    assert options.take(idle=True, free=True, now=1.0) == [("gear", "high")]
    assert options.take(idle=True, free=True, now=2.0 + OPTIONS_REFRESH_S) == [("gear", "high")]
    options.set("ramp", 2.0, connected=True)  # set again: sent once
    assert options.take(idle=True, free=True, now=3.0 + OPTIONS_REFRESH_S) == [("ramp", 2.0)]


def test_a_kept_setting_changed_while_the_port_is_closed_is_sent_on_the_reconnect() -> None:
    """A setting the controller keeps (``resend=False``) is sent when it is set: set while the
    port is closed, or before the controller answers, that is once it answers again. Before,
    the new value was saved and shown but never reached the controller."""
    options = Options({"ramp": 1.0}, (RAMP,))
    options.connected(answering=True)
    assert options.take(idle=True, free=True, now=0.0) == [("ramp", 1.0)]
    options.set("ramp", 2.0, connected=False)  # the port is closed
    options.connected(answering=True)
    assert options.take(idle=True, free=True, now=1.0) == [("ramp", 2.0)]
    options.connected(answering=False)  # open, the controller not answering yet
    options.set("ramp", 3.0, connected=True)
    options.all_due()  # it answers
    assert options.take(idle=True, free=True, now=2.0) == [("ramp", 3.0)]


def test_a_settings_value_is_shown_as_its_state_topic_carries_it() -> None:
    assert [setting_text(v) for v in (True, False, 2.0, 0.5, "X2")] == [
        "ON",
        "OFF",
        "2",
        "0.5",
        "X2",
    ]
    assert describe_command(SetOption("speed", "2")) == "option speed 2"
    assert describe_command(SetOption("jam", True)) == "option jam ON"


def test_each_kind_of_setting_is_its_home_assistant_platform() -> None:
    spec = dataclasses.replace(
        REGISTRY["rotorez"], settings=(REGISTRY["rotorez"].settings[1], RAMP, GEAR)
    )
    topics = Topics("rotor", {"tower": "rotor"})
    info = RotatorInfo("tower", "Tower", spec, topics.rotator("tower"), 0.0, 360.0, 0.0, 0.0)
    msgs = {
        t: json.loads(p) for t, p in all_configs("ha", Identity("rotor"), topics, [info]).items()
    }
    node = "ha/{}/rotorbridge_rotor_r_tower/option_{}/config"
    jam, ramp, gear = (
        msgs[node.format(*p)] for p in [("switch", "jam"), ("number", "ramp"), ("select", "gear")]
    )
    assert (jam["command_topic"], jam["state_topic"], jam["payload_on"]) == (
        "rotor/option/jam",
        "rotor/option/jam/state",
        "ON",
    )
    assert (ramp["min"], ramp["max"], ramp["step"], ramp["unit_of_measurement"]) == (
        0.0,
        10.0,
        0.5,
        "s",
    )
    assert (
        ramp["command_topic"] == "rotor/option/ramp"
        and ramp["state_topic"] == "rotor/option/ramp/state"
    )
    assert gear["options"] == ["low", "high"] and gear["state_topic"] == "rotor/option/gear/state"
    for topic, payload in msgs.items():
        assert validate(topic, payload, prefix="ha") == []


def test_r_info_describes_a_number_setting_by_its_range_step_and_unit() -> None:
    from bridge.interfaces.mqtt.payloads import setting_info

    assert setting_info(RAMP) == {
        "name": "ramp",
        "label": "Ramp",
        "kind": "number",
        "min": 0.0,
        "max": 10.0,
        "step": 0.5,
        "unit": "s",
    }
