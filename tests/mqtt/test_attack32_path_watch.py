"""Attack 32 in virtual time: the main connection tells a dead path under its connections from a
frozen broker (heartbeat.py rule 12, ``PathWatch`` over ``Echo``): a probe while the connection
is silent, and the path dead only when the broker answered the probe and the connection saw
quiet past that answer, nothing read since the probe began. The real broker and a dead proxy:
tests/faults/test_attack32_stop_lost_on_a_dead_path.py."""

from __future__ import annotations

from bridge.interfaces.mqtt.heartbeat import (
    PROBE_CALM_S,
    PROBE_FIRST_S,
    PROBE_MAX_S,
    QUIET_S,
    PathWatch,
)
from tests.mqtt.test_broker_late import POLL_S, Link


def silent_link() -> Link:
    """A connection whose beat has been out through QUIET_S of quiet, the quiet going on."""
    link = Link()
    link.send()
    link.quiet(QUIET_S + POLL_S)
    assert link.echo.silent(link.clock())
    return link


def test_a_healthy_link_is_never_silent_and_never_probed() -> None:
    link, watch = Link(), PathWatch()
    for _ in range(50):
        beat = link.send()
        link.quiet(0.002)
        assert link.back(beat)
        link.quiet(2.9)
        assert not watch.due(link.clock(), link.echo.silent(link.clock()))


def test_a_silent_link_is_probed_at_once_and_dead_once_quiet_is_seen_past_the_answer() -> None:
    link, watch = silent_link(), PathWatch()
    now = link.clock()
    assert watch.due(now, link.echo.silent(now))
    assert not watch.due(now, True)  # (one probe at a time)
    link.quiet(0.01)
    watch.answered(now, link.clock())  # the broker answered a new connection
    assert not watch.dead(link.echo, link.clock())  # quiet not yet seen past the answer
    link.quiet(POLL_S)
    assert watch.dead(link.echo, link.clock())
    assert not watch.dead(link.echo, link.clock())  # (once: the answer is used up)


def test_a_read_after_the_probe_began_is_a_live_path_whatever_the_probe_says() -> None:
    """A frozen broker that runs on answers the probe waiting in its backlog, but sends the
    connection what it held first: no verdict."""
    link, watch = silent_link(), PathWatch()
    began = link.clock()
    assert watch.due(began, True)
    link.quiet(0.5)
    link.read()  # what the broker held (a STOP among it)
    watch.answered(began, link.clock())
    link.quiet(POLL_S)
    assert not watch.dead(link.echo, link.clock())


def test_an_unanswered_probe_keeps_the_connections_and_probes_again_at_a_doubling_pace() -> None:
    link, watch = silent_link(), PathWatch()
    starts = []
    for _ in range(400):
        now = link.clock()
        if watch.due(now, link.echo.silent(now)):
            starts.append(now)
            link.quiet(0.25)
            watch.unanswered()
            assert not watch.dead(link.echo, link.clock())
        link.quiet(0.25)
    gaps = [round(b - a, 2) for a, b in zip(starts, starts[1:], strict=False)]
    assert gaps[:5] == [min(PROBE_FIRST_S * 2**k, PROBE_MAX_S) for k in range(5)]
    assert max(gaps) == PROBE_MAX_S


def test_the_pace_starts_again_only_once_calm() -> None:
    watch = PathWatch()
    assert watch.due(0.0, True)
    watch.unanswered()
    assert not watch.due(PROBE_FIRST_S - 0.1, True)
    assert watch.due(PROBE_FIRST_S, True)
    watch.unanswered()
    assert not watch.due(PROBE_FIRST_S + 2 * PROBE_FIRST_S - 0.1, True)
    watch.unanswered()
    later = PROBE_FIRST_S + PROBE_CALM_S
    assert watch.due(later, True)
    watch.unanswered()
    assert watch.due(later + PROBE_FIRST_S, True)  # (the first wait again)


def test_no_beat_ever_back_no_probe() -> None:
    """An ACL that drops the beats: nothing to judge the quiet by (heartbeat.py rule 11)."""
    link, watch = Link(read_back=False), PathWatch()
    link.send()
    link.quiet(30.0)
    assert not link.echo.silent(link.clock())
    assert not watch.due(link.clock(), link.echo.silent(link.clock()))


def test_an_answer_for_the_last_connection_proves_nothing_of_the_next() -> None:
    link, watch = silent_link(), PathWatch()
    began = link.clock()
    assert watch.due(began, True)
    watch.answered(began, began + 0.01)
    watch.connected()
    link.echo.connected()
    link.read()  # the new connection's CONNACK
    link.back(link.send())
    link.send()
    link.quiet(QUIET_S + POLL_S)
    assert not watch.dead(link.echo, link.clock())
