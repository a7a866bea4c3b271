from bridge.interfaces.mqtt.topics import DiscoveryTopics, Topics


def test_single_rotator_lives_on_the_base_topic() -> None:
    t = Topics("rotor", {"tower": "rotor"})
    r = t.rotator("tower")
    assert (r.target, r.bearing, r.option_state("jam"), t.bridge_state) == (
        "rotor/target",
        "rotor/bearing",
        "rotor/option/jam/state",
        "rotor/bridge/state",
    )
    assert t.subscriptions() == [
        "rotor/target",
        "rotor/target/elevation",
        "rotor/stop",
        "rotor/lock",
        "rotor/option/+",
        "rotor/preset",
        "rotor/park",
        "rotor/nudge",
        "rotor/track",
        "rotor/follow",
        "rotor/health/reset",
        "rotor/control/claim",
        "rotor/control/release",
        "rotor/bridge/fence",
    ]
    assert t.stop_lane() == ["rotor/stop", "rotor/lock"]
    assert t.bridge_fence_lane == "rotor/bridge/fence/lane"


def test_routing_inbound_topics() -> None:
    t = Topics("rotor", {"a": "rotor/a", "b": "rotor/b"})
    assert t.route("rotor/a/target") == ("a", "target", None)
    assert t.route("rotor/b/stop") == ("b", "stop", None)
    assert t.route("rotor/b/target/elevation") == ("b", "target_elevation", None)
    assert t.route("rotor/b/option/jam") == ("b", "option", "jam")
    assert t.route("rotor/b/option/jam/state") is None
    assert t.route("rotor/b/lock/state") is None
    assert t.route("rotor/c/target") is None
    kinds = ("preset", "park", "nudge", "presets", "track", "tracking")
    assert [t.route(f"rotor/a/{k}") for k in kinds] == [
        ("a", "preset", None),
        ("a", "park", None),
        ("a", "nudge", None),
        None,  # outbound
        ("a", "track", None),
        None,  # outbound
    ]
    assert t.route("rotor/a/bearing") is None


def test_discovery_config_topics_round_trip_and_stay_under_their_prefix() -> None:
    d = DiscoveryTopics("ha/x")
    topic = d.config("sensor", "rotorbridge_rotor_r_tower", "bearing")
    assert topic == "ha/x/sensor/rotorbridge_rotor_r_tower/bearing/config"
    assert d.parse_config(topic) == ("sensor", "rotorbridge_rotor_r_tower", "bearing")
    assert (d.config_filter, d.subtree) == ("ha/x/+/+/+/config", "ha/x/")
    for other in (
        "homeassistant/sensor/node/bearing/config",  # another prefix
        "ha/x/sensor/node/bearing/state",
        "ha/x/sensor/node/config",  # too short
        "ha/x/sensor/a/node/bearing/config",  # too long
        "ha/sensor/node/bearing/config/x",
    ):
        assert d.parse_config(other) is None, other
