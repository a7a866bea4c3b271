"""The console's command bodies (interfaces/web/commands.py): what parses, and what is refused by
name."""

from __future__ import annotations

import subprocess
import sys
import time
from dataclasses import replace
from typing import Any

import pytest

from bridge.interfaces.web.commands import (
    _OFFSET_S,
    MAX_AGE_S,
    STALE,
    BadCommand,
    Order,
    WebCommand,
    aged,
    feed_clock,
    parse,
)
from tests.support import ROOT

RUN: dict[str, Any] = {
    "capture_output": True,
    "text": True,
    "check": True,
    "cwd": ROOT,
    "timeout": 60,
}


@pytest.mark.parametrize(
    ("body", "expected"),
    [
        (b'{"command":"stop"}', WebCommand("stop")),
        (b'{"command":"target","az":120.5}', WebCommand("target", az_deg=120.5)),
        (b'{"command":"target","az":10,"el":30}', WebCommand("target", az_deg=10, el_deg=30)),
        (
            b'{"command":"toward","latitude_deg":40.7,"longitude_deg":-74,"long_path":true}',
            WebCommand("toward", latitude_deg=40.7, longitude_deg=-74.0, long_path=True),
        ),
        (b'{"command":"path","long_path":true}', WebCommand("path", long_path=True)),
        (b'{"command":"preset","name":"EU"}', WebCommand("preset", name="EU")),
        (b'{"command":"park"}', WebCommand("park")),
        (b'{"command":"nudge","d_az":-5}', WebCommand("nudge", az_deg=-5.0)),
        (b'{"command":"track","body":"moon"}', WebCommand("track", name="moon")),
        (b'{"command":"lock","on":true}', WebCommand("lock", on=True)),
    ],
)
def test_commands_parse(body: bytes, expected: WebCommand) -> None:
    assert parse(body) == expected


def test_a_locator_is_checked_and_written_as_locators_are() -> None:
    cmd = parse(b'{"command":"toward","locator":"fn31PR"}')
    assert cmd.locator == "FN31pr"
    assert cmd.latitude_deg == pytest.approx(41.7, abs=0.1)
    assert cmd.described() == "console: toward FN31pr short path"


@pytest.mark.parametrize(
    ("body", "says"),
    [
        (b"", "not a JSON command"),
        (b"\xff", "not a JSON command"),
        (b"[1]", "JSON object"),
        (b'{"command":"fly"}', "unknown command"),
        (b'{"command":"target"}', '"az" is missing'),
        (b'{"command":"target","az":"120"}', "finite number"),
        (b'{"command":"target","az":NaN}', "not a number"),
        (b'{"command":"target","az":1e999}', "finite number"),
        (b'{"command":"target","az":true}', "finite number"),
        (b'{"command":"target","az":1,"azz":2}', "unknown key(s) for target: azz"),
        (b'{"command":"lock"}', '"on" is missing'),
        (b'{"command":"lock","on":"yes"}', "true or false"),
        (b'{"command":"toward","locator":"ZZ99"}', "ZZ99"),
        (b'{"command":"toward","locator":"JO62","latitude_deg":1}', "not both"),
        (b'{"command":"toward","latitude_deg":91,"longitude_deg":0}', "-90..90"),
        (b'{"command":"preset","name":""}', "1 to 80"),
        (b'{"command":"preset","name":"a\\u0000b"}', "holds U+0000, which MQTT does not carry"),
        # an attack pass: a lone surrogate killed the audit writer; the remote answered 500
        (b'{"command":"preset","name":"\\ud800"}', "holds U+D800"),
        (b'{"command":"preset","name":"X\\ufdd0"}', "holds U+FDD0"),
        (b'{"command":"track","body":"\\udfff"}', "holds U+DFFF"),
        (b'{"command":[]}', "unknown command"),
        (b'{"command":"target","az":10,"az":350}', "key 'az' given twice"),
        (b"[" * 3000, "nested too deep"),
        (b'{"command":"target","az":' + b"9" * 400 + b"}", "finite number"),
        (b'{"command":"stop","pad":"' + b"x" * 5000 + b'"}', "at most"),
    ],
)
def test_bad_bodies_are_refused_by_name(body: bytes, says: str) -> None:
    with pytest.raises(BadCommand, match=None) as caught:
        parse(body)
    assert says in str(caught.value)


