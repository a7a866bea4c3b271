"""Item: the operator console (bridge/interfaces/web/): how soon a status change reaches a page,
what open pages cost the bridge, and what the page weighs.

One bridge process (`python -m bridge run -c FILE`, `[web]` on, a station for the map) on four
emulated Rotor-EZ controllers at their real speed (6 deg/s) in the emulator host, behind paced
lines, with a private mosquitto; the rotors are kept turning by targets sent through the
console's own command API, between two bearings 350 deg apart.

Rules:
1. Latency = when a client had the status minus its ``t`` (the bridge's wall clock when the
   engine handed it over): in Chromium the page's own record (window.rotorConsole.latencies_ms,
   taken once the page has updated itself), at a plain api/events client its arrival. Both
   clocks are the machine's wall clock; the page's (timeOrigin + now) is checked against its
   Date.now(). The first status per rotator after a page connects is the newest one, not a
   change, and is not counted.
2. CPU is the bridge process's own (procfs: schedstat of all its threads) over fixed windows;
   the conditions take turns in rotated order, each a difference against its repetition's
   no-page window, new pages 3 s after they opened (they start up on 2 cores for a second).
   Chromium's CPU and the machine's load (2 shared cores) are read over the same windows; "a
   busy core" (a spinning process, no page) shows what load does to the bridge's own figure.
3. Every rotor turns from the start to the end of every window (checked against the emulators);
   a rotor near the end of its sweep is turned back before a window, never in one.
4. Each page gets a browser context of its own: Chromium allows one profile 6 connections per
   host and every page holds one for its stream (a 7th page in one profile does not load).
5. The page's weight is what Chromium fetched to show it (the event stream aside), fetched
   again with and without ``Accept-Encoding: gzip``.
"""

from __future__ import annotations

import http.client
import os
import socket
import subprocess
import threading
import time
from contextlib import suppress
from functools import partial
from pathlib import Path
from statistics import mean
from typing import Any
from urllib.parse import urlsplit

from benchmarks import harness
from benchmarks.harness import BenchError, Mqtt, Scope, start_bridge, start_broker, wait_until
from benchmarks.procfs import cpu_seconds, rss_bytes
from benchmarks.report import ItemResult, Table, Verdict, percentile
from benchmarks.rig import EmuHost
from tests.support.console import ConsoleClient, EventStream, web_section

MODEL = "rotorez"
ROTATORS = 4
PAGES = 10
ENDS_DEG = (5.0, 355.0)
SPEED_DEG_S = 6.0  # the Rotor-EZ emulator's default, a real Ham-IV's
CHROMIUM = "/usr/bin/chromium"
SHOWS_ALL = f"(window.rotorConsole?.latencies_ms.length ?? 0) >= {ROTATORS}"
CLOCK = "performance.timeOrigin + performance.now() - Date.now()"  # the page's vs the wall's
GOAL_P99_MS = 100.0
GOAL_CPU_PCT = 2.0
GOAL_WEIGHT_B = 300_000
CONDITIONS = ("no page", "10 Chromium pages", "10 plain streams", "no page, a busy core")
NONE, PAGES_10, STREAMS_10, BUSY = CONDITIONS
LABELS = {"chromium_1": "Chromium, 1 page", "stream_1": "plain stream, 1"}
LABELS |= {"chromium_10": "Chromium, 10 pages", "stream_10": "plain streams, 10"}


def _stats(values_s: list[float]) -> dict[str, Any]:
    v = [round(x * 1000.0, 2) for x in values_s]
    out = {"n": len(v), "p50_ms": percentile(v, 50), "p99_ms": percentile(v, 99), "max_ms": max(v)}
    return out | ({"samples_ms": v} if len(v) <= 1000 else {})  # the 1-client runs: a few hundred


