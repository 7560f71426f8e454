"""The hand-written stub of the native module matches the built module."""

from __future__ import annotations

import subprocess
import sys


def test_stubtest_accepts_the_stub() -> None:
    o = subprocess.run(
        [sys.executable, "-m", "mypy.stubtest", "leeway._leeway"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert o.returncode == 0, o.stdout + o.stderr
