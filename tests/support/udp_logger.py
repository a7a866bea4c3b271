"""Logger programs on UDP, as the bridge's loggers/ endpoints meet them: a PstRotator client, an
N1MM Logger+ rotor sender and a listener for the rotor program's position reports.

Written from the protocol fact sheet (../shared/protocols/logger-udp.md, whose sections are
cited below), never from bridge/loggers: a misreading shared by the server and its test client
would pass every test. Nothing here imports the bridge.

- PstClient (fact sheet 1): one ASCII datagram per command, wrapped in ``<PST>...</PST>``, no
  terminator, sent from an ephemeral port (Hamlib, QLog, horus-gui); replies are awaited on the
  client's own host at the server's port + 1 (Hamlib binds 0.0.0.0:12001; here 127.0.0.1, so
  that parallel test runs keep apart). Values are written as each client writes them: the
  manual's integer, QLog's one decimal, Hamlib 4.6's ``"%f.2"`` (``120.000000.2``).
- ``minos_reply``: the strictest reading of a reply (Minos, 1.2): it must contain a CR, split on
  ``:`` into exactly two parts, and the value must be digits only.
- N1mmSender (2): ``<N1MMRotor>`` turn datagrams in n1kdo's captured one-line form or netrotor's
  README layout, and the three stop forms.
- N1mmListener (2): where the rotor program's position reports go; a report is plain text,
  ``name @ heading*10`` with no leading zeros.
"""

from __future__ import annotations

import contextlib
import re
import select
import socket
import time
from collections.abc import Callable
from dataclasses import dataclass

from tests.support.ports import free_udp_pair
from tests.support.waiting import slow

HOST = "127.0.0.1"
MAX_REPLY = 4096


# -- sockets ------------------------------------------------------------------------------------
def udp_socket(host: str = HOST, port: int = 0) -> socket.socket:
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        sock.bind((host, port))
    except OSError:
        sock.close()
        raise
    return sock


def reserve_pst_ports(host: str = HOST) -> tuple[int, socket.socket]:
    """A free UDP port for a PST server, and a socket already bound to port + 1 where its
    replies will arrive (held from now on, so nobody else takes it). Both below the kernel's
    range for outgoing sockets (ports.py), where no test's sender can take the server's port
    before the bridge binds it."""
    port = free_udp_pair(host)
    return port, udp_socket(host, port + 1)


def _receive(sock: socket.socket, timeout_s: float) -> tuple[bytes, tuple[str, int]] | None:
    """One datagram within ``timeout_s`` (0: only one already waiting), or None."""
    ready, _, _ = select.select([sock], [], [], max(0.0, timeout_s))
    if not ready:
        return None
    data, peer = sock.recvfrom(MAX_REPLY)
    return data, (peer[0], peer[1])


def _drain(sock: socket.socket) -> list[bytes]:
    out = []
    while (got := _receive(sock, 0.0)) is not None:
        out.append(got[0])
    return out


# -- PstRotator (fact sheet 1) -------------------------------------------------------------------
def pst(*items: str) -> bytes:
    """One datagram: ``items`` (tags or queries) wrapped in <PST>...</PST>, nothing after."""
    return ("<PST>" + "".join(items) + "</PST>").encode("ascii")


def tag(name: str, value: object) -> str:
    return f"<{name}>{value}</{name}>"


def hamlib(deg: float) -> str:
    """A value as Hamlib >= 4.6 writes it: C's ``"%f.2"``, the ``.2`` appended literally."""
    return f"{deg:f}.2"


def qlog(deg: float) -> str:
    """A value as QLog and horus-gui write it: one decimal."""
    return f"{deg:.1f}"


def minos_reply(data: bytes) -> tuple[str, int]:
    """(name, value) of a reply the strictest client accepts, or AssertionError saying why not:
    it must contain a CR; with the CRs removed it splits on ``:`` into exactly two parts; the
    value is digits only (1.2, Minos)."""
    assert b"\r" in data, f"no CR in reply {data!r}"
    text = data.replace(b"\r", b"")
    parts = text.split(b":")
    assert len(parts) == 2, f"reply {data!r} does not split into two on ':'"
    name, value = parts
    assert value.isdigit() and value.isascii(), f"reply {data!r}: value not digits only"
    return name.decode("ascii"), int(value)