# -- the clients --------------------------------------------------------------------------------
class Stream:
    """A plain api/events client reading on a thread of its own (rule 1)."""

    def __init__(self, client: ConsoleClient) -> None:
        self.events = EventStream(client, timeout_s=60)
        self.sock: socket.socket | None = self.events.conn.sock
        self.latencies_s: list[float] = []
        self._seen: set[str] = set()
        self._thread = threading.Thread(target=self._run, daemon=True, name="sse-reader")
        self._thread.start()

    def _run(self) -> None:
        with suppress(EOFError, OSError, ValueError):
            while True:
                name, data = self.events.next()
                if name == "status" and data["rotator"] in self._seen:
                    self.latencies_s.append(time.time() - data["t"])
                self._seen.add(data.get("rotator"))

    def take(self) -> list[float]:
        taken, self.latencies_s = self.latencies_s, []
        return taken

    def close(self) -> None:
        if self.sock is not None:  # the reader sees the end, then the connection is closed
            with suppress(OSError):
                self.sock.shutdown(socket.SHUT_RDWR)
        self._thread.join(5)
        self.events.close()


class Browser:
    """Headless Debian Chromium through playwright: console pages, their latencies, its CPU."""

    def __init__(self, scope: Scope, url: str) -> None:
        try:
            from playwright.sync_api import sync_playwright
        except ImportError as exc:
            raise BenchError("playwright is not installed (pip install -e .[test])") from exc
        if not Path(CHROMIUM).exists():
            raise BenchError(f"{CHROMIUM} is missing (Debian: sudo apt-get install chromium)")
        self.url = url
        self._pw = sync_playwright().start()
        scope.callback(self._pw.stop)
        self.browser = self._pw.chromium.launch(executable_path=CHROMIUM, headless=True)
        scope.callback(self.browser.close)
        self.pages: list[Any] = []
        self.fetched: list[str] = []  # what the first page loaded (rule 5)
        self.clock_offsets_ms: list[float] = []

    def open(self, count: int) -> None:
        for _ in range(count):
            page = self.browser.new_context().new_page()  # rule 4
            if not self.fetched:
                page.on("request", self._record)
            page.goto(self.url)
            self.pages.append(page)
        for page in self.pages:  # connected: every rotator's newest status has come
            wait_until(partial(page.evaluate, SHOWS_ALL), 20, "a page to show every rotator")
        self.take()  # rule 1

    def _record(self, request: Any) -> None:
        if request.method == "GET":
            self.fetched.append(request.url)

    def take(self) -> list[float]:
        out: list[float] = []
        for page in self.pages:
            out += [ms / 1000 for ms in page.evaluate("rotorConsole.latencies_ms.splice(0)")]
        return out

    def close_pages(self) -> None:
        for page in self.pages:
            self.clock_offsets_ms.append(page.evaluate(CLOCK))
            page.context.close()
        self.pages = []

    def cpu_s(self) -> dict[int, float]:
        """CPU seconds of every Chromium process under this one."""
        out: dict[int, float] = {}
        for pid in _descendants(os.getpid()):
            with suppress(OSError, ValueError):
                if "chrom" in Path(f"/proc/{pid}/comm").read_text():
                    out[pid] = cpu_seconds(pid)
        return out


def _descendants(root: int) -> list[int]:
    parent: dict[int, int] = {}
    for entry in os.listdir("/proc"):
        with suppress(OSError, ValueError, IndexError):
            stat = Path(f"/proc/{entry}/stat").read_text()
            parent[int(entry)] = int(stat.rsplit(")", 1)[1].split()[1])
    found, todo = [], [root]
    while todo:
        pid = todo.pop()
        kids = [p for p, pp in parent.items() if pp == pid]
        found += kids
        todo += kids
    return found


def _machine_busy_s() -> float:
    """Busy CPU seconds of the whole machine, all cores (/proc/stat)."""
    fields = [int(x) for x in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:9]]
    return (sum(fields) - fields[3] - fields[4]) / os.sysconf("SC_CLK_TCK")


