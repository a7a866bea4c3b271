"""A plain HTTP client of the operator console (bridge/interfaces/web/), as a script would use it:
the token, the commands, the live feed. The standard library only."""

from __future__ import annotations

import asyncio
import concurrent.futures
import http.client
import json
import time
from collections.abc import Callable, Coroutine
from dataclasses import dataclass
from typing import Any, TypeVar

from tests.support.mosquitto import free_port
from tests.support.waiting import slow

T = TypeVar("T")


def web_section(port: int | None = None, **more: Any) -> dict[str, Any]:
    """The ``[web]`` table of a rig's configuration: on, loopback, a free port."""
    return {"enabled": True, "bind": "127.0.0.1", "port": port or free_port(), **more}


@dataclass
class Answer:
    status: int
    doc: Any
    headers: dict[str, str]


class ConsoleClient:
    def __init__(self, port: int, host: str = "127.0.0.1") -> None:
        self.port = port
        self.host = host
        self.token: str | None = None

    def request(
        self,
        method: str,
        path: str,
        body: bytes | None = None,
        headers: dict[str, str] | None = None,
    ) -> Answer:
        conn = http.client.HTTPConnection(self.host, self.port, timeout=slow(10))
        try:
            conn.request(method, path, body=body, headers=headers or {})
            resp = conn.getresponse()
            raw = resp.read()
            kind = resp.getheader("Content-Type", "")
            doc = json.loads(raw) if kind.startswith("application/json") else raw
            return Answer(resp.status, doc, {k.lower(): v for k, v in resp.getheaders()})
        finally:
            conn.close()

    def session(self) -> str:
        answer = self.post("/api/session", {}, token=False)
        assert answer.status == 200, answer
        self.token = answer.doc["token"]
        return str(self.token)

    def post(
        self, path: str, doc: Any, *, token: bool = True, headers: dict[str, str] | None = None
    ) -> Answer:
        sent = {"Content-Type": "application/json", "Origin": f"http://{self.host}:{self.port}"}
        if token and self.token is not None:
            sent["X-Rotor-Token"] = self.token
        sent.update(headers or {})
        return self.request("POST", path, json.dumps(doc).encode(), sent)

    def get(self, path: str) -> Answer:
        headers = {"X-Rotor-Token": self.token} if self.token else {}
        return self.request("GET", path, headers=headers)

    def command_head(self, rotator: str, body: bytes) -> bytes:
        """The head of the page's own command request for ``body``, to send by hand (a body
        held up on the way: the tests send it in parts)."""
        return (
            f"POST /api/rotators/{rotator}/command HTTP/1.1\r\n"
            f"Host: {self.host}:{self.port}\r\nOrigin: http://{self.host}:{self.port}\r\n"
            f"Content-Type: application/json\r\nX-Rotor-Token: {self.token}\r\n"
            f"Content-Length: {len(body)}\r\n\r\n"
        ).encode()

    def command(self, rotator: str, **doc: Any) -> Answer:
        return self.post(f"/api/rotators/{rotator}/command", doc)


class EventStream:
    """``api/events``, read event by event."""

    def __init__(self, client: ConsoleClient, timeout_s: float = 10.0) -> None:
        self.conn = http.client.HTTPConnection(client.host, client.port, timeout=slow(timeout_s))
        self.conn.request("GET", "/api/events", headers={"X-Rotor-Token": client.token or ""})
        self.resp = self.conn.getresponse()
        assert self.resp.status == 200, self.resp.status

    def next(self) -> tuple[str, Any]:
        """The next event (name, data), comments skipped; TimeoutError if none comes."""
        name, data = "message", []
        while True:
            line = self.resp.readline()
            if not line:
                raise EOFError("the stream ended")
            text = line.decode().rstrip("\n")
            if not text:
                if data:
                    return name, json.loads("\n".join(data))
                continue
            if text.startswith(":"):
                continue
            field, _, value = text.partition(": ")
            if field == "event":
                name = value
            elif field == "data":
                data.append(value)

    def until(
        self, want: Callable[[str, Any], bool], timeout_s: float = 10.0, what: str = ""
    ) -> tuple[str, Any]:
        """The first event (name, data) ``want`` takes, within ``slow(timeout_s)``; the events
        before it are passed over (a status, or another error: a wait that took the first
        error of any kind failed on a line's junk reported meanwhile)."""
        deadline = time.monotonic() + slow(timeout_s)
        seen: list[str] = []
        while time.monotonic() < deadline:
            name, data = self.next()
            if want(name, data):
                return name, data
            seen.append(name if name == "status" else f"{name} {data}")
        raise AssertionError(f"no event {what or want} in {slow(timeout_s):g} s; saw {seen[-5:]}")

    def close(self) -> None:
        self.conn.close()


def run_async(coro: Coroutine[Any, Any, T]) -> T:
    """``asyncio.run(coro)`` on a thread of its own: a module that also drives a browser
    through Playwright's sync API has an event loop running on the test's thread."""
    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        return pool.submit(asyncio.run, coro).result()
