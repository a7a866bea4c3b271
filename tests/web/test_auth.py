"""The console's safety checks (interfaces/web/auth.py), pure: tokens, the password, the login
limit, the Origin and the host name."""

from __future__ import annotations

import ipaddress

import pytest

from bridge.interfaces.web import auth

T0 = 1_800_000_000.0


def test_a_token_is_good_until_it_expires_and_only_under_its_key() -> None:
    tokens = auth.Tokens(auth.key_for(None))
    token = tokens.issue(T0)
    assert tokens.valid(token, T0)
    assert tokens.valid(token, T0 + auth.TOKEN_LIFETIME_S - 1)
    assert not tokens.valid(token, T0 + auth.TOKEN_LIFETIME_S + 1)
    assert not auth.Tokens(auth.key_for(None)).valid(token, T0)  # a restarted bridge's key


@pytest.mark.parametrize("bad", [None, "", "x", "1.2", "a.b.c", "zz.00.00", "." * 300])
def test_anything_but_a_token_is_refused(bad: str | None) -> None:
    assert not auth.Tokens(b"k" * 32).valid(bad, T0)


def test_a_token_with_its_time_changed_is_refused() -> None:
    tokens = auth.Tokens(b"k" * 32)
    issued, nonce, mac = tokens.issue(T0).split(".")
    later = f"{int(issued, 16) + 10**6:x}"
    assert not tokens.valid(f"{later}.{nonce}.{mac}", T0 + 10**6)


def test_the_password_keys_tokens_across_restarts_and_a_new_password_ends_them() -> None:
    token = auth.Tokens(auth.key_for("correct horse")).issue(T0)
    assert auth.Tokens(auth.key_for("correct horse")).valid(token, T0)
    assert not auth.Tokens(auth.key_for("another one")).valid(token, T0)


def test_passwords_compare_whole() -> None:
    assert auth.password_matches("secret-pw", "secret-pw")
    for other in ("", "secret-p", "secret-pw ", "Secret-pw", "secret-pwsecret-pw"):
        assert not auth.password_matches(other, "secret-pw")


def test_failed_logins_are_limited_per_address_and_a_success_costs_nothing() -> None:
    limit = auth.LoginLimiter()
    assert limit.wait("10.0.0.1", T0) is None
    for _ in range(auth.LOGIN_BURST_PER_CLIENT):
        assert limit.wait("10.0.0.1", T0) is None
        limit.failed("10.0.0.1", T0)
    wait = limit.wait("10.0.0.1", T0)
    assert wait is not None and wait > 1
    assert limit.wait("10.0.0.2", T0) is None  # another address has its own tries
    assert limit.wait("10.0.0.1", T0 + auth.LOGIN_EVERY_S) is None  # one more, later


def test_failed_logins_count_by_address_and_the_kind_of_name_asked_for() -> None:
    names = ("shack.example.org",)
    key = auth.login_key
    ours = {key("10.0.0.1", h, names) for h in ("127.0.0.1:8754", "localhost", "Shack.example.org")}
    assert ours == {"10.0.0.1 ours"}  # (a review: one bucket per kind of name was too many)
    others = {key("10.0.0.1", h, names) for h in ("rebind.evil.example", "x.example", None)}
    assert others == {"10.0.0.1 other"}  # one bucket for every other name
    assert key("2001:db8::1", "[::1]:8754") == key("2001:db8::2", "[::2]") == "2001:db8::/64 ours"

    # X-Forwarded-Host counts beside Host, never instead of it: any page may write it (an
    # attack pass: a rebinding page named the console's address there, and spent the operator's
    # tries); a proxy asks the bridge by its address and passes on the name the browser used
    for host, forwarded, kind in [
        ("rebind.evil.example", "127.0.0.1:8754", "other"),
        ("rebind.evil.example", "shack.example.org", "other"),
        ("127.0.0.1:8754", "rebind.evil.example", "other"),
        ("127.0.0.1:8754", "shack.example.org, rebind.evil.example", "other"),
        ("127.0.0.1:8754", "rebind.evil.example, shack.example.org", "other"),
        ("127.0.0.1:8754", "shack.example.org", "ours"),  # docs/console.md's nginx and Caddy
        ("127.0.0.1:8754", "192.168.1.10:8443", "ours"),
        ("shack.example.org", "shack.example.org", "ours"),  # Caddy passing Host on as it came
        ("127.0.0.1:8754", "", "ours"),
        ("127.0.0.1:8754", None, "ours"),
    ]:
        assert key("10.0.0.1", host, names, forwarded=forwarded) == f"10.0.0.1 {kind}", (
            host,
            forwarded,
        )