# -- the rotors ---------------------------------------------------------------------------------
class Turner:
    """Keeps every rotor turning from one end of its sweep to the other (rule 3)."""

    def __init__(self, host: EmuHost, client: ConsoleClient, ids: list[str]) -> None:
        self.host, self.client, self.ids = host, client, ids
        self.goal: dict[str, float] = {}

    def ensure(self, need_s: float) -> None:
        """Every rotor turning, with at least ``need_s`` of its sweep ahead."""
        flipped: dict[int, float] = {}
        for i, (az, moving) in enumerate(self.host.states()):
            goal = self.goal.get(self.ids[i])
            if goal is None or not moving or abs(goal - az) < need_s * SPEED_DEG_S + 10.0:
                goal = max(ENDS_DEG, key=lambda end: abs(end - az))
                answer = self.client.command(self.ids[i], command="target", az=goal)
                if answer.status != 200:
                    raise BenchError(f"target {goal} to {self.ids[i]}: {answer.doc}")
                self.goal[self.ids[i]] = goal
                flipped[i] = abs(goal - az)

        def toward() -> bool:  # a reversal waits out the Rotor-EZ's 5 s brake delay
            now = self.host.states()
            return all(
                now[i][1] and abs(self.goal[self.ids[i]] - now[i][0]) < left - 2.0
                for i, left in flipped.items()
            )

        if flipped:
            wait_until(toward, 30, "the rotors to turn toward their new targets", 0.1)

    def check(self, what: str) -> None:
        if not all(moving for _, moving in self.host.states()):
            raise BenchError(f"a rotor stopped during {what}")


# -- the measurements ---------------------------------------------------------------------------
def _window(bridge_pid: int, browser: Browser, window_s: float) -> dict[str, float]:
    """Rule 2: the bridge's CPU and RSS, Chromium's CPU and the machine's load over one window."""
    b0, c0, m0, t0 = cpu_seconds(bridge_pid), browser.cpu_s(), _machine_busy_s(), time.monotonic()
    time.sleep(window_s)
    b1, c1, m1, t1 = cpu_seconds(bridge_pid), browser.cpu_s(), _machine_busy_s(), time.monotonic()
    chromium = sum(v - c0.get(pid, 0.0) for pid, v in c1.items())
    return {
        "cpu_pct": 100.0 * (b1 - b0) / (t1 - t0),
        "rss_mib": rss_bytes(bridge_pid) / 2**20,
        "chromium_cpu_pct": 100.0 * chromium / (t1 - t0),
        "machine_busy_cores": (m1 - m0) / (t1 - t0),
        "window_s": t1 - t0,
    }


def _weight(port: int, token: str, urls: list[str]) -> list[dict[str, Any]]:
    """Rule 5: each GET the page made (the stream aside), as served with and without gzip."""
    rows = []
    for url in dict.fromkeys(urls):
        path = urlsplit(url).path or "/"
        if path.endswith("/api/events") or urlsplit(url).port != port:
            continue
        sizes = {}
        for enc in ("gzip", "identity"):
            conn = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
            try:
                conn.request("GET", path, headers={"X-Rotor-Token": token, "Accept-Encoding": enc})
                resp = conn.getresponse()
                body = resp.read()
                if resp.status != 200:
                    raise BenchError(f"GET {path}: {resp.status}")
                sizes[enc] = (len(body), resp.getheader("Content-Encoding") or "-")
            finally:
                conn.close()
        (served, encoding), plain = sizes["gzip"], sizes["identity"][0]
        rows.append({"path": path, "served_b": served, "encoding": encoding, "plain_b": plain})
    return rows


