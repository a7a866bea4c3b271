"""An attack pass on the remote: two endpoints onto one station rotator (one GS-232A port for
PstRotatorAz beside a GS-232B or rotctld one: ``gs232_replies`` is per endpoint, so serving both
takes two ``[[endpoints]]`` naming the same rotator), a console STOP kept while the station's
broker is away, and numbers past a float's range in what the station publishes."""

from __future__ import annotations

from collections.abc import Callable, Iterator

import pytest

from bridge.core.errors import RefusalCode, Refused
from bridge.core.model import Source, Stop, Target
from bridge.remote.run import Remote
from bridge.remote.settings import RemoteSettings
from tests.support.mosquitto import free_port
from tests.support.rig import Rig


@pytest.fixture
def remote(station: Rig) -> Iterator[Remote]:
    r = Remote(
        RemoteSettings(
            operator="DL1ABC",
            mqtt={"host": "127.0.0.1", "port": station.broker.port, "base_topic": "rotor"},
            endpoints=[
                {"rotator": "tower", "rotctld_port": free_port()},
                {"rotator": "tower", "gs232_port": free_port(), "gs232_replies": "A"},
            ],
            web={"enabled": True, "port": free_port()},
        )
    )
    r.start()
    yield r
    r.stop()


def test_a_stop_on_one_endpoint_refuses_a_move_another_endpoint_judged_before_it(
    remote: Remote,
) -> None:
    """docs/architecture.md rule 11 across the remote's front ends: the GS-232A port's STOP,
    sent while the rotctld port's P was between its judge and the link, must not be overtaken
    by the P (remote/rotator.py ``submit``). With one RemoteRotator per endpoint, the STOP was
    counted on the other's and the P went out after it: the rotor turned after the STOP."""
    rotctld_rot, gs232_rot = remote.rotators
    assert remote.link is not None
    link = remote.link
    hand_on: Callable[..., None] = link.send

    def send(topic: str, payload: str, *args: object, **kw: object) -> None:
        if topic.endswith("/target"):  # the GS-232A client's S, on its own thread, now
            gs232_rot.submit(Stop(Source.GS232), "gs232 S")
        hand_on(topic, payload, *args, **kw)

    link.send = send  # type: ignore[method-assign]
    with pytest.raises(Refused) as caught:
        rotctld_rot.submit(Target(200.0, None, Source.ROTCTLD), "rotctld P 200")
    assert caught.value.code is RefusalCode.STALE


def test_the_console_shows_one_rotator_once_and_its_stop_counts_for_every_endpoint(
    remote: Remote,
) -> None:
    """The console's STOP must refuse a rotctld move judged before it on either endpoint."""
    assert remote.console is not None
    shown = list(remote.console._rotators.values())
    assert [r.id for r in shown] == ["tower"]
    console_rot = shown[0]
    for rot in remote.rotators:
        before = rot.halts
        console_rot.submit(Stop(Source.WEB))
        assert rot.halts == before + 1, "the console's STOP counted on every endpoint's rotator"


def test_a_status_with_a_number_past_a_floats_range_reads_as_unavailable_not_a_crash() -> None:
    """readings.py rule 1: anyone allowed on R/status can put anything there, and it reads as
    ValueError, never more. A pass track holding an integer past a float's range raised
    OverflowError out of ``status``: the console's ticker logged a traceback every second and
    showed no rotator's status any more, and a rotctld ``p`` got no answer."""
    from tests.remote.test_remote_rotator import rotator
    from tests.support.clock import FakeClock
    from tests.support.remote import Link

    rot = rotator(Link(), FakeClock())
    huge = b"1" + b"0" * 400
    rot._view.put(
        rot.topics.status,
        b'{"state":"idle","bearing":120,"connected":true,"available":true,'
        b'"tracking":{"body":"ISS","pass_track":[[' + huge + b",10]]}}",
    )
    status = rot.status
    assert not status.available


def test_presets_and_an_error_event_with_a_number_past_a_floats_range_are_left_out() -> None:
    """R/presets and R/error are anyone's the ACL lets publish there: a preset whose bearing is
    an integer past a float's range raised OverflowError from the console's rotator's
    ``pointing`` (every use: the page's state, each command judged), and such an error event's
    time raised on paho's thread, losing it; the other presets stay, the event is not one."""
    from bridge.remote.console import Drawn, RemoteConsoleRotator, parse_event
    from tests.remote.test_remote_rotator import rotator
    from tests.support.clock import FakeClock
    from tests.support.remote import Link

    huge = b"1" + b"0" * 400
    remote = rotator(Link(), FakeClock())
    remote._view.put(remote.topics.presets, b'{"far":' + huge + b',"north":0}')
    console = RemoteConsoleRotator(remote, Drawn(), remote._view)
    assert console.pointing.presets == {"north": (0.0, None)}
    assert parse_event(b'{"kind":"refused","message":"x","time":' + huge + b"}") is None


def test_a_page_s_move_numbered_before_its_stop_kept_while_the_broker_was_away_never_goes() -> None:
    """commands.py rule 5 on the remote: a command a page numbered before a STOP the same page
    sent after it is stale however late it comes. The STOP pressed while the station's broker
    was away is kept and sent first on reconnect (interfaces/mqtt/remote.py rule 6), but its
    answer was a refusal (OFFLINE, not delivered yet), so the console did not note it: the
    page's older target, held up on the way and arriving after the reconnect, went out after
    that STOP and turned the rotor."""
    from bridge.interfaces.web.view import RotatorFacts
    from bridge.remote.console import Drawn, RemoteConsoleRotator
    from tests.remote.test_remote_rotator import rotator
    from tests.support.clock import FakeClock
    from tests.support.console import ConsoleClient
    from tests.support.remote import Link
    from tests.web.test_far_commands import new_console

    link = Link()
    remote_rot = rotator(link, FakeClock())
    console = new_console()
    console.attach(RemoteConsoleRotator(remote_rot, Drawn(), remote_rot._view), RotatorFacts())
    console.listen()
    try:
        client = ConsoleClient(console.port)
        client.session()
        link.up = False  # the station's broker away: the STOP is kept (the stand-in refuses it)
        stop = client.command("tower", command="stop", page="p1", seq=6)
        assert stop.status == 409 and stop.doc["code"] == "offline"
        link.up = True  # back: the kept STOP goes first
        late = client.command("tower", command="target", az=200, page="p1", seq=5)
        assert late.status == 409, late
        assert [t for t, _ in link.sent if t.endswith("/target")] == []
    finally:
        console.stop()
