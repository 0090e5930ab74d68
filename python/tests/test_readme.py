"""The README's Python quick start, copy-pasted: every ```python block of that section runs
from the repository root as a new user would run it."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def quick_start_blocks() -> list[str]:
    text = (ROOT / "README.md").read_text()
    start = text.index("## Python quick start")
    end = text.find("\n## ", start + 1)
    section = text[start : end if end != -1 else len(text)]
    return re.findall(r"```python\n(.*?)```", section, flags=re.S)


def test_the_quick_start_has_code():
    assert len(quick_start_blocks()) >= 2


@pytest.mark.parametrize("index", range(len(quick_start_blocks())))
def test_quick_start_block_runs(index: int):
    code = quick_start_blocks()[index]
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=False
    )
    assert done.returncode == 0, f"README block {index} failed:\n{code}\n{done.stderr}"
    assert done.stdout.strip(), "the block printed nothing"
