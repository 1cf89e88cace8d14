"""``dwr-gym benchmark --ray``: the agent x seed grid as Ray tasks on a local Ray, the same runs as local processes
train, continued where a grid stopped."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from train.cli import main

TINY_PPO = "tiny:algo=ppo,num_envs=4,hyperparams={n_steps: 32, batch_size: 64}"
BUDGET = ["--env-steps", "128", "--eval-freq", "128", "--eval-episodes", "4", "--disturbed-episodes", "2",
          "--optimum-episodes", "2", "--references"]  # fmt: skip


def without_times(result: dict) -> dict:
    return {k: v for k, v in result.items() if k not in ("seconds", "curve", "config")} | {
        "curve": [{k: v for k, v in row.items() if k != "wall_time"} for row in result["curve"]]
    }


@pytest.mark.slow
@pytest.mark.own_process
def test_a_tiny_grid_on_local_ray_trains_what_processes_train_and_continues_where_it_stopped(tmp_path: Path) -> None:
    """A tiny PPO as a Ray task and as a local process: the same result; then the grid of two seeds on Ray runs
    only the seed it lacks. Marked slow (a local Ray started twice and three tiny trainings, each evaluated: minutes
    on 2 shared cores); .ci/run runs it as its second step, `pytest -m slow`."""
    pytest.importorskip("ray")
    on_ray, local = tmp_path / "ray", tmp_path / "local"
    assert main(["benchmark", "--agents", TINY_PPO, *BUDGET, "--seeds", "1", "--ray", "--out", str(on_ray)]) == 0
    assert main(["benchmark", "--agents", TINY_PPO, *BUDGET, "--seeds", "1", "--out", str(local)]) == 0
    done = on_ray / "results" / "tiny-seed0.json"
    assert without_times(json.loads(done.read_text())) == without_times(
        json.loads((local / "results" / "tiny-seed0.json").read_text())
    )
    stamp = done.stat().st_mtime_ns
    assert main(["benchmark", "--agents", TINY_PPO, *BUDGET, "--seeds", "2", "--ray", "--out", str(on_ray)]) == 0
    assert done.stat().st_mtime_ns == stamp and (on_ray / "results" / "tiny-seed1.json").is_file()
    summary = json.loads((on_ray / "benchmark.json").read_text())["summary"]
    assert list(summary) == ["tiny"] and summary["tiny"]["seeds"] == [0, 1]


def test_bad_ray_resources_are_one_line_before_any_work(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "b"
    assert main(["benchmark", "--agents", "ppo", "--ray", "--resources-per-run", "cpu=-1", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "--resources-per-run 'cpu=-1' is invalid" in err and len(err.splitlines()) == 1
    assert not (out / "runs").exists()
