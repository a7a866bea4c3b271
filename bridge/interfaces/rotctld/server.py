"""The TCP side: the shared line server (interfaces/tcplines.py) with rotctld's parser and commands,
one session per client (``p`` answers each client in its own terms)."""

from __future__ import annotations

import string
import time
from collections.abc import Callable

from bridge.core.model import Origin, Source
from bridge.interfaces.rotctld.commands import Rotator, RotctldCommands
from bridge.interfaces.rotctld.parser import Quit, RequestParser, holds_stop
from bridge.interfaces.tcplines import (
    CLOSE,
    USEFUL_WITHIN_S,
    Close,
    Fence,
    LineServer,
    halt_count,
    halt_watchers,
)


class RotctldSession:
    """One client: its parser and its commands (tcplines.LineSession)."""

    def __init__(self, rotator: Rotator, peer: str | None = None) -> None:
        self._parser = RequestParser()
        self._commands = RotctldCommands(rotator, Origin(Source.ROTCTLD, None, peer))

    @property
    def idle(self) -> bool:
        return self._parser.idle

    @property
    def fence(self) -> Fence:
        """tcplines.py rule 9: when this client's bytes came, for its moves."""
        return self._commands.fence

    def feed(self, data: bytes) -> list[bytes | Close]:
        out: list[bytes | Close] = []
        for item in self._parser.feed(data):
            if isinstance(item, Quit):
                out.append(CLOSE)
                break
            out.append(self._commands.execute(item))
        return out


#: tcplines.py rule 8: what Hamlib's network client (``rotctl -m 2``) sends when it opens, and
#: waits for the answer to before the command it was run for
HANDSHAKES = (b"\\dump_state\n", b"\\dump_state\r\n")


def _greeting(rotator: Rotator, data: bytes) -> bytes | None:
    """tcplines.py rule 8: the answer to ``data`` when it is the handshake alone (what the
    rotator's limits say: nothing of its motion), else None."""
    if data not in HANDSHAKES:
        return None
    return b"".join(out for out in RotctldSession(rotator).feed(data) if isinstance(out, bytes))


# tcplines.py rule 2: the bytes of the commands that move nothing and need no line end, let
# through a first line held for the HTTP check while it is nothing else: rotctld answers a bare
# ``S`` (stop), ``p`` or ``s`` at once, no line end after it, and so the extended forms
# (``+S``, ``;S``, ``+\stop``: a prefix of punctuation, spaces, ``\stop``'s letters). An
# attack pass: a script's ``printf S | nc`` got no RPRT 0, and the rotor turned on to its
# target (review 64: ``+S`` likewise). What such a line can run is a stop, a position or a
# status asked, or an error; a web page's request line that begins with S (``SEARCH``) runs
# its first byte alone, a stop, and is refused whole.
SINGLES = bytes(sorted(ord(c) for c in string.punctuation if c not in "\\_#")) + b" \t\\Spsto"


class RotctldServer(LineServer):
    """One TCP listener for one rotator; one thread per client."""

    def __init__(
        self,
        rotator: Rotator,
        port: int,
        bind: str = "127.0.0.1",
        *,
        max_clients: int = 16,
        idle_timeout_s: float = 300.0,
        useful_within_s: float = USEFUL_WITHIN_S,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        super().__init__(
            rotator.id,
            port,
            bind,
            lambda: RotctldSession(rotator),
            label="rotctld",
            key="rotctld",
            max_clients=max_clients,
            idle_timeout_s=idle_timeout_s,
            useful_within_s=useful_within_s,
            clock=clock,
            peer_session=lambda peer: RotctldSession(rotator, peer),
            halts=holds_stop,
            singles=SINGLES,
            greets=lambda data: _greeting(rotator, data),
            halt_count=halt_count(rotator),
            halt_watchers=halt_watchers(rotator),
        )
        self.rotator = rotator
