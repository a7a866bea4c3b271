"""homeassistant/ rule 10: no two entities ask Home Assistant for one entity id. ``sat``'s
tracked elevation and ``sat_track``'s elevation both asked for ``sensor.sat_track_elevation``
(attack 20): Home Assistant gave the second ``_2`` and a card written from
docs/homeassistant.md showed the other antenna's value. The rule that holds for every pair: no
entity id suffix of a platform ends in '_' and another of that platform; proven here over the
suffixes of every model, feature, group and the bridge, and over any two device ids the
settings take, through the builders themselves (the ``default_entity_id`` of every config)."""

from __future__ import annotations

import json
from collections import Counter, defaultdict

from hypothesis import assume, given
from hypothesis import strategies as st

from bridge.core.text import entity_slug
from bridge.feature import registered
from bridge.interfaces.homeassistant.entities import all_configs
from bridge.interfaces.homeassistant.info import GroupInfo, Identity, RotatorInfo
from bridge.interfaces.mqtt.topics import Topics
from bridge.protocols import REGISTRY

MODELS = sorted(REGISTRY)


def _rotator(rid: str, model: str, topics: Topics) -> RotatorInfo:
    """A rotator with everything configured: every entity its model can have."""
    spec = REGISTRY[model]
    return RotatorInfo(
        rid, rid, spec, topics.rotator(rid),
        spec.az_min_deg, spec.az_max_deg, spec.el_min_deg, spec.el_max_deg,
        version="1.0", presets=("home",), has_park=True, has_station=True,
        track_options=("off", "sun", "moon", "ISS (ZARYA)"), can_follow=True,
        features=frozenset(f.name for f in registered()), spot_options=("K1ABC",),
        el_health=spec.has_elevation,
    )  # fmt: skip


def _asked(devices: list[tuple[str, str | None]]) -> list[str]:
    """Every entity id the discovery configs ask for: ``devices`` are (id, model) for a
    rotator, (id, None) for a group; the bridge's own entity with them."""
    rotators = [(i, m) for i, m in devices if m is not None]
    groups = [i for i, m in devices if m is None]
    topics = Topics(
        "rotor", {i: f"rotor/r/{i}" for i, _ in rotators}, {g: f"rotor/g/{g}" for g in groups}
    )
    infos = [_rotator(i, m, topics) for i, m in rotators]
    ginfos = tuple(GroupInfo(g, g, topics.group(g), ("a", "b")) for g in groups)
    configs = all_configs("homeassistant", Identity("rotor"), topics, infos, ginfos)
    return [json.loads(p)["default_entity_id"] for p in configs.values()]


def _suffixes() -> dict[str, set[str]]:
    """Each platform's entity id suffixes: every model's rotator with everything configured, a
    group and the bridge (its slug taken off what each asks for)."""
    out: dict[str, set[str]] = defaultdict(set)
    asked = [a for m in MODELS for a in _asked([("tower", m)])] + _asked([("tower", None)])
    bridge = entity_slug(Identity("rotor").bridge_node)
    for entity_id in asked:
        platform, rest = entity_id.split(".", 1)
        for slug in ("tower", bridge):
            if rest.startswith(slug + "_"):
                out[platform].add(rest.removeprefix(slug + "_"))
    return out


def test_no_entity_id_suffix_ends_with_another_of_its_platform() -> None:
    """Of ``a_X`` = ``b_Y`` (two slugs, ``a`` the shorter) ``X`` ends in ``_Y``: without such a
    pair no two devices whose slugs differ (the settings refuse two that are one) ask for one
    entity id."""
    suffixes = _suffixes()
    assert {"elevation", "track_el", "track_azimuth"} <= suffixes["sensor"]  # (it saw them)
    assert {"connection", "moving"} <= suffixes["binary_sensor"]
    ends = [
        (platform, longer, shorter)
        for platform, mine in suffixes.items()
        for longer in mine
        for shorter in mine
        if longer.endswith("_" + shorter)
    ]
    assert ends == []


# ids the settings take (settings/rotator.py, settings/groups.py), and ids made of the words of
# the entities' suffixes, where a pair like 'sat' and 'sat_track' is found
WORDS = ("sat", "track", "target", "elevation", "azimuth", "option", "next", "last", "speed", "el")
ROTATOR_IDS = st.one_of(
    st.from_regex(r"[a-z0-9][a-z0-9_-]{0,47}", fullmatch=True),
    st.lists(st.sampled_from(WORDS), min_size=1, max_size=4).map("_".join),
)
GROUP_IDS = st.one_of(
    st.from_regex(r"[a-z0-9_-]{1,32}", fullmatch=True),
    st.lists(st.sampled_from(WORDS), min_size=1, max_size=3).map("_".join),
)
DEVICES = st.one_of(
    st.tuples(ROTATOR_IDS, st.sampled_from(MODELS)),
    st.tuples(GROUP_IDS, st.none()),
)


@given(DEVICES, DEVICES)
def test_no_two_devices_ask_home_assistant_for_one_entity_id(
    one: tuple[str, str | None], other: tuple[str, str | None]
) -> None:
    assume(entity_slug(one[0]) != entity_slug(other[0]))  # the settings refuse the rest
    assume("bridge" not in (one[0], other[0]))
    asked = Counter(_asked([one, other]))
    assert [e for e, n in asked.items() if n > 1] == []


def test_sat_and_sat_track_ask_for_two_entity_ids_and_sat_track_keeps_the_documented_one() -> None:
    """The attack's pair: ``sat_track``'s elevation is ``sensor.sat_track_elevation`` as
    docs/homeassistant.md's table says; ``sat``'s tracked elevation is ``sensor.sat_track_el``."""
    asked = _asked([("sat", "md01"), ("sat_track", "md01")])
    assert asked.count("sensor.sat_track_elevation") == 1
    assert "sensor.sat_track_el" in asked and "sensor.sat_track_track_el" in asked
