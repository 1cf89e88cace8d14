"""Analytic policy gradients through the JAX env (``dwr-gym train --algo apg --backend jax``): options refused in one
line, the gradient it follows is the return's (finite differences agree), the state's gradient clipped on the way back
only, an exported agent that acts as the trained policy, and runs that resume bit for bit and load in ``dwr-gym
evaluate``."""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.jitted_runs import assert_resume_is_bit_for_bit, cli
from train.learning.config import ConfigError, TrainConfig
from train.learning.jitted.apg_settings import APGSettings


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"episodes": 0}, r"^episodes=0 is invalid: expected an integer in \[1, 65536\]$"),
        ({"learning_rate": 0}, r"^learning_rate=0(\.0)? is invalid"),
        ({"max_grad_norm": -1}, r"^max_grad_norm=-1(\.0)? is invalid"),
        ({"state_grad_clip": -0.5}, r"^state_grad_clip=-0.5 is invalid: expected a finite number in \[0, 1e\+09\]$"),
        ({"near_miss_clip": 0}, r"^near_miss_clip=0(\.0)? is invalid: expected a finite number in \(0, 1e\+09\]$"),
        (
            {"state_grad_clip": 0, "near_miss_clip": 16},
            r"^near_miss_clip=16 is invalid with state_grad_clip=0 \(no episode is clipped\)",
        ),
        ({"near_miss_distance": 0}, r"^near_miss_distance=0(\.0)? is invalid: expected a finite number in \(0, 100\]$"),
        ({"hold_steps": -1}, r"^hold_steps=-1 is invalid: expected an integer in \[0, 100000\]$"),
        ({"hold_weight": 0}, r"^hold_weight=0(\.0)? is invalid: expected a finite number in \(0, 1e\+06\]$"),
        (
            {"hold_heading_weight": -1},
            r"^hold_heading_weight=-1(\.0)? is invalid: expected a finite number in \[0, 1e\+06\]$",
        ),
        (
            {"hold_heading_weight": 5},
            r"^hold_heading_weight=5 is invalid with hold_steps=0 \(it acts over the last hold_steps before T_con\)",
        ),
        ({"keep_best": -1}, r"^keep_best=-1 is invalid: expected an integer in \[0, 1e\+06\]$"),
        ({"keep_best": 2.5}, r"^keep_best=2.5 is invalid"),
        ({"validation_episodes": 0}, r"^validation_episodes=0 is invalid: expected an integer in \[1, 65536\]$"),
        ({"weight_average": 1}, r"^weight_average=1(\.0)? is invalid: expected a finite number in \[0, 1\)$"),
        ({"weight_average": -0.1}, r"^weight_average=-0.1 is invalid: expected a finite number in \[0, 1\)$"),
        ({"learning_rate": "lin_x"}, r"^learning_rate='lin_x' is invalid: expected a number in \(0, 100\], or lin_"),
        ({"n_steps": 64}, r"^hyperparameter\(s\) \['n_steps'\] are not accepted by APG"),
        ({"policy_kwargs": {"log_std_init": -1}}, r"^policy_kwargs \['log_std_init'\] are not implemented by APG"),
    ],
)
def test_bad_options_are_refused_in_one_line(overrides: dict[str, Any], message: str) -> None:
    with pytest.raises(ConfigError, match=message) as error:
        APGSettings.from_algo_kwargs(overrides)
    assert "\n" not in str(error.value)


def resolved(**kwargs: Any) -> TrainConfig:
    from train.learning.hyperparams import resolve_hyperparams

    config = TrainConfig(algo="apg", backend="jax", **kwargs)
    config.validate()
    return resolve_hyperparams(config, set(kwargs))


def test_a_linear_schedule_decays_the_rate_to_zero_over_the_budget() -> None:
    from train.learning.jitted.apg_settings import check_apg_kwargs

    settings = APGSettings.from_algo_kwargs({"learning_rate": "lin_0.001"})
    assert (settings.learning_rate, settings.linear_schedule) == (0.001, True)
    assert check_apg_kwargs({"learning_rate": "lin_0.001"})["learning_rate"] == "lin_0.001"  # config.yaml keeps it
    assert check_apg_kwargs({"learning_rate": 0.001})["learning_rate"] == 0.001
    with pytest.raises(ConfigError, match=r"^learning_rate=.?lin_x.? is invalid"):
        APGSettings.from_algo_kwargs({"learning_rate": "lin_x"})


