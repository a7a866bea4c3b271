"""Who a network peer is, for the limits kept per peer (the console's failed logins,
interfaces/web/auth.py; the TCP ports' budgets, interfaces/tcplines.py): an IPv6 address counts
as its /64 (one host has all of it), an IPv4-mapped one as its IPv4 address, any other as
itself; a link-local scope (``%eth0``) is dropped."""

from __future__ import annotations

import ipaddress


def peer_key(host: str) -> str:
    try:
        address = ipaddress.ip_address(host.split("%")[0])
    except ValueError:
        return host
    if isinstance(address, ipaddress.IPv6Address):
        if address.ipv4_mapped is not None:
            return str(address.ipv4_mapped)
        return str(ipaddress.ip_network(f"{address}/64", strict=False))
    return str(address)
