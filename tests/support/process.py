"""The bridge as a user runs it: ``python -m bridge ...`` as its own process, configured by a TOML
file, in an environment without the caller's ROTOR_BRIDGE_* settings. The one ``BridgeProcess``
of the tests, the fault suite, the soak and the benchmarks (which start it through their Scope)."""

from __future__ import annotations

import contextlib
import io
import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from tests.support.waiting import slow

ROOT = Path(__file__).resolve().parents[2]


def bridge_env(extra: dict[str, str] | None = None) -> dict[str, str]:
    """This environment, less any ROTOR_BRIDGE_* setting (in any case: the bridge reads them so),
    with this checkout first on the import path; then ``extra``."""
    env = {k: v for k, v in os.environ.items() if not k.upper().startswith("ROTOR_BRIDGE_")}
    env["PYTHONPATH"] = str(ROOT) + (os.pathsep + env["PYTHONPATH"] if "PYTHONPATH" in env else "")
    env.update(extra or {})
    return env


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int | float):
        return repr(v)
    if isinstance(v, str | Path):
        return json.dumps(str(v))  # a JSON string is a valid TOML basic string
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"no TOML for {v!r}")


def to_toml(doc: dict[str, Any]) -> str:
    """Enough TOML for the bridge's configuration: scalars, tables, arrays of tables."""
    lines: list[str] = []

    def table(prefix: str, d: dict[str, Any]) -> None:
        subs = []
        for k, v in d.items():
            if isinstance(v, dict):
                subs.append((k, v))
            elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
                subs.append((k, v))
            else:
                lines.append(f"{k} = {_toml_value(v)}")
        for k, v in subs:
            name = f"{prefix}.{k}" if prefix else k
            if isinstance(v, dict):
                lines.append(f"\n[{name}]")
                table(name, v)
            else:
                for item in v:
                    lines.append(f"\n[[{name}]]")
                    table(name, item)

    table("", doc)
    return "\n".join(lines) + "\n"


def run_cli(
    *args: str, timeout_s: float = 30, env: dict[str, str] | None = None
) -> subprocess.CompletedProcess[str]:
    """``rotor-bridge ARGS`` to its end: exit code, stdout and stderr (text)."""
    return subprocess.run(
        [sys.executable, "-m", "bridge", *args],
        capture_output=True,
        text=True,
        env=bridge_env(env),
        cwd=str(ROOT),
        timeout=slow(timeout_s),
    )


def cli(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    """``rotor-bridge ARGS`` run in this process, reported as ``run_cli`` reports it: for the
    commands that start nothing and only print (``check-config``), where a process of their
    own cost 0.3-0.6 CPU-s each and proved no more. The environment is ``bridge_env``'s while it
    runs. What only a process shows (the exit code a shell sees, no traceback, signals, ``run``)
    stays ``run_cli``'s."""
    from bridge.cli import main

    out, err = io.StringIO(), io.StringIO()
    saved = dict(os.environ)
    os.environ.clear()
    os.environ.update(bridge_env(env))
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = main(list(args))
            except SystemExit as exc:
                code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
                if isinstance(exc.code, str):
                    print(exc.code, file=sys.stderr)
    finally:
        os.environ.clear()
        os.environ.update(saved)
    return subprocess.CompletedProcess(
        ["rotor-bridge", *args], code, out.getvalue(), err.getvalue()
    )


def bridge_config(
    tmp: Path,
    broker_port: int,
    rotators: list[dict[str, Any]],
    *,
    client_id: str,
    base_topic: str = "rotor",
    mqtt: dict[str, Any] | None = None,
    sections: dict[str, Any] | None = None,
    state_name: str = "state.json",
) -> dict[str, Any]:
    """A configuration (as the TOML file's tables) for a bridge on a loopback broker."""
    return {
        "state_file": tmp / state_name,
        "mqtt": {
            "host": "127.0.0.1",
            "port": broker_port,
            "base_topic": base_topic,
            "client_id": client_id,
            **(mqtt or {}),
        },
        **(sections or {}),
        "rotators": rotators,
    }


#: starts ``argv`` with its output in the file at the path given; returns the process
Spawn = Callable[[list[str], Path], "subprocess.Popen[bytes]"]


def _spawn(argv: list[str], log_path: Path) -> subprocess.Popen[bytes]:
    with open(log_path, "ab") as log:
        return subprocess.Popen(
            argv, stdout=log, stderr=subprocess.STDOUT, env=bridge_env(), cwd=str(ROOT)
        )


def fd_limited(soft: int, hard: int) -> Spawn:
    """A ``Spawn`` that starts the bridge with its open-files limit set (``ulimit -n``)."""
    import resource

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_NOFILE, (soft, hard))

    def spawn(argv: list[str], log_path: Path) -> subprocess.Popen[bytes]:
        with open(log_path, "ab") as log:
            return subprocess.Popen(
                argv,
                stdout=log,
                stderr=subprocess.STDOUT,
                env=bridge_env(),
                cwd=str(ROOT),
                preexec_fn=limit,  # noqa: PLW1509
            )

    return spawn


class BridgeProcess:
    """``python -m bridge run -c FILE``: the real service process, its log kept in a file.

    ``config`` is written to ``tmp/<name>.toml``, or is the path of a file already written;
    ``log_level`` None starts it without ``--log-level`` (the file's or the default level).
    ``spawn`` starts the process (the benchmarks' Scope, which always ends it); ``error`` is what
    ``check`` raises when the process has ended.
    """

    def __init__(
        self,
        tmp: Path,
        config: dict[str, Any] | Path,
        *,
        log_level: str | None = "DEBUG",
        log_path: Path | None = None,
        name: str = "bridge",
        spawn: Spawn = _spawn,
        error: type[Exception] = AssertionError,
    ) -> None:
        self.tmp = tmp
        if isinstance(config, Path):
            self.config_path = config
        else:
            self.config_path = tmp / f"{name}.toml"
            self.config_path.write_text(to_toml(config))
        self.log_path = log_path or tmp / f"{name}.log"
        self.log_level = log_level
        self.spawn = spawn
        self.error = error
        self.proc: subprocess.Popen[bytes] | None = None
        self.started_t = 0.0  # time.monotonic() when it was started

    def start(self) -> BridgeProcess:
        level = [] if self.log_level is None else ["--log-level", self.log_level]
        argv = [sys.executable, "-m", "bridge", *level, "run", "-c", str(self.config_path)]
        self.started_t = time.monotonic()
        self.proc = self.spawn(argv, self.log_path)
        return self

    @property
    def pid(self) -> int:
        assert self.proc is not None
        return self.proc.pid

    def alive(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    def check(self) -> None:
        """Raise ``error`` (with the end of the log) if the process has ended."""
        if not self.alive():
            status = None if self.proc is None else self.proc.returncode
            raise self.error(f"the bridge exited with status {status}\n{self.log()[-1500:]}")

    def log(self) -> str:
        return self.log_path.read_text(errors="replace") if self.log_path.exists() else ""

    def terminate(self, timeout_s: float = 10.0) -> int:
        assert self.proc is not None
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
        return self.proc.wait(slow(timeout_s))

    def kill(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(slow(10))

    def rss_kib(self) -> int:
        assert self.proc is not None
        for line in Path(f"/proc/{self.proc.pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
        raise AssertionError("no VmRSS")
