"""``python -m benchmarks list | run NAME [ARGS] [--docs] | render [--check]``: the suite's one entry point."""

from __future__ import annotations

import argparse
import sys

from benchmarks import registry


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m benchmarks", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    listing = sub.add_parser("list", help="every benchmark, one line each: name, group, what it measures")
    listing.add_argument("--group", help="only this group (speed, training, learning, robustness, quality, ...)")
    run = sub.add_parser("run", help="run one benchmark; ARGS go to it (python -m benchmarks run NAME --help)")
    run.add_argument("name", help="the benchmark (python -m benchmarks list)")
    run.add_argument(
        "args", nargs=argparse.REMAINDER, help="its arguments; --docs: write its JSON and render its blocks"
    )
    render = sub.add_parser("render", help="render every generated block of the README and docs from its JSON")
    render.add_argument("--check", action="store_true", help="change nothing; exit 1 naming each block that fails")
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    if args.command == "list":
        names = [n for n in registry.SUITE if args.group in (None, registry.group(n))]
        if not names:
            raise SystemExit(f"--group {args.group!r} is unknown: expected one of "
                             f"{', '.join(dict.fromkeys(map(registry.group, registry.SUITE)))}")  # fmt: skip
        width = max(map(len, names))
        for name in names:
            print(f"{name:<{width}}  {registry.group(name):<10}  {registry.summary(name)}")
        return 0
    if args.command == "render":
        from benchmarks.core import docs

        if args.check:
            found = docs.problems()
            for problem in found:
                print(problem, file=sys.stderr)
            return 1 if found else 0
        for path in docs.render():
            print(f"rendered the blocks of {path.relative_to(docs.ROOT)}")
        return 0
    code = registry.load(args.name).main(args.args) or 0  # (before the docs' imports: some set threads first)
    if code == 0 and "--docs" in args.args:
        from benchmarks.core import docs

        for path in docs.render([args.name]):
            print(f"rendered the blocks of {path.relative_to(docs.ROOT)}")
    return int(code)


if __name__ == "__main__":
    sys.exit(main())
