"""Attack 33: a careless user's odd numbers on the demo's flags end in a Python traceback instead
of the one-line refusal every other bad flag gets (``--speed-deg-s 0.1``, ``--models rotorz``,
``--base-topic rotor/#``: exit code 2 and a line naming the flag). ``--satellite-rises-in-s nan``
(or ``inf``, ``1e300``) starts the private broker and then dies in ``time.gmtime``;
``--web-port 99999`` (or ``-1``) dies in ``socket.bind`` with ``OverflowError``; ``--duration-s
inf`` starts everything and dies at once in ``math.ceil`` ("cannot convert float infinity to
integer") instead of running until q; ``--duration-s nan`` starts and ends the demo at once,
saying nothing of why. Each is input the demo cannot use: refused with exit code 2 and a message
naming the flag, before anything starts (no private broker, nothing left in the temp folder)."""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge import demo
from bridge.cli import build_parser
from tests.support.mosquitto import answers, free_port

ODD = [
    ("--satellite-rises-in-s", "nan"),
    ("--satellite-rises-in-s", "inf"),
    ("--satellite-rises-in-s", "1e300"),
    ("--web-port", "99999"),
    ("--web-port", "-1"),
    ("--duration-s", "inf"),
    ("--duration-s", "nan"),
    ("--duration-s", "1e300"),
    ("--duration-s", "-1"),
    ("--mqtt-port", "99999"),
]


@pytest.mark.parametrize(("flag", "value"), ODD)
def test_an_odd_number_on_a_demo_flag_is_refused_naming_the_flag(
    flag: str,
    value: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    port = free_port()
    argv = ["demo", "--mqtt-port", str(port), "--web-port", "0", flag, value]
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as refused:
        code = refused.code
    else:
        try:
            code = demo.run(args)
        except Exception as crash:  # what the user sees: a traceback
            pytest.fail(f"{flag} {value}: a traceback, {crash!r}")
    err = capsys.readouterr().err
    assert code == 2, f"{flag} {value}: exit code {code}, not a refusal; said: {err[-300:]}"
    assert flag in err, f"the refusal does not name {flag}: {err[-300:]}"
    assert not answers("127.0.0.1", port), "a private broker was left running"
    assert sorted(p.name for p in tmp_path.iterdir()) == []
