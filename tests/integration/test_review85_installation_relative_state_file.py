"""Review 85: claim.py rule 5's ``installation`` hashes the machine id, the host name and the
state file's path as the configuration wrote it (app.py: ``os.fsdecode(settings.state_file)``),
not the absolute path the client id hashes (settings ``_installation``). Two installations on
one host, each run from its own directory with ``state_file = "state.json"`` (two systemd
units with their own ``WorkingDirectory``, two users with ``state_file = "~/rotor/state.json"``),
have different state files but one ``installation``: bridge B on ``rotor/tower`` reads bridge A's
``rotor/tower/info``, stamped with that installation, takes it for its own earlier run ("a stamp
of this installation never refuses it") and runs: one target on ``rotor/tower/target`` turns
A's tower and B's mast (attack 18's clash, back through the installation)."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from tests.support import Probe, slow, wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.process import ROOT, Spawn, bridge_env
from tests.support.rig import Rig


def spawn_in(directory: Path) -> Spawn:
    """A ``Spawn`` that starts the bridge with ``directory`` as its working directory (a
    systemd unit's ``WorkingDirectory``)."""

    def spawn(argv: list[str], log_path: Path) -> subprocess.Popen[bytes]:
        with open(log_path, "ab") as log:
            return subprocess.Popen(
                argv, stdout=log, stderr=subprocess.STDOUT, env=bridge_env(), cwd=str(directory)
            )

    assert ROOT != directory
    return spawn


def test_two_installations_with_a_relative_state_file_never_both_run_nested(
    tmp_path: Path, broker: Mosquitto, probe: Probe, monkeypatch: pytest.MonkeyPatch
) -> None:
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    with (
        Rig(tmp_path / "a", broker, probe) as a,
        Rig(tmp_path / "b", broker, probe, spawn=spawn_in(tmp_path / "b")) as b,
    ):
        # A: base topic rotor, rotators tower and yagi, run from /srv/a with state.json there
        monkeypatch.chdir(tmp_path / "a")
        a.sections = {"state_file": "state.json"}
        tower = a.add("tower", emu={"start_az_deg": 0, "jitter_deg": 0})
        a.add("yagi", emu={"start_az_deg": 0, "jitter_deg": 0})
        first = a.start()
        a.ready("tower")
        a.ready("yagi")
        # B: base topic rotor/tower (A's tower's), run from /srv/b with its own state.json
        b.sections = {"state_file": "state.json"}
        b.base = "rotor/tower"
        mast = b.add("mast", emu={"start_az_deg": 200, "jitter_deg": 0})
        bridge = b.start_process()
        wait_until(
            lambda: (
                not bridge.alive()
                or any(m.text == "online" for m in probe.on("rotor/tower/bridge/state"))
            ),
            slow(30),
            "the bridge on rotor/tower to refuse (exit) or run",
        )
        probe.publish("rotor/tower/target", "90")
        tower.wait_for(lambda s: abs(s.az_deg - 90) <= 3 and not s.is_moving, slow(15))
        after = mast.state()
        assert (after.az_deg, after.is_moving) == (200, False), after
        assert not first.failed.is_set()
        assert bridge.proc is not None
        assert bridge.proc.wait(slow(15)) == 2, bridge.log()[-1500:]  # refused, naming A
