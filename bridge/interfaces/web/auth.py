"""Who may use the console, and which requests are the page's own. Pure: time is handed in.

The console turns an antenna, so a request another site makes a browser send must never move
it (the rotctld port once obeyed a browser's HTTP request as commands). Rules:

1. Nothing that moves a rotator is a GET. Commands are POSTs with a JSON body and a token in the
   ``X-Rotor-Token`` header: a plain form post cannot set a header, and another site's fetch
   with one is held back by the browser's preflight, which the console never grants.
2. A token is ``<issued, hex>.<nonce>.<mac>``, the MAC an HMAC-SHA256 of the first two parts
   under the console's key. It is good for TOKEN_LIFETIME_S after it was issued and checked in
   constant time. Without a password the key is random per process (a restarted bridge hands
   out new tokens; the page asks again by itself); with one it is derived from the password and
   this installation's own random secret (PBKDF2, so a token seen on the wire is slow to guess
   the password from, and another bridge with the same password takes none of these tokens),
   so tokens outlive a restart and die with a changed password. A token past its life is still
   genuine: it carries a STOP or a lock ON (docs/architecture.md rule 11), nothing else.
   The time a token is issued and judged by is the station's clock (app.py hands the one its
   heartbeats carry: the wall clock, never set back while the bridge runs, interfaces/mqtt/
   heartbeat.py rule 6): on the raw wall clock set back 10 minutes every token handed out
   before was "issued in the future", and each click of every page was refused as expired,
   a login again on every page (an attack pass).
   A token is ASCII (hex and dots): anything else offered as one is no token, looked at no
   further (an attack pass: a header or subprotocol holding a byte that is not UTF-8, or a
   first message's lone surrogate, raised encoding it for the MAC, a 500 and a traceback at
   ERROR for anyone who reaches the port, no token needed).
3. A password is compared in constant time (digests of equal length). Failed logins are
   limited per client address (an IPv6 address by its /64, which one client has plenty of) and
   kind of name asked for (``login_key``); a client over its limit is answered without the
   password being looked at, so a flood learns nothing, and a right password from another
   address, or from the operator's own page while another name's page in the same browser
   floods (an attack pass: a DNS-rebinding page locked the operator's own logins out), is
   never held back by it. A login is to one of the console's own names only when its ``Host``
   and every name in any ``X-Forwarded-Host`` are (rule 5's names, read as rule 5 reads them):
   any page may write that header on its own origin's requests, and a rebinding page that
   named the console's own address in it spent the operator's tries (an attack pass). Behind a
   proxy, which writes it over any a page wrote, the name the browser used still decides. A
   login that succeeds costs nothing (each new tab logs in).
4. A POST whose ``Origin`` is not this host (the ``Host`` header, or the ``X-Forwarded-Host`` a
   reverse proxy sets) is refused: another site's page, even one holding a token. A request
   without ``Origin`` is not a browser's and needs the token like any. An ``Origin`` that is no
   URL (``http://[::1``) is another site's too, refused (403), never a 500 (an attack pass).
5. Without a password the console only listens on loopback (settings/web.py) and takes only
   requests addressed to an IP literal, ``localhost`` or a name the user listed (``host_names``,
   a reverse proxy's): a web page whose own host name has been pointed at 127.0.0.1 (DNS
   rebinding) would otherwise be "this host" and could fetch a token. Behind a proxy the name
   asked for is the ``X-Forwarded-Host`` it passes on, checked the same way (a name pointed at
   the proxy is the same attack).
6. Behind a reverse proxy every request comes from the proxy's address. One listed in
   ``trusted_proxies`` is believed about the browser's (its ``X-Forwarded-For``'s last entry
   that is no listed proxy), for the login's limit and for who sent a command; nothing else's
   ``X-Forwarded-For`` is (an attack pass: through the proxy, one visitor's wrong passwords
   held back the operator's right one for as long as they went on). An entry with the port
   some proxies add is read as its address (it was taken for junk, and every browser counted
   as the proxy); a listed network wider than one address is check-config's warning.
   Whoever reaches the console directly from a trusted proxy's address writes the
   ``X-Forwarded-For`` it likes, so each failed login named a new client with tries of its
   own (an attack pass: with ``trusted_proxies = ["127.0.0.1"]``, the docs' own example, any
   program on the host tried 3,000 passwords in about a second, none held back). A proxy
   vouches for PROXIED_NEW_BURST clients new to the limiter (they get tries of their own),
   then for one every PROXIED_NEW_EVERY_S; the rest share one client's tries, the proxy's. A
   client known before (one that failed once) keeps its own; under such a flood a client new
   to the console waits with the flood's.
"""

from __future__ import annotations

import hashlib
import hmac
import ipaddress
import secrets
from collections import OrderedDict
from dataclasses import dataclass, field
from urllib.parse import urlsplit

from bridge.core.ratelimit import TokenBucket