def test_the_yaml_is_read_and_apg_needs_the_jax_backend() -> None:
    config = resolved(env_id="DWRPointStabilization-v2", hyperparam_overrides={"episodes": 8})
    assert config.algo_kwargs["episodes"] == 8 and config.algo_kwargs["state_grad_clip"] == 4.0
    assert config.algo_kwargs["learning_rate"] == "lin_0.001" and config.algo_kwargs["keep_best"] == 20
    assert config.total_timesteps > 0
    with pytest.raises(
        ConfigError, match=r"^--algo 'apg' is invalid with --backend sb3: .*apg trains with --backend jax$"
    ):
        TrainConfig(algo="apg").validate()
    assert resolved(residual=True, expert="ptc").algo_kwargs["episodes"] == 64  # residual_apg.yml


jax = pytest.importorskip("jax")


def small_apg(state_grad_clip: float = 0.0, residual: bool = False) -> Any:
    from dwr_gym.jax_env import make_gymnax_env
    from train.learning.jitted.apg import JaxAPG

    env, params = make_gymnax_env("DWRPointStabilization-v2", T_con_range=[2.0, 2.2])
    settings = APGSettings(episodes=2, net_arch=(8,), state_grad_clip=state_grad_clip)
    return JaxAPG(settings, env, params, residual=residual)


def test_the_gradient_it_follows_is_the_returns() -> None:
    """jax.grad of an episode's return along a random direction of the weights equals the finite difference."""
    apg = small_apg()
    state = apg.init(0)
    key = jax.random.PRNGKey(3)
    params = jax.tree.map(lambda x: x * 20.0 if x.ndim == 2 else x, state.params)  # a policy that moves the robot

    def episode_return(p: Any) -> Any:
        return apg.episode(p, state.obs_stats, key)[0]

    direction = jax.tree.map(lambda x: jax.random.normal(jax.random.PRNGKey(x.size), x.shape), params)
    gradient = jax.grad(episode_return)(params)
    slope = sum(float(np.sum(np.asarray(g) * np.asarray(d)))
                for g, d in zip(jax.tree.leaves(gradient), jax.tree.leaves(direction), strict=True))  # fmt: skip
    eps = 1e-3
    plus = episode_return(jax.tree.map(lambda p, d: p + eps * d, params, direction))
    minus = episode_return(jax.tree.map(lambda p, d: p - eps * d, params, direction))
    difference = float(plus - minus) / (2 * eps)
    assert abs(slope) > 0.1 and slope == pytest.approx(difference, rel=0.05)


def test_the_states_gradient_is_clipped_on_the_way_back_only() -> None:
    import jax.numpy as jnp

    from train.learning.jitted.apg import clip_gradient

    x = {"a": jnp.array([3.0, 4.0]), "n": jnp.array(2, jnp.int32)}
    assert clip_gradient(x, 1.0)["a"].tolist() == [3.0, 4.0]
    gradient = jax.grad(lambda a: jnp.sum(clip_gradient({"a": a, "n": x["n"]}, 1.0)["a"] * jnp.array([30.0, 40.0])))
    np.testing.assert_allclose(gradient(x["a"]), [0.6, 0.8], rtol=1e-6)  # norm 50 clipped to 1, same direction
    small = jax.grad(lambda a: jnp.sum(clip_gradient(a, 1.0) * jnp.array([0.3, 0.4])))(x["a"])
    np.testing.assert_allclose(small, [0.3, 0.4], rtol=1e-6)  # within the limit: unchanged


