"""Where the N1MM position reports go, as an address the loggers' thread sends to without a
lookup (server.py rule 6): ``n1mm_report_to`` may name the logger's computer (``n1mm-pc.lan``),
and a name handed to ``sendto`` is resolved right there, on the thread that reads every logger
port. A name server that does not answer held that thread in the lookup 5 to 10 s at every
report (an attack pass: a PstRotator STOP reached the rotor 5 s late, 50 degrees on).

Rules:
1. The loggers' thread never resolves a name. An address given in digits is the address, known
   at once, and nothing is looked up. A name is looked up on a thread of its own (one per
   host:port, however many rotators report there), started with the loggers' thread and
   stopped with it; the loggers' thread reads the last address it found (``current``), and
   while none was found, its reports are dropped (said once by server.py).
2. The name is looked up again every REFRESH_S (the logger's computer may get a new address
   from DHCP), and after a failure every RETRY_S. A lookup that fails keeps the address found
   before: a name server down for a while stops no report to a computer that is still there.
   A failure is said once at warning level, until a lookup works again (said at info level,
   with the address).
3. Only IPv4 is asked for: the reports leave from the N1MM port's own socket, an IPv4 one.
4. stop() never waits for a lookup: the thread is a daemon, told to end, and ends when its
   lookup returns (a lookup the name server never answers lasts its timeout, seconds).
"""

from __future__ import annotations

import ipaddress
import logging
import socket
import threading
from collections.abc import Callable

log = logging.getLogger(__name__)

REFRESH_S = 60.0  # rule 2: a name found is looked up again this often
RETRY_S = 10.0  # rule 2: a name not found is looked up again this often

Lookup = Callable[[str, int], str]  # a name and a port -> an IPv4 address in digits


def lookup_ipv4(host: str, port: int) -> str:
    """Rule 3: the first IPv4 address of ``host`` (OSError if it has none)."""
    infos = socket.getaddrinfo(host, port, socket.AF_INET, socket.SOCK_DGRAM)
    if not infos:  # (getaddrinfo raises rather than answer nothing; the safe side)
        raise OSError(f"no IPv4 address for {host}")
    return str(infos[0][4][0])


def in_digits(host: str) -> str | None:
    """Rule 1: ``host`` as an IPv4 address in digits, if it is one (no lookup)."""
    try:
        return str(ipaddress.IPv4Address(host))
    except ValueError:
        return None


class ReportAddress:
    """One ``n1mm_report_to``: ``current()`` is where a report goes now, None while a name has
    not been found (rule 1)."""

    def __init__(self, host: str, port: int, lookup: Lookup = lookup_ipv4) -> None:
        self.host, self.port = host, port
        self._lookup = lookup
        digits = in_digits(host)
        self.by_name = digits is None
        self._address: tuple[str, int] | None = None if digits is None else (digits, port)
        self._stop: threading.Event | None = None
        self.lookups = 0  # (how many the thread made: for the tests)

    def current(self) -> tuple[str, int] | None:
        """Rule 1: where a report goes now; never a lookup (one attribute read)."""
        return self._address

    def start(self) -> None:
        """Rule 1: a name's thread of its own (nothing for an address in digits)."""
        if not self.by_name or self._stop is not None:
            return
        self._stop = stop = threading.Event()
        threading.Thread(
            target=self._run, args=(stop,), name=f"n1mm-lookup {self.host}", daemon=True
        ).start()

    def stop(self) -> None:
        """Rule 4: the thread is told to end; never waited for."""
        if self._stop is not None:
            self._stop.set()
            self._stop = None

    def _run(self, stop: threading.Event) -> None:
        failing = False
        while not stop.is_set():
            self.lookups += 1
            try:
                digits = self._lookup(self.host, self.port)
                if in_digits(digits) is None:  # (a lookup's answer is digits: the safe side)
                    raise OSError(f"the lookup gave {digits!r}, not an IPv4 address")
            except Exception as exc:  # rule 2: said once, the address found before kept
                if not failing:
                    kept = self._address
                    log.warning(
                        "N1MM reports to %s:%d: the name could not be looked up (%s); %s",
                        self.host,
                        self.port,
                        exc,
                        f"they still go to {kept[0]}" if kept else "none is sent until it is",
                    )
                failing = True
                if stop.wait(RETRY_S):
                    return
                continue
            address = digits, self.port
            if address != self._address or failing:
                log.info("N1MM reports to %s:%d go to %s", self.host, self.port, digits)
            self._address, failing = address, False
            if stop.wait(REFRESH_S):
                return
