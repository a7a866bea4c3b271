"""A command's MQTT 5 user properties read one way whatever their number: one given twice with
two values is read as neither (an attack pass: of two ``operator`` the first was taken, of two
``sent`` the last), and a ``sent`` in digits other than ASCII's cannot be read (``１２３`` was
read as 123 by ``float``). connection.py ``operator_of``, heartbeat.py rule 5."""

from __future__ import annotations

import paho.mqtt.client as paho
import pytest
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.properties import Properties

from bridge.core.model import Origin, Source
from bridge.interfaces.mqtt.connection import operator_of, stamp_of
from bridge.interfaces.mqtt.heartbeat import station_of
from tests.mqtt.test_service import service


def message(*pairs: tuple[str, str]) -> paho.MQTTMessage:
    msg = paho.MQTTMessage(topic=b"rotor/tower/target")
    msg.properties = Properties(PacketTypes.PUBLISH)
    msg.properties.UserProperty = list(pairs)
    return msg


def test_one_operator_or_the_same_one_twice_names_the_sender() -> None:
    svc, _, _ = service({"tower": "rotorez"})
    for msg in (message(("operator", "DL1ABC")), message(*[("operator", "DL1ABC")] * 2)):
        assert svc.origin(operator_of(msg)).operator == "DL1ABC"


def test_two_operators_that_differ_name_nobody() -> None:
    svc, _, _ = service({"tower": "rotorez"})
    origin = svc.origin(operator_of(message(("operator", "DL1ABC"), ("operator", "EVIL"))))
    assert origin == Origin(Source.MQTT)


@pytest.mark.parametrize(
    "pairs",
    [
        [("sent", "1000"), ("expiry", "5"), ("sent", "999")],
        [("sent", "1000"), ("expiry", "5"), ("expiry", "600")],
        [("sent", "１０００"), ("expiry", "5")],  # full-width digits
        [("sent", "1000"), ("expiry", "٥")],  # an Arabic-Indic five
    ],
)
def test_a_stamp_given_twice_two_ways_or_not_in_ascii_digits_cannot_be_read(
    pairs: list[tuple[str, str]],
) -> None:
    stamp = stamp_of(message(*pairs))
    assert stamp is not None
    why = stamp.judge(1001.0)
    assert why is not None and why.startswith("its send time cannot be read")


def test_a_stamp_given_twice_the_same_way_is_one_stamp() -> None:
    stamp = stamp_of(message(("sent", "1000"), ("expiry", "5"), ("sent", "1000")))
    assert stamp is not None and stamp.judge(1001.0) is None


def test_a_heartbeat_naming_two_stations_names_none() -> None:
    assert station_of([("station", "a1"), ("station", "a1")]) == "a1"
    assert station_of([("station", "a1"), ("station", "b2")]) is None
