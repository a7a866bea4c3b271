"""Loaded by every Python started with this directory on PYTHONPATH: only a bridge
(``python -m bridge``) started with STOP_TRACE set is traced (benchmarks/stop_trace.py)."""

import os
import sys

if os.environ.get("STOP_TRACE") and sys.orig_argv[1:3] == ["-m", "bridge"]:
    from benchmarks.stop_trace import install

    install(os.environ["STOP_TRACE"])