def test_the_state_clip_is_each_episodes_whatever_the_batch() -> None:
    """An update's gradient is the mean of its episodes' gradients, each clipped (state_grad_clip) as it would be
    alone: the clip's effect does not change with ``episodes`` (the mean's own gradient would scale each episode's
    cotangent by 1/episodes, and the clip with it)."""
    import jax.numpy as jnp

    apg = small_apg(state_grad_clip=4.0)
    state = apg.init(0)
    state = state.replace(params=jax.tree.map(lambda x: x * 20.0 if x.ndim == 2 else x, state.params))
    _, key = jax.random.split(state.rng)  # the update's episodes
    keys = jax.random.split(key, apg.settings.episodes)
    alone = [jax.grad(lambda p, k=k: apg.episode(p, state.obs_stats, k)[0])(state.params) for k in keys]
    mean = jnp.concatenate([-(a + b).ravel() / 2 for a, b in zip(*map(jax.tree.leaves, alone), strict=True)])
    _, metrics = apg.update(state)
    assert float(metrics["grad_norm"]) == pytest.approx(float(jnp.linalg.norm(mean)), rel=1e-4)
    unclipped = small_apg(state_grad_clip=0.0).update(state)[1]  # (the clip is active here: the test can fail)
    assert float(unclipped["grad_norm"]) > 1.15 * float(metrics["grad_norm"])


def test_the_schedules_updates_are_what_the_budget_buys() -> None:
    from dwr_gym.jax_env import make_gymnax_env
    from train.learning.jitted.apg import JaxAPG

    env, params = make_gymnax_env("DWRPointStabilization-v2", T_con_range=[2.0, 2.2])
    settings = APGSettings(episodes=4, net_arch=(8,), linear_schedule=True, learning_rate=0.01)
    apg = JaxAPG(settings, env, params, total_timesteps=4 * 42 * 10)  # ten updates of four episodes of 40-44 steps
    assert apg.decay_updates == 10

    def moved(before: Any, after: Any) -> float:
        return max(float(np.max(np.abs(np.asarray(a) - np.asarray(b))))
                   for a, b in zip(jax.tree.leaves(before.params), jax.tree.leaves(after.params), strict=True))  # fmt: skip

    state = apg.init(0)
    steps = []
    for _ in range(12):
        before, (state, _) = state, apg.update(state)
        steps.append(moved(before, state))
    assert steps[0] == pytest.approx(0.01, rel=1e-3)  # Adam's first step: the rate
    assert all(a > b for a, b in itertools.pairwise(steps[:10]))  # shrinking
    assert max(steps[10:]) < 1e-8  # past the budget the rate is 0: the weights stay (to float32 rounding)


def test_keep_best_exports_the_best_policy_its_validation_measured() -> None:
    """With ``keep_best`` the exported network is the one of highest mean return on the run's fixed validation
    episodes, whichever came later; a network of NaN weights is never kept; without it, the last."""
    from dwr_gym.jax_env import make_gymnax_env
    from train.learning.jitted.apg import JaxAPG

    env, params = make_gymnax_env("DWRPointStabilization-v2", T_con_range=[2.0, 2.2])
    apg = JaxAPG(APGSettings(episodes=2, net_arch=(8,), keep_best=1, validation_episodes=3), env, params)
    state = apg.init(0)
    leaves, tree = jax.tree.flatten(state.params)

    def random_network(i: int) -> Any:
        return jax.tree.unflatten(tree, [jax.random.normal(jax.random.PRNGKey(10 * i + j), x.shape) * 3.0
                                         for j, x in enumerate(leaves)])  # fmt: skip

    candidates = [state.params] + [random_network(i) for i in range(3)]
    returns = []
    for candidate in candidates:
        state, metrics = apg.validate(state.replace(params=candidate))
        returns.append(float(metrics["validation_return"]))
        assert int(metrics["steps"]) == 3 * 40 or 3 * 40 < int(metrics["steps"]) <= 3 * 44
    best = int(np.argmax(returns))
    assert len(set(returns)) == len(returns) and float(state.best_return) == max(returns)
    for kept, expected in zip(jax.tree.leaves(apg.exported_params(state)), jax.tree.leaves(candidates[best]),
                              strict=True):  # fmt: skip
        assert np.array_equal(kept, expected)
    broken = jax.tree.map(lambda x: x * np.nan, state.params)
    after, metrics = apg.validate(state.replace(params=broken))
    assert not bool(metrics["kept"])  # (the env holds a NaN action's robot still: its return is finite, and low)
    assert float(after.best_return) == max(returns)
    last = JaxAPG(APGSettings(episodes=2, net_arch=(8,)), env, params)
    assert last.exported_params(state) is state.params  # keep_best off: the last policy


