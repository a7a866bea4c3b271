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
    # lastword.py rule 16: the stop lane carries nothing a neighbour's lock words can flood
    assert t.stop_lane() == ["rotor/stop"]
    assert t.lock_lane() == ["rotor/lock"]
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


def routed_one_by_one(
    t: Topics, roots: dict[str, str], topic: str
) -> tuple[str, str, str | None] | None:
    """What route answers, worked out from the rotators' topics one at a time, in their order:
    a core command, then a registered feature's command, then an option."""
    for rid in roots:
        r = t.rotator(rid)
        for kind in ("target", "target_elevation", "stop", "lock", "preset", "park", "nudge"):
            if topic == getattr(r, kind):
                return rid, kind, None
        for feature in t.features:
            for command in feature.commands:
                if topic == r.feature(command.suffix):
                    return rid, command.kind, None
        prefix = r.option("")
        if topic.startswith(prefix) and "/" not in topic[len(prefix) :]:
            return rid, "option", topic[len(prefix) :]
    return None


def test_route_answers_for_the_first_rotator_whose_topic_it_is_whatever_the_roots() -> None:
    """One table built once answers as the rotators' topics looked at one by one: with one
    rotator on the base topic, with 16, and with roots one inside another."""
    layouts = [
        {"tower": "rotor"},
        {f"r{i}": f"rotor/r{i}" for i in range(16)},
        {"a": "rotor/a", "ab": "rotor/a/b", "opt": "rotor/a/option", "base": "rotor"},
    ]
    for roots in layouts:
        t = Topics("rotor", roots)
        suffixes = {"target", "target/elevation", "stop", "lock", "preset", "park", "nudge"}
        suffixes |= {c.suffix for f in t.features for c in f.commands}
        suffixes |= {"option/jam", "option/jam/state", "option/", "bearing", "status", "b/target"}
        topics = {f"{root}/{s}" for root in roots.values() for s in suffixes}
        topics |= {"rotor", "rotor/", "other/target", "homeassistant/sensor/x/bearing/config"}
        for topic in sorted(topics):
            assert t.route(topic) == routed_one_by_one(t, roots, topic), topic


def test_the_posts_another_bridge_would_stand_on_are_this_bridges_own_topics() -> None:
    """claim.py rule 5: each rotator's and group's root and the base topic, and a bridge's info
    under each rotator's and group's root; nothing above the base topic."""
    several = Topics("rotor", {"tower": "rotor/tower", "yagi": "far/yagi"}).posts()
    assert several == [
        "rotor/bridge/info",
        "rotor/tower/bridge/info",
        "far/yagi/bridge/info",
        "rotor/tower/info",
        "far/yagi/info",
        "rotor/info",
    ]
    grouped = Topics("rotor", {"upper": "rotor/upper"}, {"tower": "rotor/tower"}).posts()
    assert grouped == [  # review 77: a group's root too
        "rotor/bridge/info",
        "rotor/upper/bridge/info",
        "rotor/tower/bridge/info",
        "rotor/upper/info",
        "rotor/tower/info",
        "rotor/info",
    ]
    assert Topics("rotor/tower", {"mast": "rotor/tower"}).posts() == [
        "rotor/tower/bridge/info",
        "rotor/tower/info",
    ]