def run(scope: Scope, quick: bool) -> ItemResult:
    latency_s, window_s, reps = (8.0, 4.0, 2) if quick else (15.0, 6.0, 3)
    result = ItemResult("console", "Operator console: status to page, CPU with pages, weight")
    data: dict[str, Any] = {"window_s": window_s, "repetitions": reps}
    port = start_broker(scope)
    host = EmuHost(scope, MODEL, ROTATORS)
    ids = [f"r{i}" for i in range(ROTATORS)]
    mqtt = Mqtt(port, ["rotor/+/status", "rotor/+/availability", "rotor/+/state"])
    scope.callback(mqtt.close)
    rotators = [{"id": rid, "model": MODEL, "port": str(host.link(i))} for i, rid in enumerate(ids)]
    sections = {"web": (web := web_section()), "station": {"locator": "JO62qm"}}
    bridge = start_bridge(scope, port, rotators, sections=sections)
    mqtt.wait_all([f"rotor/{rid}/availability" for rid in ids], "online", 60)
    mqtt.wait_all([f"rotor/{rid}/state" for rid in ids], "idle", 60)  # past the start-up brake
    client = ConsoleClient(web["port"])
    client.session()
    browser = Browser(scope, f"http://127.0.0.1:{web['port']}/")
    turner = Turner(host, client, ids)

    # 1. status change -> page update: one page, one plain stream
    turner.ensure(latency_s + 5.0)
    browser.open(1)
    stream = Stream(client)
    time.sleep(1.0)
    stream.take(), browser.take()  # what came before the run
    mark, t0, busy0 = mqtt.mark(), time.monotonic(), _machine_busy_s()
    time.sleep(latency_s)
    lat = {"chromium_1": browser.take(), "stream_1": stream.take()}
    elapsed = time.monotonic() - t0
    data["latency_machine_busy_cores"] = (_machine_busy_s() - busy0) / elapsed
    turner.check("the latency run")
    stream.close()
    browser.close_pages()
    published = [m for m in mqtt.messages[mark:] if m.topic.endswith("/status")]
    data["status_per_s_per_rotor"] = len(published) / ROTATORS / elapsed
    data["stream_status_per_s_per_rotor"] = len(lat["stream_1"]) / ROTATORS / elapsed

    # 2. CPU and memory, the conditions in rotated order (rule 2)
    windows: dict[str, list[dict[str, float]]] = {c: [] for c in CONDITIONS}
    lat["chromium_10"], lat["stream_10"] = [], []
    for rep in range(reps):
        for cond in CONDITIONS[rep:] + CONDITIONS[:rep]:
            harness.check_abort()
            streams: list[Stream] = []
            busy: subprocess.Popen[bytes] | None = None
            if cond == PAGES_10:
                browser.open(PAGES)
            elif cond == STREAMS_10:
                streams = [Stream(client) for _ in range(PAGES)]
            elif cond == BUSY:
                busy = scope.spawn([harness.PYTHON, "-c", "while True: pass"], log_name="busy.log")
            turner.ensure(window_s + 5.0)  # after the pages, which take seconds to open
            time.sleep(3.0 if cond == PAGES_10 else 1.0)  # 10 new pages settle in about 2 s
            browser.take()
            for s in streams:
                s.take()
            windows[cond].append(_window(bridge.pid, browser, window_s))
            turner.check(f"a window ({cond})")
            lat["chromium_10"] += browser.take()
            for s in streams:
                lat["stream_10"] += s.take()
                s.close()
            browser.close_pages()
            if busy is not None:
                harness.stop_process(busy)
    bridge.check()
    data["windows"] = windows
    data["weight"] = _weight(web["port"], client.token or "", browser.fetched)  # 3.
    data["clock_offset_ms"] = max(abs(x) for x in browser.clock_offsets_ms)
    if not all(lat.values()):
        raise BenchError(f"no status reached {[k for k, v in lat.items() if not v]}")
    data["latency"] = {key: _stats(values) for key, values in lat.items()}
    return _report(result, data)


