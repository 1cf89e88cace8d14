"""APG's open-loop teacher (train/learning/jitted/apg_teacher.py): its options refused in one line, the policy it
clones does better than the initial one, its env steps count in the budget and the schedule, and a run taught then
interrupted resumes bit for bit without being taught again."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.jitted_runs import assert_resume_is_bit_for_bit, cli
from train.learning.config import ConfigError
from train.learning.jitted.apg_settings import APGSettings

pytest.importorskip("jax")
import jax
import jax.numpy as jnp


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"teacher_episodes": -1}, r"^teacher_episodes=-1 is invalid: expected an integer in \[0, 65536\]$"),
        ({"teacher_iterations": 0}, r"^teacher_iterations=0 is invalid: expected an integer in \[1, 1e\+06\]$"),
        ({"teacher_learning_rate": 0}, r"^teacher_learning_rate=0(\.0)? is invalid"),
        ({"clone_steps": 0}, r"^clone_steps=0 is invalid: expected an integer in \[1, 1e\+07\]$"),
        ({"teacher_episodes": "many"}, r"^teacher_episodes='many' is invalid"),
    ],
)
def test_bad_teacher_options_are_refused_in_one_line(overrides: dict[str, Any], message: str) -> None:
    with pytest.raises(ConfigError, match=message) as error:
        APGSettings.from_algo_kwargs(overrides)
    assert "\n" not in str(error.value)


def small_apg(total_timesteps: float = 0.0, **settings: Any) -> Any:
    from dwr_gym.jax_env import make_gymnax_env
    from train.learning.jitted.apg import JaxAPG

    env, params = make_gymnax_env("DWRPointStabilization-v2", T_con_range=[2.0, 2.2])
    fields = {"episodes": 4, "net_arch": (16,), "validation_episodes": 16, **settings}
    return JaxAPG(APGSettings(**fields), env, params, total_timesteps=total_timesteps)


def mean_return(apg: Any, params: Any, state: Any) -> float:
    keys = jax.random.split(jax.random.PRNGKey(99), 16)  # fresh episodes, none of the teacher's
    returns, _ = jax.vmap(apg.episode, in_axes=(None, None, 0))(params, state.obs_stats, keys)
    return float(jnp.mean(returns))


def test_the_cloned_policy_does_better_than_the_initial_one_and_no_update_is_counted() -> None:
    from train.learning.jitted.apg_teacher import clone_from_teacher

    apg = small_apg(teacher_episodes=16, teacher_iterations=60, clone_steps=2000)
    state = apg.init(0)
    taught, measures = clone_from_teacher(apg, state)
    # 2 s to go 0.3-3 m at 0.5 m/s: the teacher drives towards the goal, the initial policy barely moves
    assert mean_return(apg, taught.params, taught) > mean_return(apg, state.params, state) + 1.0
    assert measures["teacher_return"] > mean_return(apg, state.params, state)
    assert 0.0 <= measures["teacher_in_time"] <= 1.0 and np.isfinite(measures["clone_loss"])
    assert measures["steps"] == pytest.approx(16 * 61 * 41, rel=0.05)  # 40-44 steps an episode, 61 plays of each
    assert int(taught.updates) == 0  # the updates, the schedule and keep_best start after it
    for a, b in zip(jax.tree.leaves(taught.best_params), jax.tree.leaves(taught.params), strict=True):
        assert np.array_equal(np.asarray(a), np.asarray(b))
    assert int(jax.tree.leaves(taught.opt_state)[0]) == 0  # Adam's count: a fresh state for the cloned weights


def test_the_teachers_steps_come_out_of_the_schedules_budget() -> None:
    from train.learning.jitted.apg_teacher import teacher_steps

    plain = small_apg(total_timesteps=4 * 42 * 10, learning_rate=0.01, linear_schedule=True)
    taught = small_apg(learning_rate=0.01, linear_schedule=True, teacher_episodes=8, teacher_iterations=9,
                       total_timesteps=4 * 42 * 10 + 8 * 42 * 10)  # fmt: skip
    assert plain.decay_updates == 10
    assert taught.decay_updates == 10  # what the teacher spends (8 episodes, 10 plays) is not the updates'
    assert teacher_steps(taught.settings, 42.0) == 8 * 42 * 10


TAUGHT = ("train", "--algo", "apg", "--backend", "jax", "--env", "DWRPointStabilization-v2", "--eval-episodes", "3",
          "--no-progress", "--env-kwargs", "T_con_range=[10,11]", "--hyperparams", "episodes=2",
          "learning_rate=0.0003", "policy_kwargs=dict(net_arch=[16])", "keep_best=2", "validation_episodes=2",
          "teacher_episodes=2", "teacher_iterations=3", "clone_steps=20")  # fmt: skip


@pytest.mark.slow
def test_a_taught_run_resumes_bit_for_bit_without_a_second_lesson(tmp_path: Path) -> None:
    """Taught (about 1,700 env steps) then stopped at 3,000 and resumed to 6,000, it ends as the run of 6,000 does:
    the resumed run is not taught again (its updates are past 0)."""
    import yaml

    split = assert_resume_is_bit_for_bit(TAUGHT, 6000, 2000, tmp_path)
    saved = yaml.safe_load((split / "config.yaml").read_text())
    assert saved["learned_from"] == "reward"
    assert saved["config"]["algo_kwargs"]["teacher_episodes"] == 2


def test_the_cli_says_it_is_taught_and_counts_the_lesson(tmp_path: Path) -> None:
    from train.learning.runs import read_state

    done = cli(*TAUGHT, "--total-timesteps", "1000", "--eval-freq", "1000", "--run-dir", str(tmp_path / "run"))
    assert done.returncode == 0, done.stderr
    said = done.stdout + done.stderr
    assert "first cloned from the best sequences of 2 episodes (3 Adam steps each)" in said
    assert "open-loop teacher: " in said and "of its 2 sequences in time" in said and "nan" not in said
    assert read_state(tmp_path / "run")["timesteps"] >= 2 * 200 * 4  # the lesson's plays, at least 200 steps each
