"""Free loopback ports for the tests, TCP and UDP, that no other test can take before the one
they are handed to listens on them. Nothing here imports the bridge.

A port the kernel hands out (bind to 0, read it, close) is one any test's outgoing connection or
unbound ``sendto`` may be given next, before the test's listener binds it; a busy parallel suite
does that (a PstRotator port was taken so in a CI run, and a module's fifteen tests failed to
start). So a port is picked below the kernel's range for outgoing sockets, where only a listener
can take it, from this worker's own share (two workers never pick the same port), and never
twice in one process.
"""

from __future__ import annotations

import os
import random
import socket

HOST = "127.0.0.1"

_PICK = random.SystemRandom()
_HANDED: set[int] = set()  # the ports this process picked: not picked twice, bound or not


def _ephemeral_low() -> int:
    try:
        with open("/proc/sys/net/ipv4/ip_local_port_range") as f:
            return int(f.read().split()[0])
    except (OSError, ValueError, IndexError):
        return 32768


def _own_range() -> range:
    """This process's share of the ports below the kernel's range for outgoing sockets: one
    slice per parallel worker (``PYTEST_XDIST_WORKER`` gwN of ``PYTEST_XDIST_WORKER_COUNT``),
    so that two workers never pick the same port (they did: both found it free, and the second
    to listen failed, once in eight CI runs)."""
    low, top = 10_000, _ephemeral_low()
    worker = os.environ.get("PYTEST_XDIST_WORKER", "")
    try:
        index, count = int(worker.removeprefix("gw")), int(os.environ["PYTEST_XDIST_WORKER_COUNT"])
    except (KeyError, ValueError):
        return range(low, top)
    if not 0 <= index < count or top - low < 100 * count:
        return range(low, top)
    share = (top - low) // count
    return range(low + index * share, low + (index + 1) * share)


def _binds(kind: int, port: int, host: str) -> bool:
    with socket.socket(socket.AF_INET, kind) as s:
        try:
            s.bind((host, port))
        except OSError:
            return False
    return True


def _pick(kind: int, host: str, fits: int = 1) -> int:
    """A port p free now for ``kind`` with p .. p + fits - 1 all free and never handed out,
    all of them in this process's share (``_own_range``)."""
    share = _own_range()
    ports = range(share.start, share.stop - (fits - 1))
    for _ in range(200):
        port = _PICK.choice(ports)
        span = range(port, port + fits)
        if any(p in _HANDED for p in span) or not all(_binds(kind, p, host) for p in span):
            continue
        _HANDED.update(span)
        return port
    if fits > 1:
        raise RuntimeError(f"no {fits} free ports in a row in {ports} after 200 tries")
    with socket.socket(socket.AF_INET, kind) as s:  # a crowded range: the kernel's choice
        s.bind((host, 0))
        return int(s.getsockname()[1])


def free_port(host: str = HOST) -> int:
    """A TCP port on ``host`` free now, that no outgoing connection can take (module doc)."""
    return _pick(socket.SOCK_STREAM, host)


def free_udp_port(host: str = HOST) -> int:
    """A UDP port on ``host`` free now, that no unbound sender can take (module doc)."""
    return _pick(socket.SOCK_DGRAM, host)


def free_udp_pair(host: str = HOST) -> int:
    """A UDP port n free now with n + 1 free too (a PstRotator server and its replies)."""
    return _pick(socket.SOCK_DGRAM, host, fits=2)
