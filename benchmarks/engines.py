"""An older engine beside this one: a commit's ``bridge/`` taken out of git into a work directory
and run with its own import path, so that one run can set it beside the working tree's on the
same machine, under the same load, taking turns (a figure measured against a later baseline
cannot hide a regression since an older one).

Rules:
1. Only ``bridge/`` comes from the commit; the emulators, the rig and the measurement are this
   checkout's, so both engines meet the same controllers, lines and broker.
2. The old engine's process imports its own ``bridge`` first and alone (PYTHONPATH is its root,
   its working directory too); that the import resolves there is checked before it is used.
3. Every engine starts from bytecode, as an installed bridge does (``pip install`` compiles the
   package; the service then runs with PYTHONDONTWRITEBYTECODE=1 and reads those files): its
   ``bridge/`` is compiled into ``__pycache__`` before it is run (``compiled``). Without it, a
   machine that never writes bytecode (this one sets PYTHONDONTWRITEBYTECODE=1) compiles each
   engine's whole source at every start, and a start-up figure measures the size of the source
   rather than what a user's service does.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

from benchmarks.harness import PYTHON, REPO, Scope
from tests.support import bridge_env
from tests.support.process import Spawn


def engine_at(scope: Scope, commit: str) -> tuple[Path | None, str]:
    """``commit``'s ``bridge/`` in the scope's work directory (its root), or None and why not."""
    root = scope.workdir / f"engine-{commit}"
    root.mkdir(parents=True, exist_ok=True)
    try:
        archive = subprocess.run(
            ["git", "-C", str(REPO), "archive", commit, "bridge"],
            capture_output=True,
            timeout=60,
            check=True,
        )
        subprocess.run(["tar", "-x", "-C", str(root)], input=archive.stdout, check=True)
        where = subprocess.run(  # rule 2
            [PYTHON, "-c", "import bridge; print(bridge.__file__)"],
            capture_output=True,
            text=True,
            cwd=root,
            env=engine_env(root),
            timeout=60,
            check=True,
        ).stdout.strip()
        if not where.startswith(str(root)):
            return None, f"the old engine's bridge/ is not the one imported there ({where})"
        compiled(root)
    except FileNotFoundError as exc:
        return None, f"{exc.filename} is not installed"
    except subprocess.TimeoutExpired as exc:
        return None, f"{' '.join(map(str, exc.cmd))} took over {exc.timeout:g} s"
    except subprocess.CalledProcessError as exc:
        said = exc.stderr.decode(errors="replace") if isinstance(exc.stderr, bytes) else exc.stderr
        return None, f"{' '.join(map(str, exc.cmd))[:80]} failed: {(said or '').strip()[-300:]}"
    return root, ""


def compiled(root: Path) -> None:
    """``root``'s ``bridge/`` compiled to bytecode beside its source, as ``pip install`` leaves an
    installed one (rule 3); files already current are left as they are."""
    subprocess.run(
        [PYTHON, "-m", "compileall", "-q", str(root / "bridge")],
        capture_output=True,
        timeout=120,
        check=True,
    )


def engine_env(root: Path) -> dict[str, str]:
    env = bridge_env()
    env["PYTHONPATH"] = str(root)  # rule 2
    env.setdefault("PYTHONUNBUFFERED", "1")
    return env


def engine_spawner(scope: Scope, root: Path | None) -> Spawn:
    """How a Rig or BridgeProcess starts the bridge: this checkout's (None) or the one at root."""
    if root is None:
        return scope.spawner
    env = engine_env(root)

    def spawn(argv: list[str], log: Path) -> subprocess.Popen[bytes]:
        return scope.spawn(argv, log_name=str(log.relative_to(scope.workdir)), cwd=root, env=env)

    return spawn
