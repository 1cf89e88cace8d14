"""The learners' registry (train/learning/learners.py): every entry trains through one contract, and what reads the
registry (the configuration, the help, the hyperparameters, the agent loader) accepts exactly its entries."""

from __future__ import annotations

import importlib
import inspect
import sys

import pytest

from train.env_ids import TASK_ENV_ID
from train.learning.config import ConfigError, TrainConfig
from train.learning.learners import ALGORITHMS, BACKENDS, KINDS, LEARNERS, find_learner


@pytest.mark.parametrize("learner", LEARNERS, ids=lambda learner: f"{learner.algo}-{learner.backend}")
def test_every_learner_has_a_trainer_with_the_one_signature_and_defaults_for_the_task(learner) -> None:
    assert learner.kind in KINDS and find_learner(learner.algo, learner.backend) is learner
    trainer = importlib.import_module(learner.trainer).train
    assert list(inspect.signature(trainer).parameters) == ["config", "command", "on_evaluation"]
    if learner.hyperparams is not None:
        assert callable(learner.function(learner.hyperparams))
    from train.learning.hyperparams import default_budget

    envs, steps = default_budget(learner.algo, False, TASK_ENV_ID)  # its YAML has a section for the task
    assert envs >= 1 and steps >= 1


def test_each_algorithm_on_each_backend_is_one_entry_and_the_help_lists_them() -> None:
    pairs = [(learner.algo, learner.backend) for learner in LEARNERS]
    assert len(pairs) == len(set(pairs))
    import dataclasses

    fields = {f.name: f.metadata["help"] for f in dataclasses.fields(TrainConfig)}
    assert all(algo in fields["algo"] for algo in ALGORITHMS)
    assert all(backend in fields["backend"] for backend in BACKENDS)


@pytest.mark.parametrize(
    ("options", "message"),
    [({"algo": "es"}, r"^--algo 'es' is invalid with --backend sb3: sb3 trains ppo, .*; es trains with --backend jax$"),
     ({"algo": "sac", "backend": "jax"}, r"^--algo 'sac' is invalid with --backend jax: .*sac trains with --backend sb3 or sbx$"),
     ({"algo": "sac", "backend": "sbx", "residual": True},
      r"^--residual is invalid with --backend sbx --algo sac: it is implemented by --backend sb3 \(ppo, .*\) or --backend jax \(ppo, es, apg\)$"),
     ({"algo": "ppo", "backend": "jax", "init_from": "."}, r"^--init-from is invalid with --backend jax --algo ppo: .*--backend sb3"),
     ({"algo": "a2c"}, r"^--algo 'a2c' is invalid: expected one of 'ppo'")],
)  # fmt: skip
def test_what_no_learner_trains_is_refused_in_one_line(options: dict, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        TrainConfig(**options).validate()


def test_a_learner_whose_library_is_missing_is_refused_naming_its_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    from train.learning.hyperparams import algorithm_class

    monkeypatch.setitem(sys.modules, "sb3_contrib", None)  # import sb3_contrib raises ImportError
    with pytest.raises(ImportError, match=r'^--backend sb3 --algo tqc needs sb3_contrib, .*"dwr-gym\[train\]"$'):
        find_learner("tqc", "sb3").check_installed()
    with pytest.raises(ConfigError, match=r'needs sb3_contrib, .*"dwr-gym\[train\]"$'):
        algorithm_class("tqc")
    find_learner("ppo", "sb3").check_installed()
    assert algorithm_class("es", "jax").__name__ == "PPO"  # the ES's evolved actor is saved as an SB3 PPO