def test_a_stop_with_its_command_key_twice_is_still_a_stop() -> None:
    """A review: a key given twice is refused only with two values (core/jsonkeys.py)."""
    assert parse(b'{"command":"stop","command":"stop"}').halts()


def test_a_move_sent_too_long_ago_or_ahead_of_the_clock_is_refused_a_halt_never() -> None:
    """commands.py rule 6: ``sent`` is the bridge's steady clock as the page reckoned it."""
    click = parse(b'{"command":"target","az":120,"sent":100.0}')
    assert click.sent == 100.0
    assert aged(click, 100.0 + MAX_AGE_S - 0.5) is None
    assert aged(click, 112.4) == "not carried out: sent 12 s ago (a move older than 5 s is refused)"
    assert "ahead of the bridge's clock" in str(aged(click, 98.0))
    unlock = parse(b'{"command":"lock","on":false,"sent":100.0}')
    assert aged(unlock, 200.0) is not None  # a lock OFF held up is as late as a move
    for halt in (
        b'{"command":"stop"',
        b'{"command":"lock","on":true',
        b'{"command":"track","body":"off"',
    ):
        assert aged(parse(halt + b',"sent":100.0}'), 1000.0) is None
    assert aged(parse(b'{"command":"park"}'), 1000.0) is None  # a script's, unstamped
    for bad in (b'"x"', b"-1", b"true", b"1e999"):
        with pytest.raises(BadCommand, match='"sent"'):
            parse(b'{"command":"park","sent":' + bad + b"}")


def test_a_move_the_page_sent_before_a_halt_is_stale_however_late_its_request_began() -> None:
    """Rule 5 with rule 6's send time: an attack pass, a click (or a lock OFF) held up before
    its request reached the console, after a STOP (a lock ON) by MQTT was carried out, was
    carried out: only when its request began was compared with the halt."""
    order, halted = Order(), 1000.0  # (the steady clock: monotonic)
    before, after = halted - 0.3 + _OFFSET_S, halted + 0.3 + _OFFSET_S  # (the feed's clock)
    for cmd in (
        WebCommand("target", az_deg=300.0, page="p1", seq=2, sent=before),
        WebCommand("lock", on=False, page="p1", seq=2, sent=before),
        WebCommand("target", az_deg=300.0, sent=before),  # a script's, not numbered
    ):
        assert order.stale("hf", cmd, halted + 2.0, halted) == STALE, cmd
        assert order.stale("hf", replace(cmd, sent=after), halted + 2.0, halted) is None, cmd
    assert order.stale("hf", WebCommand("target", az_deg=1.0), halted + 2.0, halted) is None
    # the page's own STOP, numbered before the click: the page sent the click after it,
    # though its reckoning of the time errs on the old side (rule 6)
    order.halted("hf", WebCommand("stop", page="p1", seq=5), halted)
    mine = WebCommand("target", az_deg=30.0, page="p1", seq=6, sent=halted - 0.01 + _OFFSET_S)
    assert order.stale("hf", mine, halted + 0.5, halted) is None
    assert order.stale("hf", replace(mine, seq=4), halted + 0.5, halted) == STALE


def test_the_feed_clock_is_not_the_hosts_uptime_and_holds_across_a_bridge_restart() -> None:
    """Rule 6: the clock every page is told is the host's steady clock moved by the boot's own
    offset. The steady clock alone said how long the host had been up; and two processes of
    one boot (a bridge restarted) agree, so a click reckoned against the one before is judged
    by its true age."""
    told = "from bridge.interfaces.web.commands import feed_clock; import time; "
    told += "print(repr(feed_clock() - time.monotonic()))"
    offsets = {
        round(float(subprocess.run([sys.executable, "-c", told], **RUN).stdout), 3)
        for _ in range(2)
    }
    assert len(offsets) == 1, offsets  # one offset for every process of this boot
    (offset,) = offsets
    assert offset > 1.0 and round(feed_clock() - time.monotonic(), 3) == offset