TOKEN_LIFETIME_S = 7 * 24 * 3600.0
PBKDF2_ROUNDS = 100_000
LOGIN_BURST_PER_CLIENT = 5  # rule 3: failed tries, then one per LOGIN_EVERY_S per address
LOGIN_EVERY_S = 30.0
# rule 6: clients new to the limiter a trusted proxy may vouch for (each then gets tries of its
# own), then one per PROXIED_NEW_EVERY_S; past that they share the proxy's own tries
PROXIED_NEW_BURST = 16
PROXIED_NEW_EVERY_S = 60.0
CLIENTS_KEPT = 4096


def key_for(password: str | None, secret: bytes = b"") -> bytes:
    """Rule 2: the key tokens are signed with (``secret``: this installation's own)."""
    if password is None:
        return secrets.token_bytes(32)
    return hashlib.pbkdf2_hmac(
        "sha256", password.encode(), b"rotor-bridge console tokens" + secret, PBKDF2_ROUNDS
    )


@dataclass
class Tokens:
    key: bytes

    def issue(self, now_s: float) -> str:
        body = f"{int(now_s):x}.{secrets.token_hex(8)}"
        return f"{body}.{self._mac(body)}"

    def valid(self, token: str | None, now_s: float) -> bool:
        issued = self.issued(token)
        return issued is not None and issued - 60.0 <= now_s < issued + TOKEN_LIFETIME_S

    def expires(self, token: str | None) -> float | None:
        issued = self.issued(token)
        return None if issued is None else issued + TOKEN_LIFETIME_S

    def issued(self, token: str | None) -> float | None:
        """When a genuine token (this key's) was issued, whether or not it has expired; None
        for anything else (rule 2)."""
        if not token or len(token) > 200 or not token.isascii():  # (rule 2: ours are ASCII)
            return None
        body, _, mac = token.rpartition(".")
        issued_hex, _, nonce = body.partition(".")
        if not nonce or not hmac.compare_digest(mac.encode(), self._mac(body).encode()):
            return None
        try:
            return float(int(issued_hex, 16))
        except ValueError:
            return None

    def _mac(self, body: str) -> str:
        return hmac.new(self.key, body.encode(), hashlib.sha256).hexdigest()


def password_matches(given: str, password: str) -> bool:
    """Rule 3: in constant time, whatever the lengths. A lone surrogate (JSON's ``\\ud800``,
    which no password file holds: it is UTF-8) is a wrong password like any, counted against
    the tries (an attack pass: its ``encode`` raised, a 500 with a traceback, never limited)."""
    return hmac.compare_digest(
        hashlib.sha256(given.encode("utf-8", "surrogatepass")).digest(),
        hashlib.sha256(password.encode()).digest(),
    )


@dataclass
class LoginLimiter:
    """Rule 3: ``wait`` says whether ``client`` (an address) may try now; ``failed`` spends.
    ``proxy``: the trusted proxy that vouched for ``client`` (rule 6), if one did."""

    _clients: OrderedDict[str, TokenBucket] = field(default_factory=OrderedDict)
    _vouched: OrderedDict[str, TokenBucket] = field(default_factory=OrderedDict)  # rule 6

    def wait(self, client: str, now_s: float, proxy: str | None = None) -> float | None:
        """None: the try may go ahead; else the seconds until one may."""
        bucket = self._clients.get(client_key(client))
        if bucket is None:
            if proxy is None or self._new_allowed(proxy, now_s):
                return None
            return self.wait(_proxied(proxy), now_s)  # rule 6: the proxy's own tries
        return None if _refilled(bucket, now_s).tokens >= 1.0 else _wait(bucket)

    def failed(self, client: str, now_s: float, proxy: str | None = None) -> None:
        key = client_key(client)
        if key not in self._clients and proxy is not None:  # rule 6: new, vouched for
            if self._new_allowed(proxy, now_s):
                self._vouched[proxy].take(now_s)
            else:
                key = _proxied(proxy)
        tries = _touched(self._clients, key, LOGIN_BURST_PER_CLIENT, LOGIN_EVERY_S, now_s)
        tries.take(now_s)

    def _new_allowed(self, proxy: str, now_s: float) -> bool:
        """Rule 6: whether ``proxy`` may still vouch for a client new to the limiter."""
        vouched = _touched(self._vouched, proxy, PROXIED_NEW_BURST, PROXIED_NEW_EVERY_S, now_s)
        return _refilled(vouched, now_s).tokens >= 1.0


def _touched(
    buckets: OrderedDict[str, TokenBucket], key: str, burst: int, every_s: float, now_s: float
) -> TokenBucket:
    """``key``'s bucket (full if new: ``burst``, then one per ``every_s``), made the most
    recent; the least recent go past CLIENTS_KEPT."""
    bucket = buckets.pop(key, None)
    if bucket is None:
        bucket = TokenBucket.full(burst, 1.0 / every_s, now_s)
    buckets[key] = bucket  # most recent last
    while len(buckets) > CLIENTS_KEPT:
        buckets.popitem(last=False)
    return bucket


def _refilled(bucket: TokenBucket, now_s: float) -> TokenBucket:
    """``bucket`` with what it earned up to ``now_s`` (looked at, nothing taken)."""
    bucket.tokens = min(bucket.burst, bucket.tokens + (now_s - bucket.t) * bucket.rate_per_s)
    bucket.t = now_s
    return bucket


