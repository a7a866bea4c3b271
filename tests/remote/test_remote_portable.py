"""The remote is meant for the operator's own computer, Windows included: it must not need a
module only a POSIX system has (fcntl, termios, pty: the engine's serial code and the pty
server), nor ``select.poll`` (Windows' select module has ``select()`` alone). Proven here by
running ``rotor-bridge remote`` in a Python that refuses to import them and has no poll, against
a real broker: it gets as far as asking the broker for the station."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from tests.support.mosquitto import Mosquitto, free_port
from tests.support.waiting import slow

POSIX_ONLY = ("fcntl", "termios", "pty", "tty", "resource", "grp", "pwd")

RUN = f"""
import select
import sys
for name in {POSIX_ONLY!r}:
    sys.modules[name] = None  # import fails, as on Windows
for name in [n for n in dir(select) if n.startswith(("poll", "POLL", "epoll", "EPOLL"))]:
    delattr(select, name)  # Windows' select has select() alone
from bridge.cli import main
try:
    main(["remote", "-c", sys.argv[1]])
finally:
    loaded = sorted(m for m in sys.modules if m.split(".")[0] == "serial")
    print("LOADED", loaded, file=sys.stderr)
"""


def test_the_remote_starts_without_posix_modules(tmp_path: Path, broker: Mosquitto) -> None:
    conf = tmp_path / "remote.toml"
    conf.write_text(
        'operator = "DL1ABC"\ninfo_wait_s = 1\n'
        f'[mqtt]\nhost = "127.0.0.1"\nport = {broker.port}\nbase_topic = "nostation"\n'
        f"[[endpoints]]\nrotctld_port = {free_port()}\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", RUN, str(conf)],
        capture_output=True,
        text=True,
        timeout=slow(60),
        check=False,
        cwd=Path(__file__).parents[2],
    )
    # it reached the broker and looked for the station's rotator: no import failed on the way
    assert done.returncode == 2, done.stderr
    assert "no description of the station's rotator on nostation/info" in done.stderr
    assert "LOADED []" in done.stderr  # nor pyserial: the remote has no serial line
