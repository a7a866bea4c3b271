"""Loaded by every Python started with this directory on PYTHONPATH: a bridge (``python -m
bridge``) started with BENCH_WITHOUT set runs without the part it names, for exchange_cpu's
``--without`` (benchmarks/without.py): what that part of a reading costs is this tree's CPU
less the CPU without it, in the same run."""

import os
import sys

if os.environ.get("BENCH_WITHOUT") and sys.orig_argv[1:3] == ["-m", "bridge"]:
    from benchmarks.without import install

    install(os.environ["BENCH_WITHOUT"])
