"""Every ```python block of README.md runs as written, in order, in one interpreter started in
the repository's root (the blocks build on each other, as a reader's session does)."""

from __future__ import annotations

import re
import subprocess
import sys

from conftest import ROOT


def python_blocks() -> list[str]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    return re.findall(r"^```python\n(.*?)^```", text, flags=re.S | re.M)


def test_readme_has_python_blocks() -> None:
    assert len(python_blocks()) >= 3


def test_readme_python_blocks_run() -> None:
    code = "\n".join(python_blocks())
    p = subprocess.run(
        [sys.executable, "-W", "error", "-c", code],
        capture_output=True, text=True, timeout=900, cwd=ROOT,
    )
    assert p.returncode == 0, p.stderr[-4000:]
