"""Review 154 (d490b077: benchmarks/procfs.py ``tree_cpu_seconds``, exchange_cpu's CPU of the
bridge with the processes it started): the tree is summed over the children alive at each
reading. A child that ends between two readings (the stop express killed as hung, or ended,
and started again RESTART_FIRST_S later) is in the first and not in the second: the CPU it
spent, before the window and in it, is taken off the window's, and the idle "% of one core"
comes out too low, below zero for a child that spent more than the window's share. Its CPU is
the parent's ``cutime``/``cstime`` once it is reaped (as Express reaps it: ``child.wait``),
which ``cpu_seconds`` does not read."""

from __future__ import annotations

import os
import subprocess
import sys

from benchmarks.procfs import tree_cpu_seconds

KID = (  # spends 0.3 s of CPU (its own clock: no wall time involved), says so, ends when told
    "import sys, time\n"
    "t = time.process_time()\n"
    "while time.process_time() - t < 0.3:\n"
    "    pass\n"
    "print('spent', flush=True)\n"
    "sys.stdin.readline()\n"
)
PARENT = (  # a bridge with one child: started, then ended and reaped between two readings
    "import subprocess, sys\n"
    f"kid = subprocess.Popen([sys.executable, '-c', {KID!r}], stdin=subprocess.PIPE,\n"
    "                       stdout=subprocess.PIPE, text=True)\n"
    "kid.stdout.readline()\n"
    "print('spent', flush=True)\n"
    "sys.stdin.readline()\n"
    "kid.stdin.close()\n"
    "kid.wait()\n"
    "print('reaped', flush=True)\n"
    "sys.stdin.readline()\n"
)


def test_the_cpu_of_a_process_tree_never_goes_back_when_a_child_ends() -> None:
    parent = subprocess.Popen(
        [sys.executable, "-c", PARENT], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
    )
    assert parent.stdin is not None and parent.stdout is not None
    try:
        assert parent.stdout.readline() == "spent\n"
        before = tree_cpu_seconds(parent.pid)
        assert before >= 0.3  # the child's 0.3 s counted while it lives
        parent.stdin.write("\n")
        parent.stdin.flush()
        assert parent.stdout.readline() == "reaped\n"
        after = tree_cpu_seconds(parent.pid)
        tick = 1 / os.sysconf("SC_CLK_TCK")  # (a reaped child is counted in ticks: its
        # cutime and cstime, where a live one's schedstat counts nanoseconds)
        assert after >= before - 2 * tick, (
            f"the tree's CPU went back from {before:.3f} to {after:.3f} s"
        )
    finally:
        parent.kill()
        parent.wait()
