"""``dwr-gym benchmark --ray``: the agent x seed grid as Ray tasks on a local Ray, the same runs as local processes
train, continued where an interrupted grid stopped."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from train.cli import main

TINY_PPO = "tiny:algo=ppo,num_envs=4,hyperparams={n_steps: 32, batch_size: 64}"
BUDGET = ["--env-steps", "128", "--eval-freq", "128", "--eval-episodes", "4", "--disturbed-episodes", "2",
          "--optimum-episodes", "2", "--references", "--seeds", "2"]  # fmt: skip


def without_times(result: dict) -> dict:
    return {k: v for k, v in result.items() if k not in ("seconds", "curve", "config")} | {
        "curve": [{k: v for k, v in row.items() if k != "wall_time"} for row in result["curve"]]
    }


@pytest.mark.slow
def test_a_tiny_grid_on_local_ray_trains_what_processes_train_and_continues_where_it_stopped(tmp_path: Path) -> None:
    """Two seeds of a tiny PPO as Ray tasks, then as local processes, the same results; a result removed is the
    only run trained again. Marked slow (a local Ray start-up and four tiny trainings: about a minute on 2 shared
    cores); .ci/run runs it as its second step, `pytest -m slow`."""
    pytest.importorskip("ray")
    on_ray, local = tmp_path / "ray", tmp_path / "local"
    assert main(["benchmark", "--agents", TINY_PPO, *BUDGET, "--ray", "--out", str(on_ray)]) == 0
    assert main(["benchmark", "--agents", TINY_PPO, *BUDGET, "--out", str(local)]) == 0
    for seed in (0, 1):
        ray_result = json.loads((on_ray / "results" / f"tiny-seed{seed}.json").read_text())
        local_result = json.loads((local / "results" / f"tiny-seed{seed}.json").read_text())
        assert without_times(ray_result) == without_times(local_result)
    kept = on_ray / "results" / "tiny-seed0.json"
    stamp = kept.stat().st_mtime_ns
    (on_ray / "results" / "tiny-seed1.json").unlink()  # seed 1 cut off after training, before its evaluation
    assert main(["benchmark", "--agents", TINY_PPO, *BUDGET, "--ray", "--out", str(on_ray)]) == 0
    assert kept.stat().st_mtime_ns == stamp and (on_ray / "results" / "tiny-seed1.json").is_file()
    summary = json.loads((on_ray / "benchmark.json").read_text())["summary"]
    assert list(summary) == ["tiny"] and summary["tiny"]["seeds"] == [0, 1]


def test_bad_ray_resources_are_one_line_before_any_work(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "b"
    assert main(["benchmark", "--agents", "ppo", "--ray", "--resources-per-run", "cpu=-1", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "--resources-per-run 'cpu=-1' is invalid" in err and len(err.splitlines()) == 1
    assert not (out / "runs").exists()
