"""Model specs are data: the exchange size they state is what goes over the wire, and the idle
poll interval derived from it leaves every model's line at least 95 % free."""

from __future__ import annotations

import pytest

from bridge import emulators
from bridge.protocols import REGISTRY
from bridge.protocols.base import HamlibRotType

ROTOR_EZ_BOARDS = ("rotorez", "rotorcard", "dcu1")  # their emulator sends 0xE0 at power-on
REPORTING = sorted(name for name, spec in REGISTRY.items() if spec.can_report_position)


def measured_exchange(model: str) -> tuple[int, int]:
    """(query bytes, reply bytes) of one poll, the reply as the emulated controller (written
    from the documents, not from our codecs) sends it."""
    spec = REGISTRY[model]
    codec = spec.codec_factory()
    options = {"power_on_junk": False} if model in ROTOR_EZ_BOARDS else {}
    if model.startswith("easycomm"):  # its answer's width varies: the widest one
        options = {"start_az_deg": 359.9, "start_el_deg": 180.0 if spec.has_elevation else 0.0}
    if model == "rt21":  # its reply grows with the bearing: the longest, 123.4;
        options = {"start_az_deg": 123.4}
    device = emulators.create(model, now=0.0, **options)
    enable = codec.encode_enable()
    if enable:  # as the bridge has it: automatic motion on (SatEL: "Motion ENABLED")
        device.receive(enable, 0.0)
        device.due_output(1.0)
    asked = codec.encode_query()
    assert asked is not None
    query = b"".join(asked) if isinstance(asked, list) else asked  # an RC2800's axes in turn
    device.receive(query, 2.0)
    return len(query), len(device.due_output(100.0))


@pytest.mark.parametrize("model", REPORTING)
def test_the_exchange_size_on_the_spec_is_what_the_wire_carries(model: str) -> None:
    spec = REGISTRY[model]
    assert (spec.query_bytes, spec.reply_bytes) == measured_exchange(model)


def test_a_controller_that_cannot_be_asked_has_no_exchange() -> None:
    dcu1 = REGISTRY["dcu1"]
    assert dcu1.codec_factory().encode_query() is None
    assert (dcu1.query_bytes, dcu1.reply_bytes, dcu1.exchange_time_s()) == (0, 0, 0.0)


@pytest.mark.parametrize("model", sorted(REGISTRY))
def test_idle_polling_with_the_defaults_takes_at_most_5_percent_of_the_line(model: str) -> None:
    spec = REGISTRY[model]
    for baud in {spec.baud, 600, 1200, 4800, 9600, 115200}:
        interval_s = spec.default_idle_poll_interval_s(baud)
        line_s = (spec.query_bytes + spec.reply_bytes) * 10 / baud  # 8N1: 10 bits a byte
        assert spec.exchange_time_s(baud) == pytest.approx(line_s)
        assert line_s / interval_s <= 0.045, (baud, interval_s)  # 5 % with room to measure
        assert interval_s >= 1.0  # a still rotor is never polled more often than once a second


def test_the_derived_idle_intervals_of_the_slow_lines() -> None:
    """Rot2Prog (600 baud, 25-byte exchange) and SatEL (9600, a 166-byte report exchange) poll
    rarely; the fast lines keep the 1 s floor."""
    intervals = {name: spec.default_idle_poll_interval_s() for name, spec in REGISTRY.items()}
    assert intervals == {
        "rotorez": 1.0,
        "rotorcard": 1.0,
        "dcu1": 1.0,
        "rot2prog": 9.3,
        "rot1prog": 3.4,
        "md01": 1.0,
        "satel": 3.9,
        **{name: 1.0 for name in REGISTRY if name.startswith("gs232")},
        **{name: 1.0 for name in REGISTRY if name.startswith("easycomm")},
        "rt21": 1.0,
        "prosistel": 1.0,
        "prosistel-el": 1.0,
        "prosistel-el-a": 1.0,
        "prosistel-combi": 1.0,
        "rc2800": 1.0,
        "rc2800-az": 1.0,
    }


def test_hamlib_facts_are_on_the_spec() -> None:
    """Hamlib 4.5.4's model numbers, rot_type and get_info text (its rotctl -l, dump_state,
    get_info), which the rotctld port reports."""
    facts = {
        name: (spec.hamlib_model, spec.hamlib_rot_type, spec.hamlib_info)
        for name, spec in REGISTRY.items()
    }
    assert facts == {
        "rotorez": (401, HamlibRotType.OTHER, "Rotor-EZ"),
        "rotorcard": (402, HamlibRotType.OTHER, "RotorCard"),
        "dcu1": (403, HamlibRotType.OTHER, "DCU-1/DCU-1X"),
        "rot2prog": (901, HamlibRotType.AZEL, None),
        "rot1prog": (902, HamlibRotType.AZ, None),
        "md01": (903, HamlibRotType.AZEL, None),
        "satel": (2101, HamlibRotType.AZEL, "SatEL rotator"),
        "gs232a": (601, HamlibRotType.AZEL, None),
        "gs232b": (603, HamlibRotType.AZEL, None),
        "gs232a-az": (609, HamlibRotType.AZ, None),
        "gs232b-az": (611, HamlibRotType.AZ, None),
        "gs232a-450": (601, HamlibRotType.AZEL, None),
        "gs232b-450": (603, HamlibRotType.AZEL, None),
        "gs232a-az-450": (609, HamlibRotType.AZ, None),
        "gs232b-az-450": (611, HamlibRotType.AZ, None),
        **{
            f"easycomm{v}{variant}": (h, HamlibRotType.OTHER, info)
            for v, h, info in ((2, 202, "EasycommII"), (3, 204, "EasycommIII"))
            for variant in ("", "-az", "-separate")
        },
        "rt21": (405, HamlibRotType.OTHER, None),
        "prosistel": (1701, HamlibRotType.AZ, None),
        "prosistel-el": (1702, HamlibRotType.AZ, None),  # its elevation is its bearing
        "prosistel-el-a": (1704, HamlibRotType.AZ, None),  # the same, on unit A
        "prosistel-combi": (1703, HamlibRotType.AZEL, None),
        # Hamlib's one model of the current protocol; the azimuth box is driven by it too
        "rc2800": (1001, HamlibRotType.AZEL, None),
        "rc2800-az": (1001, HamlibRotType.AZ, None),
    }


def test_speed_defaults_come_from_the_spec_and_yield_to_the_users() -> None:
    satel = REGISTRY["satel"]
    assert satel.speeds_deg_s() == (6.0, 2.5)  # a Yaesu G-5500
    assert satel.speeds_deg_s(4.5) == (4.5, 2.5)
    assert satel.speeds_deg_s(None, 1.0) == (6.0, 1.0)
    assert REGISTRY["rot2prog"].speeds_deg_s() == (1.0, 1.0)
