"""The console's safety checks (interfaces/web/auth.py), pure: tokens, the password, the login
limit, the Origin and the host name."""

from __future__ import annotations

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