def test_weight_average_is_the_polyak_average_and_what_is_validated_and_exported(tmp_path: Path) -> None:
    """With ``weight_average`` each update moves the average (1 - decay) of the way to the new network; the average is
    what the run exports and what ``keep_best`` validates; a state saved before the average existed loads with the
    network as its average."""
    import dataclasses
    import pickle

    import flax.serialization

    from train.learning.jitted.apg import JaxAPG
    from train.learning.jitted.run import load_runner

    base = small_apg(state_grad_clip=1.0)
    apg = JaxAPG(dataclasses.replace(base.settings, weight_average=0.9), base.env, base.env_params)
    state = apg.init(0)
    after, _ = apg.update(state)
    for average, old, new in zip(jax.tree.leaves(after.average_params), jax.tree.leaves(state.params),
                                 jax.tree.leaves(after.params), strict=True):  # fmt: skip
        np.testing.assert_allclose(average, 0.9 * np.asarray(old) + 0.1 * np.asarray(new), rtol=1e-6, atol=1e-7)
    assert any(not np.array_equal(a, b) for a, b in zip(jax.tree.leaves(after.average_params),
                                                        jax.tree.leaves(after.params), strict=True))  # fmt: skip
    assert apg.exported_params(after) is after.average_params
    kept = JaxAPG(dataclasses.replace(apg.settings, keep_best=1, validation_episodes=2), apg.env, apg.env_params)
    validated, metrics = kept.validate(after)
    assert bool(metrics["kept"])
    for a, b in zip(jax.tree.leaves(kept.exported_params(validated)), jax.tree.leaves(after.average_params),
                    strict=True):  # fmt: skip
        assert np.array_equal(a, b)
    old = flax.serialization.to_state_dict(after)
    del old["average_params"]
    path = tmp_path / "resume_state.pkl"
    path.write_bytes(pickle.dumps({"timesteps": 7, "runner": flax.serialization.msgpack_serialize(old)}))
    loaded, steps = load_runner(path, apg.init(1))
    assert steps == 7
    for a, b in zip(jax.tree.leaves(loaded.average_params), jax.tree.leaves(after.params), strict=True):
        assert np.array_equal(a, b)


def test_an_update_counts_the_episodes_steps_and_keeps_every_number_finite() -> None:
    apg = small_apg(state_grad_clip=1.0, residual=True)
    state = apg.init(0)
    after, metrics = apg.update(state)
    assert 2 * 40 <= int(metrics["steps"]) <= 2 * 44 and int(after.updates) == 1  # two episodes of T_con 2-2.2 s
    assert not bool(metrics["skipped"])
    assert np.isfinite(float(metrics["return_mean"])) and np.isfinite(float(metrics["grad_norm"]))
    assert all(np.all(np.isfinite(np.asarray(leaf))) for leaf in jax.tree.leaves(after.params))
    changed = [not np.array_equal(a, b) for a, b in zip(jax.tree.leaves(state.params), jax.tree.leaves(after.params),
                                                          strict=True)]  # fmt: skip
    assert any(changed)


