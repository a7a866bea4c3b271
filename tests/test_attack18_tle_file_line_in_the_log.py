"""Attack 18: the warning about a TLE file's bad entries quotes the first one whole: a file
that is one long line (a compressed download named instead of the text, a binary, /dev/zero)
puts megabytes into one log line, at every change of the file (up to the 4 MiB read, four
times that escaped: 16 MB from /dev/zero). Every other quotation of what a file or a sender
wrote is cut short (the state file's malformed entry at 80 characters)."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from bridge.sky.catalog import TleCatalog

QUOTED_MAX = 1000  # characters: far more than any TLE line (69) or satellite name


def test_a_tle_file_of_one_long_line_is_no_megabyte_log_line(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    path = tmp_path / "active.txt"
    path.write_bytes(b"\x1f\x8b" + b"x" * (1 << 20))  # a gzip's start, then one long line
    with caplog.at_level(logging.WARNING, logger="bridge.sky.catalog"):
        assert TleCatalog(path).names() == []
    said = [r.getMessage() for r in caplog.records]
    assert said, "the bad entry was not said"
    assert max(len(line) for line in said) < QUOTED_MAX, [len(line) for line in said]
