"""The docs: every Python snippet of the README and of the site runs as written, each in a fresh interpreter as a
user pastes it; every generated block names its producer and agrees with the JSON it is rendered from (a hand edit, a
block without a producer, a JSON off its schema all fail); the README reads in one sitting."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from benchmarks.core import docs
from train.reporting.doc_tables import markdown_files, regenerate, render

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


README_SNIPPETS = [code for code, why in snippets(ROOT / "README.md") if why is None]


@pytest.mark.parametrize("code", README_SNIPPETS)
def test_the_readmes_snippets_print_no_warning(code: str, tmp_path: Path) -> None:
    """What a newcomer runs first says nothing but its output: no Gymnasium "out of date" warning, no other."""
    result = run(code, tmp_path)
    assert result.returncode == 0 and "Warning" not in result.stderr, result.stderr[-2000:]


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


def test_every_generated_block_names_its_producer_and_is_what_its_json_renders() -> None:
    assert docs.problems() == [], "run: python -m benchmarks render (python -m benchmarks render --check says why)"


def test_a_table_that_disagrees_with_its_json_is_found() -> None:
    table = render("claims")
    opening = docs.marker("claims", "reproduce")
    text = f"{opening}\n{table.replace('holds', 'fails', 1)}<!-- /generated -->\n"
    assert regenerate(text) == f"{opening}\n{table}<!-- /generated -->\n" != text


def page_with(tmp_path: Path, block: str) -> Path:
    """A copy of the repository's docs JSON and one page holding ``block`` (a README must exist too)."""
    import shutil

    shutil.copytree(ROOT / "docs", tmp_path / "docs", ignore=shutil.ignore_patterns("*.md", "*.png", "*.gif", "*.csv"))
    (tmp_path / "README.md").write_text("# dwr-gym\n")
    (tmp_path / "docs" / "page.md").write_text(f"Some prose.\n\n{block}\nMore prose.\n")
    return tmp_path


@pytest.mark.parametrize(
    ("producer", "edit", "found"),
    [
        ("reproduce", lambda body: body.replace("holds", "fails", 1), "differs from what docs/reproduce/claims.json"),
        ("compare", lambda body: body, "but 'reproduce' produces it"),
        (None, lambda body: body, "names no producer"),
        ("legacy", lambda body: body, "names no producer"),
    ],
    ids=["hand edit", "wrong producer", "no producer", "a marker of before the convention"],
)
def test_a_block_edited_by_hand_or_without_its_producer_fails(tmp_path: Path, producer, edit, found: str) -> None:
    body = "\n" + render("claims")
    opening = {None: "<!-- generated: claims -->", "legacy": "<!-- table: claims -->"}.get(producer) or docs.marker(
        "claims", producer
    )
    problems = docs.problems(page_with(tmp_path, f"{opening}{edit(body)}<!-- /generated -->"))
    assert len(problems) == 1 and found in problems[0], problems


def test_a_json_off_its_schema_fails(tmp_path: Path) -> None:
    root = page_with(tmp_path, f"{docs.marker('claims', 'reproduce')}\n{render('claims')}<!-- /generated -->")
    assert docs.problems(root) == []
    path = root / "docs" / "reproduce" / "claims.json"
    data = json.loads(path.read_text())
    data["claims"] = {"renamed": data.pop("claims")}
    path.write_text(json.dumps(data))
    (problem,) = docs.problems(root)
    assert "does not fit its schema: 'claims' is dict, expected list" in problem


def test_the_readme_reads_in_one_sitting() -> None:
    assert len((ROOT / "README.md").read_text().splitlines()) <= 350
