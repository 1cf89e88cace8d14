"""MkDocs hooks: pages whose text comes from the code, so that the docs and the code cannot disagree.

- ``<!-- env-docstring -->``: the docstring of :class:`dwr_gym.env.DWRPointStabilizationEnv` (Gymnasium's env
  page format: Description, Action Space, Observation Space, Rewards, Starting State, Episode End, Arguments,
  Version History), turned from its reStructuredText roles into Markdown;
- ``<!-- env-parameters -->``: every field of :class:`dwr_gym.params.EnvParams` with its v1 and v0 default,
  its unit and its docstring, read from dwr_gym/params.py;
- ``<!-- cli-help -->``: ``dwr-gym COMMAND --help`` of every command, from the parser itself.
"""

from __future__ import annotations

import ast
import contextlib
import inspect
import io
import os
import re
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]


def markdown_of(docstring: str) -> str:
    """A reStructuredText-flavoured docstring as Markdown: ``code`` and :role:`name` as code, doctests fenced."""
    text = inspect.cleandoc(docstring)
    text = re.sub(r":(?:class|func|mod|data|meth|attr):`~?([^`]+)`", r"`\1`", text)
    text = re.sub(r"``([^`]+)``", r"`\1`", text)
    lines, fenced = [], False
    for line in text.splitlines():
        doctest = line.startswith(">>>") or (fenced and line.strip() != "" and not line.startswith("##"))
        if doctest and not fenced:
            lines += ["```pycon"]
            fenced = True
        elif not doctest and fenced:
            lines += ["```", ""]
            fenced = False
        lines.append(line)
    if fenced:
        lines.append("```")
    return "\n".join(lines)


def env_docstring() -> str:
    """The env page: the class docstring, its first line as the lead, every section a level-2 heading."""
    from dwr_gym.env import DWRPointStabilizationEnv

    return markdown_of(DWRPointStabilizationEnv.__doc__ or "")


def env_parameters() -> str:
    """| keyword | v1 | v0 | unit | meaning | for every field of EnvParams, from the source of dwr_gym/params.py."""
    from dwr_gym import V1_DEFAULTS

    source = (ROOT / "dwr_gym" / "params.py").read_text()
    lines = source.splitlines()
    tree = ast.parse(source)
    cls = next(node for node in tree.body if isinstance(node, ast.ClassDef) and node.name == "EnvParams")
    rows = ["| keyword | v1 default | v0 default | unit | meaning |", "|---|---|---|---|---|"]
    body = cls.body
    for i, node in enumerate(body):
        if not (isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name) and node.value is not None):
            continue
        name = node.target.id
        default = ast.get_source_segment(source, node.value) or ""
        unit = re.search(r"#\s*\[(.+?)\]", lines[node.lineno - 1])
        doc = body[i + 1] if i + 1 < len(body) else None
        meaning = doc.value.value if isinstance(doc, ast.Expr) and isinstance(doc.value, ast.Constant) else ""
        v1 = repr(V1_DEFAULTS[name]) if name in V1_DEFAULTS else default
        meaning = " ".join(markdown_of(str(meaning)).split()).replace("|", "\\|")
        rows.append(f"| `{name}` | `{v1}` | `{default}` | {unit.group(1) if unit else ''} | {meaning} |")
    return "\n".join(rows)


def cli_help() -> str:
    """``dwr-gym --help`` and each command's, as the parser prints them (100 columns)."""
    os.environ["COLUMNS"] = "100"
    from train.cli import build_parser

    parser = build_parser()
    commands = parser._subparsers._group_actions[0].choices  # type: ignore[union-attr]
    parts = ["```text\n$ dwr-gym --help\n" + parser.format_help().rstrip() + "\n```"]
    for name, sub in commands.items():
        with contextlib.redirect_stdout(io.StringIO()):
            text = sub.format_help().rstrip()
        parts.append(f"### `dwr-gym {name}`\n\n```text\n$ dwr-gym {name} --help\n{text}\n```")
    return "\n\n".join(parts)


GENERATED = {"<!-- env-docstring -->": env_docstring, "<!-- env-parameters -->": env_parameters,
             "<!-- cli-help -->": cli_help}  # fmt: skip


ROLE = re.compile(r":(?:class|func|mod|data|meth|attr|exc):(?=<code>)")


def on_page_content(html: str, **kwargs: Any) -> str:
    """Drop the reStructuredText roles that the API reference's docstrings keep (':class:' before the code)."""
    return ROLE.sub("", html)


def on_page_markdown(markdown: str, **kwargs: Any) -> str:
    """Replace each marker of :data:`GENERATED` by what its function makes from the code."""
    for marker, make in GENERATED.items():
        if marker in markdown:
            markdown = markdown.replace(marker, make())
    return markdown
