"""Who may use the console, and which requests are the page's own. Pure: time is handed in.

The console turns an antenna, so a request another site makes a browser send must never move
it (the rotctld port once obeyed a browser's HTTP request as commands). Rules:

1. Nothing that moves a rotator is a GET. Commands are POSTs with a JSON body and a token in the
   ``X-Rotor-Token`` header: a plain form post cannot set a header, and another site's fetch
   with one is held back by the browser's preflight, which the console never grants.
2. A token is ``<issued, hex>.<nonce>.<mac>``, the MAC an HMAC-SHA256 of the first two parts
   under the console's key. It is good for TOKEN_LIFETIME_S after it was issued and checked in
   constant time. Without a password the key is random per process (a restarted bridge hands
   out new tokens; the page asks again by itself); with one it is derived from the password
   (PBKDF2, so a token seen on the wire is slow to guess the password from), so tokens outlive
   a restart and die with a changed password.
3. A password is compared in constant time (digests of equal length). Logins are rate-limited
   per client address and overall; a refused try is answered without looking at the password,
   so a flood learns nothing.
4. A POST whose ``Origin`` is not this host (the ``Host`` header, or the ``X-Forwarded-Host`` a
   reverse proxy sets) is refused: another site's page, even one holding a token. A request
   without ``Origin`` is not a browser's and needs the token like any.
5. Without a password the console only listens on loopback (settings_web.py) and takes only
   requests addressed to an IP literal, ``localhost`` or a name the user listed (``host_names``,
   a reverse proxy's): a web page whose own host name has been pointed at 127.0.0.1 (DNS
   rebinding) would otherwise be "this host" and could fetch a token.
"""

from __future__ import annotations

import hashlib
import hmac
import ipaddress
import secrets
from collections import OrderedDict
from dataclasses import dataclass, field
from urllib.parse import urlsplit

from bridge.ratelimit import TokenBucket

TOKEN_LIFETIME_S = 7 * 24 * 3600.0
PBKDF2_ROUNDS = 100_000
LOGIN_BURST_PER_CLIENT = 5  # rule 3: then one try per LOGIN_EVERY_S per address
LOGIN_EVERY_S = 30.0
LOGIN_BURST_ALL = 20  # every address together: then one per LOGIN_ALL_EVERY_S
LOGIN_ALL_EVERY_S = 5.0
CLIENTS_KEPT = 4096


def key_for(password: str | None) -> bytes:
    """Rule 2: the key tokens are signed with."""
    if password is None:
        return secrets.token_bytes(32)
    return hashlib.pbkdf2_hmac(
        "sha256", password.encode(), b"rotor-bridge console tokens", PBKDF2_ROUNDS
    )


@dataclass
class Tokens:
    key: bytes

    def issue(self, now_s: float) -> str:
        body = f"{int(now_s):x}.{secrets.token_hex(8)}"
        return f"{body}.{self._mac(body)}"

    def valid(self, token: str | None, now_s: float) -> bool:
        if not token or len(token) > 200:
            return False
        body, _, mac = token.rpartition(".")
        issued_hex, _, nonce = body.partition(".")
        if not nonce or not hmac.compare_digest(mac.encode(), self._mac(body).encode()):
            return False
        try:
            issued = int(issued_hex, 16)
        except ValueError:
            return False
        return issued - 60.0 <= now_s < issued + TOKEN_LIFETIME_S

    def _mac(self, body: str) -> str:
        return hmac.new(self.key, body.encode(), hashlib.sha256).hexdigest()


def password_matches(given: str, password: str) -> bool:
    """Rule 3: in constant time, whatever the lengths."""
    return hmac.compare_digest(
        hashlib.sha256(given.encode()).digest(), hashlib.sha256(password.encode()).digest()
    )


@dataclass
class LoginLimiter:
    """Rule 3: ``allow`` spends a try for ``client`` (an address) or says how long to wait."""

    _clients: OrderedDict[str, TokenBucket] = field(default_factory=OrderedDict)
    _all: TokenBucket | None = None

    def allow(self, client: str, now_s: float) -> float | None:
        """None: the try may go ahead; else the seconds until one may."""
        if self._all is None:
            self._all = TokenBucket.full(LOGIN_BURST_ALL, 1.0 / LOGIN_ALL_EVERY_S, now_s)
        bucket = self._clients.pop(client, None)
        if bucket is None:
            bucket = TokenBucket.full(LOGIN_BURST_PER_CLIENT, 1.0 / LOGIN_EVERY_S, now_s)
        self._clients[client] = bucket  # most recent last
        while len(self._clients) > CLIENTS_KEPT:
            self._clients.popitem(last=False)
        if not bucket.take(now_s):
            return _wait(bucket)
        if not self._all.take(now_s):
            return _wait(self._all)
        return None


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
    parts = urlsplit(origin.strip())
    if parts.scheme not in ("http", "https") or not parts.netloc:
        return False
    mine = {_netloc(h) for h in (host, (forwarded_host or "").split(",")[0]) if h and h.strip()}
    return _netloc(parts.netloc) in mine


def host_is_local_name(host: str | None, names: tuple[str, ...] = ()) -> bool:
    """Rule 5: an IP literal, localhost or one of ``names`` (lower case), with any port."""
    if not host:
        return False
    name = host.strip()
    if name.startswith("["):  # [::1]:8754
        name = name[1 : name.find("]")] if "]" in name else name
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
