"""Hamlib's rotctl as the tests' judge: the one place its command line is built.

Rules:
1. Every rotctl a test runs goes through ``rotctl_argv`` (or ``run_rotctl``), so every deadline
   of it scales with waiting.slow (waiting.py rule 1): the run as a whole (coreutils
   ``timeout`` at slow(RUN_S), the subprocess at slow(RUN_S + 5)) and Hamlib's own read
   timeout, the one that failed on a busy machine (``read_block_generic(): Timed out 0.400417
   seconds after 0 chars``). That one is the backend's own (400 ms for a SPID or a GS-232, 2 s
   for ``-m 2``), as Hamlib itself reports it (``rotctl -L``), times the factor, handed back
   with ``--set-conf=timeout=MS``: on a quiet machine Hamlib judges the emulators' and the
   bridge's timing by its own numbers, on a busy one it waits as long as the machine needs.
2. Hamlib's retry count stays the backend's own: a retry sends the command again, so more of
   them could hide a reply that was lost rather than late.
3. The backend's timeout is asked once per model and process (a rotctl that opens nothing);
   a model whose timeout cannot be read is a failed test, never a guess.
"""

from __future__ import annotations

import functools
import subprocess

from tests.support.waiting import slow

RUN_S = 20.0  # a whole rotctl run on a quiet machine, at most


@functools.cache
def hamlib_timeout_ms(rotctl_path: str, model: str) -> int:
    """The backend's own read timeout (rule 3), from ``rotctl -L``'s ``timeout`` entry, which
    it prints before it tries to open the (here impossible) device."""
    argv = [rotctl_path, "-m", model, "-r", "/nonexistent/rotor", "-L"]
    done = subprocess.run(
        argv, stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=slow(10)
    )
    lines = iter(done.stdout.splitlines())
    for line in lines:
        if line.startswith("timeout:"):
            for value in lines:
                if "Value:" in value:
                    return int(float(value.rsplit("Value:", 1)[1]))
    raise AssertionError(f"no timeout in `{' '.join(argv)}`: {done.stdout[-400:]!r}")


def rotctl_argv(rotctl_path: str, model: int | str, where: int | str, *args: str) -> list[str]:
    """``rotctl -m MODEL -r WHERE ARGS`` with every deadline scaled (rule 1); ``where`` is a
    device path, or a TCP port on 127.0.0.1 as a number."""
    model = str(model)
    device = f"127.0.0.1:{where}" if isinstance(where, int) else where
    argv = ["timeout", f"{slow(RUN_S):g}", rotctl_path, "-m", model, "-r", device]
    own_ms = hamlib_timeout_ms(rotctl_path, model)
    if own_ms > 0:
        argv.append(f"--set-conf=timeout={round(slow(own_ms))}")
    return [*argv, *args]


def run_rotctl(
    rotctl_path: str, model: int | str, where: int | str, *args: str
) -> subprocess.CompletedProcess[str]:
    """``rotctl_argv`` run to its end; the caller judges its status and output."""
    argv = rotctl_argv(rotctl_path, model, where, *args)
    return subprocess.run(
        argv, capture_output=True, text=True, timeout=slow(RUN_S + 5), check=False
    )
