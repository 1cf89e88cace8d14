"""``--threads``: our commands run torch on 1 thread (or N) and give the caller its own count back."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from train.cli import main
from train.learning.config import TrainConfig
from train.learning.hyperparams import resolve_hyperparams
from train.learning.training import train
from train.threads import torch_threads

torch = pytest.importorskip("torch")


@pytest.fixture
def caller_threads() -> Iterator[int]:
    """The caller's session at 3 torch threads, put back as it was after the test."""
    before = torch.get_num_threads()
    torch.set_num_threads(3)
    yield 3
    torch.set_num_threads(before)


def test_scope_sets_the_count_and_restores_the_callers_also_after_an_error(caller_threads: int) -> None:
    with torch_threads() as count:
        assert count == 1 and torch.get_num_threads() == 1
    assert torch.get_num_threads() == caller_threads
    with pytest.raises(KeyboardInterrupt), torch_threads(2):
        assert torch.get_num_threads() == 2
        raise KeyboardInterrupt
    assert torch.get_num_threads() == caller_threads


def test_train_runs_on_one_thread_and_gives_the_session_its_count_back(tmp_path: Path, caller_threads: int) -> None:
    config = TrainConfig(total_timesteps=128, num_envs=4, eval_freq=10**6, eval_episodes=4,
                         run_dir=str(tmp_path / "run"), progress=False)  # fmt: skip
    resolve_hyperparams(config, set())
    config.algo_kwargs.update(n_steps=32, batch_size=64)
    during: list[int] = []
    train(config, command=["test"], on_evaluation=lambda row: during.append(torch.get_num_threads()))
    assert during and set(during) == {1}  # more would wait on torch's pool on a busy machine
    assert torch.get_num_threads() == caller_threads


@pytest.mark.parametrize("command", ["evaluate", "compare", "robustness", "sweep"])
def test_a_bad_thread_count_is_one_line_naming_the_flag(command: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main([command, "--threads", "0", "--out", "unused-never-created"]) == 2
    error = capsys.readouterr().err
    assert "--threads 0 is invalid" in error and len(error.strip().splitlines()) == 1
    assert not Path("unused-never-created").exists()


@pytest.mark.parametrize("threads", [0, -1, 1025, True, 2.0, "2"])
def test_a_thread_count_that_is_not_an_integer_in_range_is_refused(threads: object) -> None:
    from train.threads import MAX_THREADS, check_threads

    with pytest.raises(ValueError, match=r"^--threads .* is invalid: expected an integer in \[1, 1024\]$"):
        check_threads(threads)  # type: ignore[arg-type]
    assert check_threads(None) == 1 and check_threads(1) == 1 and check_threads(MAX_THREADS) == MAX_THREADS
