"""benchmarks/throughput.py: its docs block is rendered from its JSON, and its background load always ends."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "throughput.py"


@pytest.fixture(scope="module")
def throughput():  # benchmarks/ is not a package
    spec = importlib.util.spec_from_file_location("throughput", SCRIPT)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("block", ["throughput", "compare", "compare_quiet", "instructions"])
def test_each_docs_block_is_what_the_benchmarks_render_from_their_json(throughput, block: str) -> None:
    assert throughput.docs_block(block) == throughput.rendered_block(block)


def test_the_record_holds_the_loaded_run_and_the_goals(throughput) -> None:
    results = json.loads(throughput.JSON_PATH.read_text())
    assert "loaded" in results and results["load_processes"] >= 2
    assert "\n".join(throughput.goals(results)).count("issue 23") == 5


def test_the_background_load_runs_in_its_block_and_ends_with_it(throughput) -> None:
    with throughput.background_load(2, 60.0) as busy:
        assert len(busy) == 2 and all(process.poll() is None for process in busy)
    assert all(process.poll() is not None for process in busy)
    with pytest.raises(RuntimeError), throughput.background_load(1, 60.0) as busy:
        raise RuntimeError("a failed measurement")
    assert busy[0].poll() is not None