class PstClient:
    """A PstRotator UDP client on this host, talking to ``server_port``.

    Commands leave from an ephemeral port (``source``); replies are read at ``server_port + 1``
    (``replies``), where Hamlib, QLog and horus-gui listen. A reply to the source port is a
    mistake the fact sheet warns about; ``stray`` shows whether one came."""

    def __init__(
        self, server_port: int, host: str = HOST, *, replies: socket.socket | None = None
    ) -> None:
        self.server = (host, server_port)
        self.source = udp_socket(host)
        try:
            self.replies = replies if replies is not None else udp_socket(host, server_port + 1)
        except OSError:
            self.source.close()
            raise
        assert self.replies.getsockname()[1] == server_port + 1
        self.peers: list[tuple[str, int]] = []  # where each reply came from

    def send(self, datagram: bytes) -> None:
        self.source.sendto(datagram, self.server)

    def command(self, *items: str) -> None:
        self.send(pst(*items))

    def reply(self, timeout_s: float | None = None) -> bytes | None:
        """The next datagram at port + 1, or None within ``timeout_s``; who sent it is added
        to ``peers``."""
        # left out: a deadline for a reply that must come; given: a quiet period for one that
        # must not (waiting.py rule 2)
        got = _receive(self.replies, slow(3.0) if timeout_s is None else timeout_s)
        if got is None:
            return None
        self.peers.append(got[1])
        return got[0]

    def stray(self, timeout_s: float = 0.0) -> bytes | None:
        """A datagram that came back to the source port instead (there should be none)."""
        got = _receive(self.source, timeout_s)
        return None if got is None else got[0]

    def ask(self, query: str, timeout_s: float = 3.0) -> bytes:
        """``AZ?`` or ``EL?`` on its own (as Hamlib sends them): the reply datagram."""
        self.send(pst(f"{query}?"))
        got = self.reply(slow(timeout_s))
        assert got is not None, f"no reply to {query}? at port {self.server[1] + 1}"
        return got

    def drain(self) -> list[bytes]:
        return _drain(self.replies)

    def close(self) -> None:
        self.source.close()
        self.replies.close()

    def __enter__(self) -> PstClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


# -- N1MM Logger+ (fact sheet 2) -----------------------------------------------------------------
def n1mm_turn(
    rotor: str,
    az_deg: float,
    *,
    offset: str = "0.0",
    bidirectional: int = 0,
    freqband: str = "14",
    layout: str = "one line",
) -> bytes:
    """A turn as N1MM sends it: n1kdo's captured sample (one line, no XML declaration, goazi
    with one decimal) or, with ``layout="readme"``, netrotor's README layout on several lines."""
    fields = [
        tag("rotor", rotor),
        tag("goazi", f"{az_deg:.1f}"),
        tag("offset", offset),
        tag("bidirectional", bidirectional),
        tag("freqband", freqband),
    ]
    if layout == "one line":
        return ("<N1MMRotor>" + "".join(fields) + "</N1MMRotor>").encode("ascii")
    inner = "".join(f"\r\n  {f}" for f in fields)
    return f"<N1MMRotor>{inner}\r\n</N1MMRotor>\r\n".encode("ascii")


#: the three stop forms (fact sheet 2): netrotor's README (Ctrl+Alt+J), the rotor's name as the
#: stop's text, and <rotor> beside <stop>
N1MM_STOPS: dict[str, Callable[[str], bytes]] = {
    "netrotor": lambda rotor: (
        f"<N1MMRotor><stop>{tag('rotor', rotor)}{tag('freqband', '21.0')}</stop></N1MMRotor>"
    ).encode("ascii"),
    "name in stop": lambda rotor: f"<N1MMRotor>{tag('stop', rotor)}</N1MMRotor>".encode("ascii"),
    "rotor beside stop": lambda rotor: (
        f"<N1MMRotor>{tag('rotor', rotor)}{tag('stop', 1)}</N1MMRotor>"
    ).encode("ascii"),
}


class N1mmSender:
    """N1MM Logger+'s side: datagrams to the rotor program's command port, from an ephemeral
    port (there is no reply channel)."""

    def __init__(self, port: int, host: str = HOST) -> None:
        self.to = (host, port)
        self.sock = udp_socket(host)

    def send(self, datagram: bytes) -> None:
        self.sock.sendto(datagram, self.to)

    def close(self) -> None:
        self.sock.close()


_REPORT = re.compile(rb"(?P<name>.+) @ (?P<tenths>0|[1-9][0-9]*)")


@dataclass(frozen=True)
class Report:
    raw: bytes
    name: str
    heading_deg: float
    t: float  # when it was read (time.monotonic)


def parse_report(data: bytes, t: float = 0.0) -> Report:
    """A position report, ``name @ heading*10`` (``rotor on com1 @ 650`` is 65.0 deg), or
    AssertionError naming what is wrong with it."""
    m = _REPORT.fullmatch(data)
    assert m is not None, f"not a position report 'name @ heading*10': {data!r}"
    tenths = int(m.group("tenths"))
    assert tenths < 3600, f"heading over 360 deg in {data!r}"
    return Report(data, m.group("name").decode("ascii"), tenths / 10.0, t)


class N1mmListener:
    """Where the rotor program sends its position reports (13010 by default; here a port of our
    own, given to the bridge as its report destination)."""

    def __init__(self, host: str = HOST, port: int = 0) -> None:
        self.sock = udp_socket(host, port)
        self.address = f"{host}:{self.sock.getsockname()[1]}"
        self.seen: list[Report] = []

    def drain(self) -> list[Report]:
        now = time.monotonic()
        new = [parse_report(d, now) for d in _drain(self.sock)]
        self.seen += new
        return new

    def wait(self, predicate: Callable[[Report], bool], timeout_s: float, what: str) -> Report:
        """The first report from now on for which ``predicate`` holds (every report read is
        checked for the documented form and kept in ``seen``)."""
        deadline = time.monotonic() + slow(timeout_s)
        while True:
            got = _receive(self.sock, deadline - time.monotonic())
            if got is None:
                recent = [r.raw for r in self.seen[-8:]]
                raise AssertionError(f"no report {what} in {timeout_s:g} s; last seen {recent}")
            report = parse_report(got[0], time.monotonic())
            self.seen.append(report)
            if predicate(report):
                return report

    def close(self) -> None:
        with contextlib.suppress(OSError):
            self.sock.close()
