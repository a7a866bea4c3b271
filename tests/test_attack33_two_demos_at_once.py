"""Attack 33: two demos started at once (two terminals, a double click on a launcher) each find
nothing answering on 127.0.0.1:1883 and each start a private mosquitto there; the one whose
mosquitto loses the race for the port ends with "could not start: no MQTT broker answers and
mosquitto exited: ... Address already in use", exit code 1, although a broker (the other demo's)
answers by then. The README: the demo "never gets in the way of ... another demo": with a
broker that is another demo's it starts a private mosquitto on a free port. Two
``rotor-bridge demo`` processes started at once on one port, three times: one of them failed
twice. The test makes the race certain: the other demo's broker comes up between this demo's
look (``connack``, which found nothing an instant before) and its own mosquitto's bind.
Asserted: what the user sees, the demo's exit code and whether it said it is bridged."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from bridge import demo
from bridge.cli import build_parser
from bridge.demo.mosquitto import Mosquitto as PrivateBroker
from tests.support.mosquitto import free_port
from tests.support.waiting import slow


def test_a_demo_whose_private_port_another_demo_just_took_still_starts(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    port = free_port()
    looks: list[tuple[int, bool] | None] = []
    real_connack = demo.connack_of

    def looked_an_instant_before_the_other_came_up(
        host: str, p: int, *a: float, **kw: Callable[[], bool]
    ) -> tuple[int, bool] | None:
        if not looks:  # this demo's first look: the other demo's mosquitto not up yet
            looks.append(None)
            return None
        looks.append(real_connack(host, p, *a, **kw))
        return looks[-1]

    other = PrivateBroker(tmp_path / "other", port=port)  # the other demo's, up a moment later
    try:
        other.start(slow(10))
        monkeypatch.setattr(demo, "connack_of", looked_an_instant_before_the_other_came_up)
        args = build_parser().parse_args(
            ["demo", "--mqtt-port", str(port), "--web-port", "0", "--duration-s", "1"]
        )
        code = demo.run(args)
    finally:
        other.stop()
    said = capsys.readouterr()
    assert code == 0, f"the second demo did not start (exit {code}): {said.err[-400:]}"
    assert "bridged to" in said.out, said.out[-400:]
