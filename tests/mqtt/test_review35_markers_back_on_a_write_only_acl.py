"""Review 35 on db50b34f: markers a new connection's look found refused are asked again every
RESEND_MAX_S, and come back on "once a PUBACK takes one" (halts.py ``_refused_now``). On a
live connection the markers had been coming back until the PUBACKs refused them, so a PUBACK
that takes one is some sign the ACL changed back. The look had more: its hello did not come
back, so reading was denied too, and a PUBACK says nothing of reading (delivery.py: "a publish
taken says nothing of reading"; lastword.py rule 15: an ACL that denies reading alone is told
by no answer). An administrator who mends a typo by letting the bridge publish its markers
(``topic write``) but not read them has the markers turned on again while none can come back:
the next STOP on the stop lane holds the rotator's MQTT targets, its main copy ending nothing
(lastword.py rule 13: while markers can come), for the rest of the connection, hours or days
(review 23's symptom), where the markers known off let the copy end the hold.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import paho.mqtt.client as paho

from bridge.interfaces.mqtt.claim import Claim, Instance
from bridge.interfaces.mqtt.client import LOOK_MAX_S, MqttClient
from bridge.interfaces.mqtt.lastword import RESEND_MAX_S
from bridge.settings import MqttSettings
from tests.mqtt.test_attack5_refused_markers import ConfirmedRig
from tests.mqtt.test_review22_lost_lane_copy import controller
from tests.support import Probe, slow, wait_until
from tests.support.mosquitto import Mosquitto

FENCE, HELLO, CANARY = "rotor/bridge/fence", "rotor/bridge/hello", "rotor/canary"
ALLOWED = "topic readwrite rotor/#\n"
# a typo: B/bridge/# denied to the bridge's user, reading and writing
DENIED = f"topic readwrite rotor/#\ntopic deny {FENCE}\ntopic deny {HELLO}\ntopic deny {CANARY}\n"
# "mended": the markers may be published, not read (no line grants reading them)
WRITE_ONLY = "".join(
    f"topic readwrite {t}\n"
    for t in ("rotor/bridge/state", "rotor/bridge/info", "rotor/sync", CANARY)
) + (f"topic write {FENCE}\ntopic write {HELLO}\n")


def test_markers_a_look_found_unreadable_stay_off_when_the_acl_lets_them_be_published_only(
    tmp_path: Path,
) -> None:
    acl = tmp_path / "acl"
    acl.write_text(ALLOWED)
    # started as root, mosquitto would become user "mosquitto", who cannot read pytest's tmp
    broker = Mosquitto(
        tmp_path / "broker", extra_conf=f"allow_anonymous true\nacl_file {acl}\nuser root"
    )
    broker.start()
    rig = ConfirmedRig()  # a service on a fake clock, the halts timer's work run by hand
    svc, halts, tower = rig.svc, rig.svc._halts, rig.tower  # noqa: SLF001
    looks: list[None] = []
    client = MqttClient(
        MqttSettings(port=broker.port, base_topic="rotor", client_id="rev35w", protocol="5"),
        will_topic="rotor/bridge/state",
        subscriptions=[FENCE, HELLO],
        on_message=lambda topic, payload, retain, *_: svc.on_message(topic, payload, retain),
        on_connect=lambda: looks.append(None),
        on_new_connection=svc.main_gone,  # (as the app's ``_main_new``)
        on_markers=lambda readable: svc.markers_allowed() if readable else svc.markers_denied(),
        claim=Claim(Instance.me("rev35w"), "rotor", "rotor/bridge/info", HELLO),
        fence_topic=FENCE,
    )
    svc.confirm_markers_with(client.publish_marker_confirmed, client.markers_refused)
    probe = Probe(broker.port, CANARY)

    def run(seconds: int, until: Callable[[], bool] = lambda: False) -> None:
        """The halts timer's work, ``seconds`` of it, each marker's PUBACK come."""
        for _ in range(seconds):
            rig.clock.t += 1.0
            halts.resend_if_due()
            sync = client._client.publish("rotor/sync", b"", qos=1)  # noqa: SLF001
            sync.wait_for_publish(slow(5))  # (every PUBACK before it has come)
            assert sync.rc == paho.MQTT_ERR_SUCCESS and sync.is_published()
            halts._refused_now()  # noqa: SLF001
            if until():
                return

    try:
        client.start()
        wait_until(lambda: looks, slow(LOOK_MAX_S), "the first look's end")
        assert halts.word.markers
        # an ACL reload with a typo: a lane STOP's marker, sent again at QoS 1, is refused on
        # both topics (lastword.py rule 15); its main copy ends the hold (rule 7)
        acl.write_text(DENIED)
        broker.reload()
        svc.on_lane_message("rotor/stop", b"", False)
        run(120, lambda: not halts.word.markers)
        assert not halts.word.markers, "the markers refused on the live connection"
        svc.on_message("rotor/stop", b"", False)
        # the broker restarted, the typo still there: the new look's probe is refused, its
        # hello never back: the markers said lost, asked again every RESEND_MAX_S (db50b34f)
        broker.restart()
        wait_until(lambda: len(looks) == 2, slow(LOOK_MAX_S), "the second look's end")
        wait_until(lambda: not halts.word.markers, slow(10), "the markers said lost")
        # the administrator "mends" the typo: the markers may be published, not read
        acl.write_text(WRITE_ONLY)
        broker.reload()
        wait_until(
            lambda: probe.publish(CANARY, "mended?") and probe.on(CANARY),
            slow(10),
            "the broker read the new ACL",
        )
        run(4 * int(RESEND_MAX_S))  # the markers asked again: each PUBACK takes them
        tower.calls.clear()
        svc.on_lane_message("rotor/stop", b"", False)  # the operator's STOP, both connections
        svc.on_message("rotor/stop", b"", False)
        svc.on_message("rotor/target", b"300", False)  # a new target, after the STOP
        run(3600)  # an hour: no marker can come back, the broker delivers none
        reached, _locked = controller(tower.calls)
        assert reached == [300.0], (
            "an hour after a STOP on the stop lane, a target published after it still waits: "
            "the markers were turned on by a PUBACK while the broker lets the bridge publish "
            f"them but not read them, and the hold waits for one (markers on: "
            f"{halts.word.markers}, holding: {halts.word.holding}): {tower.calls}"
        )
    finally:
        client.stop()
        probe.close()
        broker.stop()