def test_an_update_whose_gradient_is_undefined_is_skipped() -> None:
    """One episode whose derivative is NaN (here sqrt at 0, as 0/0 at the goal) makes the batch's gradient undefined:
    the update is skipped, reported, and no weight becomes NaN; the next defined batch moves them again."""
    import jax.numpy as jnp

    from train.learning.jitted.apg import JaxAPG

    class Undefined(JaxAPG):
        poisoned = True

        def episode(self, params: Any, stats: Any, key: Any, limit: Any = None) -> tuple[Any, Any]:
            total, steps = super().episode(params, stats, key, limit)
            kernel = jax.tree.leaves(params)[-1]
            nan = jnp.sqrt(jnp.sum(kernel * 0.0)) if self.poisoned else 0.0  # d/dx sqrt(0 * x) = inf * 0
            return total + nan, steps

    base = small_apg(residual=True)
    apg = Undefined(base.settings, base.env, base.env_params, residual=True)
    state = apg.init(0)
    after, metrics = apg.update(state)
    assert bool(metrics["skipped"]) and np.isfinite(float(metrics["return_mean"]))
    for a, b in zip(jax.tree.leaves(state.params), jax.tree.leaves(after.params), strict=True):
        assert np.array_equal(a, b)  # Adam's first step on a zero gradient: none
    apg.poisoned = False
    apg.update = jax.jit(apg._update)
    moved, metrics = apg.update(after)
    assert not bool(metrics["skipped"])
    assert all(np.all(np.isfinite(np.asarray(leaf))) for leaf in jax.tree.leaves(moved.params))
    assert any(not np.array_equal(a, b) for a, b in zip(jax.tree.leaves(after.params), jax.tree.leaves(moved.params),
                                                        strict=True))  # fmt: skip


def test_the_exported_agent_acts_as_the_trained_policy() -> None:
    from train.learning.jitted.apg_trainer import apg_policy_kwargs
    from train.learning.jitted.export import SB3Exporter
    from train.learning.training_env import make_training_env

    apg = small_apg()
    state = apg.init(0)
    leaves, tree = jax.tree.flatten(state.params)  # random weights: some actions clipped, some not
    keys = jax.random.split(jax.random.PRNGKey(7), len(leaves))
    params = jax.tree.unflatten(tree, [jax.random.normal(k, x.shape) for k, x in zip(keys, leaves, strict=True)])
    stats = state.obs_stats
    config = resolved(env_id="DWRPointStabilization-v2", hyperparam_overrides={"policy_kwargs": {"net_arch": [8]}})
    model = SB3Exporter(make_training_env(config), {"policy_kwargs": apg_policy_kwargs(apg.settings)}).load(
        *jax.device_get((params, stats.mean, stats.var))
    )
    rng = np.random.default_rng(0)
    obs = rng.normal(size=(300, 10)) * [1, 1, 1, 1, 1, 1, 0.5, 20, 1, 1] + [1, 0, 0, 0, 0, 0, 0.5, 30, 1, 0]
    obs = obs.astype(np.float32)
    expected = np.asarray(apg.act(params, obs, stats))
    assert 0.05 < np.mean(np.abs(expected) == 1.0) < 0.95
    actions, _ = model.predict(obs, deterministic=True)
    np.testing.assert_allclose(actions, expected, atol=1e-4)


TINY = ("train", "--algo", "apg", "--backend", "jax", "--env", "DWRPointStabilization-v2", "--eval-episodes", "3",
        "--no-progress", "--env-kwargs", "T_con_range=[10,11]", "--hyperparams", "episodes=2", "learning_rate=0.0003",
        "policy_kwargs=dict(net_arch=[16])", "keep_best=2", "validation_episodes=2")  # fmt: skip


@pytest.mark.slow
def test_cli_trains_resumes_bit_for_bit_and_evaluates(tmp_path: Path) -> None:
    """(With keep_best, the validations before every second update resume as they ran. A constant rate: a linear
    schedule decays over the budget of the command that starts the run, so one resumed
    with a larger budget follows another schedule than a run started with it.)"""
    split = assert_resume_is_bit_for_bit(TINY, 3000, 1000, tmp_path)
    import yaml

    saved = yaml.safe_load((split / "config.yaml").read_text())
    assert saved["learned_from"] == "reward" and saved["config"]["algo"] == "apg"
    done = cli("evaluate", "--agents", str(split), "--n", "3", "--scenarios", "random", "--controllers", "ptc",
               "--env", "DWRPointStabilization-v2", "--optimum", "none", "--no-progress",
               "--out", str(tmp_path / "evaluate"))  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "split" in done.stdout and "ptc" in done.stdout