def _proxied(proxy: str) -> str:
    """Rule 6: the tries the clients a proxy vouched for past its share have between them."""
    return f"through {client_key(proxy)}"


Networks = tuple[ipaddress.IPv4Network | ipaddress.IPv6Network, ...]  # rule 6: the proxies


def login_key(
    client: str, host: str | None, names: tuple[str, ...] = (), *, forwarded: str | None = None
) -> str:
    """Rule 3: whose failed logins count together: the client's address (``client_key``) and
    whether the request was addressed to one of the console's own names (an IP literal,
    ``localhost``, one of ``names``) or another, so that a page of another name open in the
    operator's browser (DNS rebinding) spends its own tries, not those of the operator's own
    tab, and a client that writes names of its own gets one bucket more, not one per name (a
    review: one per kind of name was three and more). Its own names are ``host`` and every
    name in ``forwarded`` (the ``X-Forwarded-Host``, if any), all of them: a rebinding page
    writes the console's own address there, its ``Host`` it cannot."""
    asked = [host, *(forwarded.split(",") if forwarded and forwarded.strip() else ())]
    ours = all(host_is_local_name(name, names) for name in asked)
    return f"{client_key(client)} {'ours' if ours else 'other'}"


def forwarded_client(
    peer: str | None,
    forwarded_for: str | None,
    proxies: Networks,
) -> str:
    """Rule 6: the client a request is from: the connection's address, or, from one of
    ``proxies``, the last address in ``X-Forwarded-For`` that is not one of them (what the
    nearest proxy saw; those before it anyone can write)."""
    if not peer or not forwarded_for or not _among(peer, proxies):
        return peer or "?"
    for item in reversed(forwarded_for.split(",")):
        entry = _address(item.strip())
        if entry is None:
            return peer  # (no address: nothing after it is believed)
        if not _among(entry, proxies):
            return entry
    return peer


def _address(entry: str) -> str | None:
    """An ``X-Forwarded-For`` entry's address: as it is, or with the port some proxies add
    (``192.0.2.7:51234``, ``[2001:db8::7]:51234``); None if it is none."""
    for text in (entry, *_without_port(entry)):
        try:
            return str(ipaddress.ip_address(text))
        except ValueError:
            continue
    return None


def _without_port(entry: str) -> tuple[str, ...]:
    if entry.startswith("["):  # [v6]:port, or [v6]
        host, sep, port = entry[1:].partition("]")
        return (host,) if sep and (port == "" or port[:1] == ":" and port[1:].isdigit()) else ()
    host, sep, port = entry.rpartition(":")
    if sep and port.isdigit() and ":" not in host:  # v4:port (a bare v6 has many colons)
        return (host,)
    return ()


def _among(address: str, networks: Networks) -> bool:
    try:
        ip = ipaddress.ip_address(address)
    except ValueError:
        return False
    if isinstance(ip, ipaddress.IPv6Address) and ip.ipv4_mapped is not None:
        ip = ip.ipv4_mapped
    return any(ip in net for net in networks)


def client_key(client: str) -> str:
    """An IPv6 address counts by its /64 (one client has all of it), any other as it is."""
    try:
        address = ipaddress.ip_address(client)
    except ValueError:
        return client
    if isinstance(address, ipaddress.IPv6Address):
        if address.ipv4_mapped is not None:
            return str(address.ipv4_mapped)
        return str(ipaddress.ip_network(f"{address}/64", strict=False))
    return str(address)


def _wait(bucket: TokenBucket) -> float:
    return max(1.0, (1.0 - bucket.tokens) / bucket.rate_per_s)


def _netloc(text: str) -> str:
    """``host[:port]`` lower-cased, without the default ports."""
    text = text.strip().casefold()
    for default in (":80", ":443"):
        if text.endswith(default):
            return text[: -len(default)]
    return text


def origin_allowed(origin: str | None, host: str | None, forwarded_host: str | None) -> bool:
    """Rule 4."""
    if origin is None:
        return True
    if origin.strip() == "null":
        return False
    try:
        parts = urlsplit(origin.strip())
    except ValueError:  # (an unclosed IPv6 bracket)
        return False
    if parts.scheme not in ("http", "https") or not parts.netloc:
        return False
    mine = {_netloc(h) for h in (host, (forwarded_host or "").split(",")[0]) if h and h.strip()}
    return _netloc(parts.netloc) in mine


def host_is_local_name(host: str | None, names: tuple[str, ...] = ()) -> bool:
    """Rule 5: an IP literal, localhost or one of ``names`` (lower case), with any port."""
    if not host:
        return False
    name = host.strip()
    if name.startswith("["):  # [::1] or [::1]:8754, and nothing else after the bracket
        inside, bracket, rest = name[1:].partition("]")
        if not bracket or not (rest == "" or (rest[:1] == ":" and rest[1:].isdigit())):
            return False
        name = inside
    elif name.count(":") == 1:
        name = name.rsplit(":", 1)[0]
    name = name.casefold()
    if name == "localhost" or name.endswith(".localhost") or name in names:
        return True
    try:
        ipaddress.ip_address(name)
    except ValueError:
        return False
    return True
