"""Evolution strategies on the jitted env (``dwr-gym train --algo es --backend jax``): options refused in one line,
a diverged candidate ranked last, mirrored pairs, one set of episodes for the whole population, an exported agent
that acts as the evolved policy, and runs that resume bit for bit and load in ``dwr-gym evaluate``."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.jitted_runs import assert_resume_is_bit_for_bit, cli
from train.learning.config import ConfigError, TrainConfig
from train.learning.evolution.settings import ESSettings

ROOT = Path(__file__).resolve().parent.parent


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"population_size": 1}, r"^population_size=1 is invalid: expected an integer in \[2, 65536\]$"),
        ({"population_size": 7}, r"^population_size=7 is invalid with antithetic sampling: expected an even number"),
        ({"sigma": 0}, r"^sigma=0(\.0)? is invalid: expected a finite number in \(0, 100\]$"),
        ({"sigma": -0.1}, r"^sigma=-0.1 is invalid"),
        ({"episodes": 0}, r"^episodes=0 is invalid: expected an integer in \[1, 4096\]$"),
        ({"strategy": "adam_es"}, r"^strategy='adam_es' is invalid: expected one of 'open_es', 'snes', 'pgpe'"),
        ({"learning_rate": 0}, r"^learning_rate=0(\.0)? is invalid"),
        ({"strategy": "cma_es"}, r"^antithetic=true is invalid with strategy='cma_es': expected antithetic=false$"),
        ({"n_steps": 64}, r"^hyperparameter\(s\) \['n_steps'\] are not accepted by ES"),
    ],
)
def test_bad_options_are_refused_in_one_line(overrides: dict[str, Any], message: str) -> None:
    with pytest.raises(ConfigError, match=message) as error:
        ESSettings.from_algo_kwargs(overrides)
    assert "\n" not in str(error.value)


def test_valid_options_are_read_and_an_odd_population_needs_no_mirrors() -> None:
    settings = ESSettings.from_algo_kwargs({"population_size": "7", "antithetic": False, "strategy": "snes",
                                            "sigma": "0.1", "policy_kwargs": {"net_arch": [32]}})  # fmt: skip
    assert (settings.population_size, settings.sigma, settings.net_arch, settings.strategy) == (7, 0.1, (32,), "snes")


def resolved(**kwargs: Any) -> TrainConfig:
    from train.learning.hyperparams import resolve_hyperparams

    config = TrainConfig(algo="es", backend="jax", **kwargs)
    config.validate()
    return resolve_hyperparams(config, set(kwargs))


def test_the_yaml_is_read_and_es_needs_the_jax_backend() -> None:
    config = resolved(hyperparam_overrides={"sigma": 0.02})
    assert config.algo_kwargs["sigma"] == 0.02 and config.algo_kwargs["strategy"] == "open_es"
    assert config.num_envs == 1 and config.total_timesteps > 0
    refused = r"^--algo 'es' is invalid with --backend sb3: .*; es trains with --backend jax$"
    with pytest.raises(ConfigError, match=refused):
        TrainConfig(algo="es").validate()
    with pytest.raises(ConfigError, match=r"^hyperparameter"):
        resolved(hyperparam_overrides={"sigmaa": 0.02})


def test_without_evosax_es_names_the_extra_to_install(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    from train.learning.training import train

    monkeypatch.setitem(sys.modules, "evosax", None)  # import evosax raises ImportError
    config = resolved(run_dir=str(tmp_path / "run"))
    with pytest.raises(ConfigError, match=r'^--backend jax --algo es needs evosax, .*: pip install "dwr-gym\[es\]"$'):
        train(config)
    assert not (tmp_path / "run").exists()  # refused before any run directory is made


jax = pytest.importorskip("jax")
pytest.importorskip("evosax")


def test_a_nan_fitness_is_ranked_last_and_never_reaches_the_mean() -> None:
    import jax.numpy as jnp

    from train.learning.evolution.strategies import centered_ranks, fitness_of, make_strategy

    returns = jnp.asarray([3.0, jnp.nan, -1.0, 2.0, 0.5, -4.0])
    ranks = np.asarray(centered_ranks(fitness_of(returns)))
    assert ranks[1] == 0.5 and ranks[0] == -0.5  # the NaN worst, the highest return best
    np.testing.assert_allclose(np.sort(ranks), np.linspace(-0.5, 0.5, 6), atol=1e-6)
    strategy, params = make_strategy(ESSettings(population_size=6, sigma=0.1), jnp.zeros(5))
    state = strategy.init(jax.random.PRNGKey(0), jnp.zeros(5), params)
    population, state = strategy.ask(jax.random.PRNGKey(1), state, params)
    diverged, _ = strategy.tell(jax.random.PRNGKey(2), population, fitness_of(returns), state, params)
    worst = returns.at[1].set(-100.0)  # the same candidate, finite and worst
    finite, _ = strategy.tell(jax.random.PRNGKey(2), population, fitness_of(worst), state, params)
    assert np.all(np.isfinite(np.asarray(diverged.mean)))
    np.testing.assert_array_equal(np.asarray(diverged.mean), np.asarray(finite.mean))
    assert not np.array_equal(np.asarray(diverged.mean), np.zeros(5))


@pytest.mark.parametrize("strategy_name", ["open_es", "snes", "pgpe"])
def test_antithetic_sampling_draws_mirrored_pairs(strategy_name: str) -> None:
    import jax.numpy as jnp

    from train.learning.evolution.strategies import make_strategy

    mean = jnp.linspace(-1.0, 1.0, 7)
    strategy, params = make_strategy(ESSettings(strategy=strategy_name, population_size=8, sigma=0.3), mean)
    state = strategy.init(jax.random.PRNGKey(0), mean, params)
    population, _ = strategy.ask(jax.random.PRNGKey(1), state, params)
    population = np.asarray(population)
    np.testing.assert_allclose(population[:4] + population[4:], 2 * np.asarray(mean)[None].repeat(4, 0), atol=1e-6)
    assert np.std(population[:4] - np.asarray(mean)) > 0.1


@pytest.fixture(scope="module")
def small_es() -> Any:
    from dwr_gym.jax_env.gymnax import make_gymnax_env
    from train.learning.evolution.strategies import JaxES

    settings = ESSettings(population_size=4, episodes=3, net_arch=(16,))
    env, env_params = make_gymnax_env("DWRPointStabilization-v1", T_con_range=(10.0, 11.0))
    return JaxES(settings, env, env_params, devices=1)


@pytest.mark.slow
def test_every_candidate_plays_the_same_episodes(small_es: Any) -> None:
    es = small_es
    state = es.init(0)
    mean = es.actor(es.mean_params(state))
    population = jax.tree.map(lambda x: jax.numpy.stack([x] * 4), mean)  # four copies of one policy
    returns, steps, _ = jax.jit(es.play)(population, state, jax.random.PRNGKey(3))
    returns = np.asarray(returns)
    assert returns.shape == (4, 3) and np.all(np.isfinite(returns))
    np.testing.assert_array_equal(returns, returns[[0]].repeat(4, 0))  # the same episodes for all candidates
    assert len(set(returns[0].tolist())) == 3  # three different episodes
    assert 0 < int(steps) <= 4 * 3 * es.max_steps


def test_the_exported_agent_acts_as_the_evolved_policy(small_es: Any) -> None:
    from train.learning.evolution.trainer import es_policy_kwargs
    from train.learning.jitted.export import SB3Exporter
    from train.learning.training_env import make_training_env

    es = small_es
    state = es.init(0)
    mean = 0.3 * jax.random.normal(jax.random.PRNGKey(1), state.strategy.mean.shape)  # an evolved mean
    stats = state.obs_stats.replace(mean=state.obs_stats.mean + 0.3, var=state.obs_stats.var * 2.0)
    state = state.replace(strategy=state.strategy.replace(mean=mean), obs_stats=stats)
    config = resolved(hyperparam_overrides={"policy_kwargs": {"net_arch": [16]}})
    model = SB3Exporter(make_training_env(config), {"policy_kwargs": es_policy_kwargs(es.settings)}).load(
        *jax.device_get((es.mean_params(state), state.obs_stats.mean, state.obs_stats.var))
    )
    rng = np.random.default_rng(0)
    obs = rng.normal(size=(300, 10)) * [1, 1, 1, 1, 1, 1, 0.5, 20, 1, 1] + [1, 0, 0, 0, 0, 0, 0.5, 30, 1, 0]
    obs = obs.astype(np.float32)
    expected = np.asarray(es.act(es.mean_params(state), obs, state.obs_stats))
    assert 0.05 < np.mean(np.abs(expected) == 1.0) < 0.95  # some actions clipped, some not
    actions, _ = model.predict(obs, deterministic=True)
    np.testing.assert_allclose(actions, expected, atol=1e-4)  # (float32, the scaling folded into the first layer)


TINY = ("train", "--algo", "es", "--backend", "jax", "--env", "DWRPointStabilization-v1", "--eval-episodes", "3",
        "--no-progress", "--env-kwargs", "T_con_range=[10,11]", "--hyperparams", "population_size=4", "episodes=2",
        "policy_kwargs=dict(net_arch=[16])")  # fmt: skip


@pytest.mark.slow
def test_cli_trains_resumes_bit_for_bit_and_evaluates(tmp_path: Path) -> None:
    split = assert_resume_is_bit_for_bit(TINY, 6000, 2000, tmp_path)
    import yaml

    saved = yaml.safe_load((split / "config.yaml").read_text())
    assert saved["learned_from"] == "reward" and saved["config"]["algo"] == "es"
    assert saved["config"]["env_id"] == "DWRPointStabilization-v1" and saved["config"]["backend"] == "jax"
    assert saved["config"]["algo_kwargs"]["population_size"] == 4
    assert (split / "best_model.zip").is_file() and any((split / "checkpoints").glob("es_*_steps.zip"))
    done = cli("evaluate", "--agents", str(split), "--n", "3", "--scenarios", "random", "--controllers", "ptc",
               "--optimum", "none", "--no-progress", "--out", str(tmp_path / "evaluate"))  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "split" in done.stdout and "ptc" in done.stdout


def test_each_archived_docs_block_is_what_its_json_renders() -> None:
    from benchmarks.core import docs
    from benchmarks.learning.archive import BLOCKS

    assert {"es-learn", "es-speed"} <= {block.name for block in BLOCKS}
    for block in BLOCKS:
        if (ROOT / block.json).is_file():
            assert docs.written(block.name) == block.body(), block.name
