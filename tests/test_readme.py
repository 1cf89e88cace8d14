"""The README's snippets for other libraries run as written, each in a fresh interpreter as a user pastes it."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"
SECTION = "## Using dwr-gym with other libraries"


def python_snippets(section: str) -> list[str]:
    """The ```python blocks of the README section titled ``section``."""
    text = README.read_text()
    start = text.index(section)
    end = text.find("\n## ", start + len(section))
    return re.findall(r"```python\n(.*?)```", text[start : end if end >= 0 else None], flags=re.DOTALL)


SNIPPETS = python_snippets(SECTION)


def test_the_section_has_a_snippet_for_gymnasium_sb3_and_cleanrl() -> None:
    assert len(SNIPPETS) == 3
    assert "gym.wrappers.vector" in SNIPPETS[0] and "stable_baselines3" in SNIPPETS[1]
    assert "dwr_gym:DWRPointStabilization-v1" in SNIPPETS[2] and "\nimport dwr_gym" not in SNIPPETS[2]


@pytest.mark.parametrize("index", range(len(SNIPPETS)), ids=["gymnasium", "sb3", "cleanrl"])
def test_readme_snippet_runs(index: int, tmp_path: Path) -> None:
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
    result = subprocess.run([sys.executable, "-c", SNIPPETS[index]], cwd=tmp_path, env=env, capture_output=True,
                            text=True, timeout=300)  # fmt: skip
    assert result.returncode == 0, result.stderr[-2000:]
    if index == 0:
        assert len(list((tmp_path / "videos" / "gym").glob("*.mp4"))) == 1
    if index == 1:
        assert len(list((tmp_path / "videos" / "sb3").glob("*.mp4"))) == 1
    if index == 2:
        assert "episodic_return=" in result.stdout
