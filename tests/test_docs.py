"""The docs: every Python snippet of the README and of the site runs as written, each in a fresh interpreter as a
user pastes it; every results table agrees with the JSON it is generated from; the README reads in one sitting."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from train.reporting.doc_tables import markdown_files, regenerate, render, stale

ROOT = Path(__file__).resolve().parents[1]
BLOCK = re.compile(r"(<!-- snippet: not run \((?P<why>.+?)\) -->\n)?```python\n(?P<code>.*?)```", re.DOTALL)


def snippets(path: Path) -> list[tuple[str, str | None]]:
    """(code, why it is not run or None) of every ```python block of a page."""
    return [(m.group("code"), m.group("why")) for m in BLOCK.finditer(path.read_text())]


PAGES = markdown_files(ROOT)
SNIPPETS = [pytest.param(code, id=f"{path.relative_to(ROOT)}:{i}") for path in PAGES
            for i, (code, why) in enumerate(snippets(path)) if why is None]  # fmt: skip


def run(code: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy", "MPLBACKEND": "Agg"}
    return subprocess.run([sys.executable, "-c", code], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=300)  # fmt: skip


@pytest.mark.parametrize("code", SNIPPETS)
def test_snippet_runs(code: str, tmp_path: Path) -> None:
    result = run(code, tmp_path)
    assert result.returncode == 0, result.stderr[-2000:]
    for folder in ("gym", "sb3"):  # the snippets that record videos write one
        if f'"videos/{folder}"' in code:
            assert len(list((tmp_path / "videos" / folder).glob("*.mp4"))) == 1, folder
    if "episodic_return=" in code:  # CleanRL's loop prints the returns of the episodes that ended
        assert "episodic_return=" in result.stdout


def test_the_page_for_other_libraries_has_a_snippet_for_gymnasium_sb3_and_cleanrl() -> None:
    text = (ROOT / "docs" / "vector-and-interop.md").read_text()
    section = text[text.index("## Using dwr-gym with other libraries") :]
    gymnasium, sb3, cleanrl = [m.group("code") for m in BLOCK.finditer(section)]
    assert '"videos/gym"' in gymnasium and "gym.wrappers.vector" in gymnasium
    assert '"videos/sb3"' in sb3 and "stable_baselines3" in sb3
    assert "dwr_gym:DWRPointStabilization-v1" in cleanrl and "\nimport dwr_gym" not in cleanrl


def test_every_snippet_that_is_not_run_says_why() -> None:
    skipped = [(path.name, why) for path in PAGES for _, why in snippets(path) if why is not None]
    assert all(why.strip() for _, why in skipped) and len(skipped) <= 2, skipped


def test_every_table_agrees_with_its_json() -> None:
    assert stale() == [], "run: python -m train.reporting.doc_tables"


def test_a_table_that_disagrees_with_its_json_is_found() -> None:
    table = render("claims")
    text = f"<!-- table: claims -->\n{table.replace('holds', 'fails', 1)}<!-- /table -->\n"
    assert regenerate(text) == f"<!-- table: claims -->\n{table}<!-- /table -->\n" != text


def test_the_readme_reads_in_one_sitting() -> None:
    assert len((ROOT / "README.md").read_text().splitlines()) <= 350