def _report(result: ItemResult, data: dict[str, Any]) -> ItemResult:
    lat = Table(
        "Status change -> page update, 4 Rotor-EZ turning",
        ["client", "n", "p50 ms", "p99 ms", "max ms", "p99 / goal"],
    )
    for key, label in LABELS.items():
        s = data["latency"][key]
        lat.add(label, s["n"], s["p50_ms"], s["p99_ms"], s["max_ms"], s["p99_ms"] / GOAL_P99_MS)
    lat.notes += [
        f"the bridge's status rate: {data['status_per_s_per_rotor']:.2f} R/status per second per "
        f"turning rotor (MQTT); {data['stream_status_per_s_per_rotor']:.2f} status events per "
        "second per rotor at a plain stream.",
        "latency = the client's wall clock when it had the status - t (the bridge's wall clock "
        "when the engine handed it over); Chromium: the page's own record, once it updated "
        f"itself; the pages' clocks within {data['clock_offset_ms']:.2f} ms of the wall clock; "
        f"machine busy {data['latency_machine_busy_cores']:.2f} cores over the 1-page run.",
    ]
    cpu = Table(
        f"Bridge CPU (% of one core) and RSS over {data['window_s']:g} s windows x "
        f"{data['repetitions']}, 4 rotors turning",
        ["condition", "CPU %", "min-max", "RSS MiB", "Chromium CPU %", "machine busy cores"],
    )
    windows = data["windows"]
    for cond, ws in windows.items():
        avg = {k: mean(w[k] for w in ws) for k in ws[0]}
        span = f"{min(w['cpu_pct'] for w in ws):.2f}-{max(w['cpu_pct'] for w in ws):.2f}"
        busy = f"{avg['machine_busy_cores']:.2f}"
        cpu.add(cond, f"{avg['cpu_pct']:.2f}", span, avg["rss_mib"], avg["chromium_cpu_pct"], busy)
    more: dict[str, Any] = {}
    for cond in CONDITIONS[1:]:
        pairs = list(zip(windows[cond], windows[NONE], strict=True))
        d_cpu = [w["cpu_pct"] - b["cpu_pct"] for w, b in pairs]
        d_rss = [w["rss_mib"] - b["rss_mib"] for w, b in pairs]
        more[cond] = {"cpu_pct": d_cpu, "rss_mib": d_rss}
        span = f"{min(d_cpu):+.2f}..{max(d_cpu):+.2f}"
        cpu.add(f"{cond} - no page", f"{mean(d_cpu):+.2f}", span, f"{mean(d_rss):+.1f}", "", "")
    data["more_than_no_page"] = more
    cpu.notes.append(
        "differences paired within each repetition, conditions in rotated order; machine busy = "
        "every process on the 2 shared cores; a busy core = a spinning process beside the bridge."
    )
    weight = Table(
        "Page weight: what Chromium fetched, the stream aside",
        ["path", "as served B", "encoding", "uncompressed B"],
    )
    for r in data["weight"]:
        weight.add(r["path"], r["served_b"], r["encoding"], r["plain_b"])
    served, plain = (sum(r[k] for r in data["weight"]) for k in ("served_b", "plain_b"))
    weight.add("total", served, "", plain)
    data["weight_total"] = {"served_b": served, "plain_b": plain}
    result.tables += [lat, cpu, weight]
    result.data = data
    result.verdicts += _verdicts(data, served, plain)
    return result


def _verdicts(data: dict[str, Any], served: int, plain: int) -> list[Verdict]:
    p99 = {k: v["p99_ms"] for k, v in data["latency"].items()}
    out = [
        Verdict(
            f"status change -> Chromium page update p99 <= {GOAL_P99_MS:.0f} ms, {n} page(s) open",
            f"{p99[f'chromium_{n}']:.1f} ms = {p99[f'chromium_{n}'] / GOAL_P99_MS:.2f} of the "
            f"goal (plain streams: {p99[f'stream_{n}']:.1f} ms)",
            p99[f"chromium_{n}"] <= GOAL_P99_MS,
        )
        for n in (1, 10)
    ]
    for cond in (STREAMS_10, PAGES_10):
        d = data["more_than_no_page"][cond]
        out.append(
            Verdict(
                f"{cond}: <= {GOAL_CPU_PCT:g} % of one core more than no page",
                f"{mean(d['cpu_pct']):+.2f} % ({min(d['cpu_pct']):+.2f}..{max(d['cpu_pct']):+.2f})"
                f" = {mean(d['cpu_pct']) / GOAL_CPU_PCT:.2f} of the goal, RSS "
                f"{mean(d['rss_mib']):+.1f} MiB",
                max(d["cpu_pct"]) <= GOAL_CPU_PCT,
            )
        )
    out.append(
        Verdict(
            f"the page with its map data <= {GOAL_WEIGHT_B // 1000} kB as served",
            f"{served / 1000:.1f} kB ({served / GOAL_WEIGHT_B:.2f} of the goal), "
            f"{plain / 1000:.1f} kB uncompressed",
            served <= GOAL_WEIGHT_B,
        )
    )
    return out
