"""The generated blocks of the README and the docs: which entry of the suite produces each, from which JSON, in
which schema, and the check that each block is what its JSON renders.

A block sits between ``<!-- generated: NAME by PRODUCER (python -m benchmarks run PRODUCER --docs) -->`` and
``<!-- /generated -->`` (the convention of :mod:`train.reporting.doc_tables`); a benchmark module declares the blocks
it produces in ``BLOCKS``, each a :class:`Block`. ::

    python -m benchmarks render            # every block anew from the JSON already written (seconds)
    python -m benchmarks render --check    # exit 1, naming each block that has no producer or differs
"""

from __future__ import annotations

import functools
import json
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from train.reporting import doc_tables

ROOT = Path(__file__).resolve().parents[2]
Types = type | tuple[type, ...]
NUMBER: tuple[type, ...] = (int, float)
OPTIONAL_NUMBER: tuple[type, ...] = (int, float, type(None))


@dataclass(frozen=True)
class Schema:
    """What a producer's JSON holds: the keys (and their types) of its object, or of every row when it is a list
    (``rows=True``). Keys the JSON has beyond these are allowed: a schema names what the renderer reads."""

    keys: dict[str, Types] = field(default_factory=dict)
    rows: bool = False

    def problems(self, data: Any) -> list[str]:
        """What in ``data`` does not fit: a missing key, a key of another type, the wrong kind of document."""
        if self.rows != isinstance(data, list) or not isinstance(data, list | dict):
            return [f"expected a JSON {'list of rows' if self.rows else 'object'}, got {type(data).__name__}"]
        items = data if isinstance(data, list) else [data]
        if self.rows and not items:
            return ["expected at least one row"]
        found = []
        for index, item in enumerate(items):
            where = f"row {index}: " if self.rows else ""
            if not isinstance(item, dict):
                found.append(f"{where}expected an object, got {type(item).__name__}")
                continue
            for key, types in self.keys.items():
                if key not in item:
                    found.append(f"{where}{key!r} is missing")
                elif not isinstance(item[key], types) or (isinstance(item[key], bool) and bool not in _tuple(types)):
                    found.append(f"{where}{key!r} is {type(item[key]).__name__}, expected {_names(types)}")
        return found


#: What ``dwr-gym benchmark`` writes (its benchmark.json), which the RL recipes copy under docs/.
BENCHMARK = Schema({"budget": dict, "machine": str, "summary": dict, "references": dict, "best_seed": dict})


def _tuple(types: Types) -> tuple[type, ...]:
    return types if isinstance(types, tuple) else (types,)


def _names(types: Types) -> str:
    return " or ".join(t.__name__ for t in _tuple(types))


@dataclass(frozen=True)
class Block:
    """One generated block: its name in the Markdown, the JSON it is rendered from (relative to the repository),
    the function that makes its body from that JSON, and the schema of the JSON."""

    name: str
    json: str
    render: Callable[[Any], str]
    schema: Schema

    def data(self, root: Path = ROOT) -> Any:
        return json.loads((root / self.json).read_text())

    def body(self, root: Path = ROOT) -> str:
        return self.render(self.data(root))


def table(name: str, schema: Schema) -> Block:
    """A table of :data:`train.reporting.doc_tables.TABLES`, as a block: a newline, then the table."""
    path, make = doc_tables.TABLES[name]
    return Block(name, path, lambda data: "\n" + make(data), schema)


def fenced(name: str, path: str, lines: Callable[[Any], list[str]], schema: Schema) -> Block:
    """A block of plain-text lines (a report), fenced as code."""
    return Block(name, path, lambda data: "\n```\n" + "\n".join(lines(data)) + "\n```\n", schema)


def command(producer: str) -> str:
    """The command that runs ``producer`` and renders its blocks, as a block's marker names it."""
    return f"python -m benchmarks run {producer} --docs"


def marker(name: str, producer: str) -> str:
    """The line that opens block ``name`` of ``producer``."""
    return f"<!-- generated: {name} by {producer} ({command(producer)}) -->"


def producers() -> dict[str, tuple[str, Block]]:
    """Block name -> (the suite entry that produces it, the block), from every entry's ``BLOCKS``."""
    from benchmarks.registry import SUITE, load

    found: dict[str, tuple[str, Block]] = {}
    for entry in SUITE:
        for block in getattr(load(entry), "BLOCKS", ()):
            if block.name in found:
                raise ValueError(f"block {block.name!r} is declared by {found[block.name][0]} and {entry}")
            found[block.name] = (entry, block)
    return found


def render(only: Iterable[str] | None = None, root: Path = ROOT) -> list[Path]:
    """Every generated block (or those of the producers ``only``) anew from its JSON; the pages rewritten."""
    chosen = set(only) if only is not None else None
    bodies: dict[str, Callable[[], str]] = {
        name: functools.partial(block.body, root)
        for name, (producer, block) in producers().items()
        if (chosen is None or producer in chosen) and (root / block.json).is_file()
    }
    written = []
    for path in doc_tables.markdown_files(root):
        text = path.read_text()
        new = doc_tables.regenerate(text, bodies)
        if new != text:
            path.write_text(new)
            written.append(path)
    return written


def problems(root: Path = ROOT) -> list[str]:
    """Every generated block that has no producer, names the wrong one, whose JSON does not parse into its schema,
    or whose body is not what its JSON renders; as 'file: block: what'."""
    known = producers()
    found = []
    for path in doc_tables.markdown_files(root):
        text, page = path.read_text(), path.relative_to(root)
        well_formed = {m.start(): m for m in doc_tables.MARKER.finditer(text)}
        for opening in doc_tables.OPENING.finditer(text):
            match = well_formed.get(opening.start())
            if match is None:
                found.append(f"{page}: {opening.group(0)}: names no producer and command, or is never closed")
                continue
            found += [f"{page}: {match.group('name')}: {what}" for what in block_problems(match, known, root)]
    return found


def block_problems(match: Any, known: dict[str, tuple[str, Block]], root: Path) -> list[str]:
    """What is wrong with one well-formed block."""
    name, producer = match.group("name"), match.group("producer")
    if name not in known:
        return ["no entry of the suite declares this block"]
    owner, block = known[name]
    if producer != owner or match.group("command") != command(owner):
        return [f"names {producer!r} ({match.group('command')}), but {owner!r} produces it: {marker(name, owner)}"]
    try:
        data = block.data(root)
    except (OSError, ValueError) as error:
        return [f"{block.json} does not parse: {error}"]
    wrong = block.schema.problems(data)
    if wrong:
        return [f"{block.json} does not fit its schema: {'; '.join(wrong[:3])}"]
    if match.group("body") != block.render(data):
        return [f"differs from what {block.json} renders (a hand edit?): run python -m benchmarks render"]
    return []


def rendered(name: str, root: Path = ROOT) -> str:
    """The body of block ``name`` as its producer's JSON renders it."""
    return producers()[name][1].body(root)


def written(name: str, root: Path = ROOT) -> str:
    """The body of block ``name`` as the README or a docs page holds it (the first page that does)."""
    for path in doc_tables.markdown_files(root):
        for match in doc_tables.MARKER.finditer(path.read_text()):
            if match.group("name") == name:
                return match.group("body")
    raise KeyError(f"block {name!r} is in no page: expected one of {', '.join(producers())}")
