"""The throughput entry of the suite (benchmarks/speed/): its docs blocks are rendered from their JSON, and its
background load always ends."""

from __future__ import annotations

import json

import pytest

from benchmarks.core import docs
from benchmarks.core.timing import background_load
from benchmarks.speed import throughput
from train.reporting.throughput_tables import goals


@pytest.mark.parametrize("block", ["throughput", "compare-commits-loaded", "compare-commits-quiet", "instructions"])
def test_each_docs_block_is_what_the_benchmarks_render_from_their_json(block: str) -> None:
    assert docs.written(block) == docs.rendered(block)


def test_the_record_holds_the_loaded_run_and_the_goals() -> None:
    results = json.loads(throughput.JSON_PATH.read_text())
    assert "loaded" in results and results["load_processes"] >= 2
    assert "\n".join(goals(results)).count("the busy-machine goal") == 5


def test_the_background_load_runs_in_its_block_and_ends_with_it() -> None:
    with background_load(2, 60.0) as busy:
        assert len(busy) == 2 and all(process.poll() is None for process in busy)
    assert all(process.poll() is not None for process in busy)
    with pytest.raises(RuntimeError), background_load(1, 60.0) as busy:
        raise RuntimeError("a failed measurement")
    assert busy[0].poll() is not None