@pytest.mark.parametrize(
    ("peer", "forwarded", "client"),
    [
        ("127.0.0.1", "192.0.2.10", "192.0.2.10"),  # the browser, by the trusted proxy
        ("127.0.0.1", "6.6.6.6, 192.0.2.10", "192.0.2.10"),  # a forged first entry
        ("127.0.0.1", "192.0.2.10, 10.0.0.2", "192.0.2.10"),  # through two trusted proxies
        ("127.0.0.1", "10.0.0.2", "127.0.0.1"),  # only proxies: the connection's
        ("127.0.0.1", "junk, 192.0.2.10", "192.0.2.10"),
        ("127.0.0.1", "192.0.2.10, junk", "127.0.0.1"),  # nothing past junk is believed
        ("192.0.2.99", "192.0.2.10", "192.0.2.99"),  # not a proxy: its header is not believed
        ("::ffff:127.0.0.1", "192.0.2.10", "192.0.2.10"),
        ("127.0.0.1", None, "127.0.0.1"),
        (None, "192.0.2.10", "?"),
        # a port some proxies add (an attack pass: such an entry was taken for junk, and every
        # browser behind the proxy counted as the proxy)
        ("127.0.0.1", "192.0.2.10:51234", "192.0.2.10"),
        ("127.0.0.1", "[2001:db8::7]:51234", "2001:db8::7"),
        ("127.0.0.1", "[2001:db8::7]", "2001:db8::7"),
        ("127.0.0.1", "2001:db8::7", "2001:db8::7"),
        ("127.0.0.1", "6.6.6.6:1, 10.0.0.2:443", "6.6.6.6"),  # a proxy with its port, skipped
        ("127.0.0.1", "192.0.2.10:port", "127.0.0.1"),  # no port: junk
        ("127.0.0.1", "[2001:db8::7]:", "127.0.0.1"),
    ],
)
def test_only_a_trusted_proxy_is_believed_about_the_browsers_address(
    peer: str | None, forwarded: str | None, client: str
) -> None:
    proxies = (ipaddress.ip_network("127.0.0.1"), ipaddress.ip_network("10.0.0.0/8"))
    assert auth.forwarded_client(peer, forwarded, proxies) == client


@pytest.mark.parametrize(
    ("origin", "host", "forwarded", "ok"),
    [
        (None, "127.0.0.1:8754", None, True),  # not a browser: the token decides
        ("http://127.0.0.1:8754", "127.0.0.1:8754", None, True),
        ("http://LOCALHOST:8754", "localhost:8754", None, True),
        ("https://shack.example.org", "127.0.0.1:8754", "shack.example.org", True),  # a proxy
        ("https://shack.example.org:443", "shack.example.org", None, True),
        ("http://evil.example", "127.0.0.1:8754", None, False),
        ("http://127.0.0.1:9999", "127.0.0.1:8754", None, False),
        ("null", "127.0.0.1:8754", None, False),  # a sandboxed frame, a file: page
        ("ftp://127.0.0.1:8754", "127.0.0.1:8754", None, False),
    ],
)
def test_origin(origin: str | None, host: str, forwarded: str | None, ok: bool) -> None:
    assert auth.origin_allowed(origin, host, forwarded) is ok


@pytest.mark.parametrize(
    ("host", "ok"),
    [
        ("127.0.0.1:8754", True),
        ("localhost:8754", True),
        ("[::1]:8754", True),
        ("192.168.1.5", True),
        ("evil.example:8754", False),  # a name pointed at 127.0.0.1 (DNS rebinding)
        ("127.0.0.1.nip.io", False),
        (None, False),
        ("", False),
    ],
)
def test_host_names_without_a_password(host: str | None, ok: bool) -> None:
    assert auth.host_is_local_name(host) is ok


def test_a_name_the_user_listed_is_taken() -> None:
    assert auth.host_is_local_name("shack.example.org:443", ("shack.example.org",))
    assert not auth.host_is_local_name("evil.example", ("shack.example.org",))
