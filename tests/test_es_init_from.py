"""ES from a saved network (``dwr-gym train --algo es --backend jax --init-from RUN``): the search starts at the saved
actor (the policy at step 0 acts as the saved agent), the run adopts its architecture and records what it learned
from, and what it cannot start from is refused in one line."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.jitted_runs import cli
from train.learning.config import ConfigError

jax = pytest.importorskip("jax")
pytest.importorskip("evosax")


def saved_ppo(run_dir: Path, learned_from: str = "expert") -> Any:
    """A small PPO agent (ReLU, [24, 16], weights away from their initialisation) saved as a run directory."""
    import torch
    import yaml
    from stable_baselines3 import PPO

    from dwr_gym.sb3 import make_sb3_vec_env

    model = PPO("MlpPolicy", make_sb3_vec_env(num_envs=1, seed=0), seed=0, device="cpu",
                policy_kwargs={"net_arch": [24, 16], "activation_fn": torch.nn.ReLU})  # fmt: skip
    with torch.no_grad():
        for param in model.policy.parameters():
            param.add_(0.3 * torch.randn_like(param))
    run_dir.mkdir(parents=True)
    model.save(run_dir / "model.zip")
    (run_dir / "config.yaml").write_text(yaml.safe_dump({"config": {"algo": "ppo"}, "learned_from": learned_from}))
    return model


def test_the_search_starts_at_the_saved_actor(tmp_path: Path) -> None:
    from dwr_gym.jax_env.gymnax import make_gymnax_env
    from train.learning.evolution.init_from import adopt, saved_actor
    from train.learning.evolution.settings import ESSettings
    from train.learning.evolution.strategies import JaxES

    model = saved_ppo(tmp_path / "saved")
    actor, net_arch, activation = saved_actor(str(tmp_path / "saved"))
    assert (net_arch, activation) == ((24, 16), "relu")
    settings = adopt(ESSettings(population_size=4, episodes=2), net_arch, activation)
    assert not settings.normalize_observations  # the saved network takes raw observations
    env, env_params = make_gymnax_env("DWRPointStabilization-v2", T_con_range=(10.0, 11.0))
    es = JaxES(settings, env, env_params, devices=1, initial_actor=actor)
    state = es.init(0)
    rng = np.random.default_rng(0)
    obs = rng.normal(size=(300, 10)) * [1, 1, 1, 1, 1, 1, 0.5, 20, 1, 1] + [1, 0, 0, 0, 0, 0, 0.5, 30, 1, 0]
    obs = obs.astype(np.float32)
    expected, _ = model.predict(obs, deterministic=True)
    assert 0.05 < np.mean(np.abs(expected) == 1.0) < 0.95  # some actions clipped, some not
    np.testing.assert_allclose(np.asarray(es.act(es.mean_params(state), obs, state.obs_stats)), expected, atol=1e-5)


def test_a_saved_actor_of_another_shape_is_refused_naming_it() -> None:
    from dwr_gym.jax_env.gymnax import make_gymnax_env
    from train.learning.evolution.settings import ESSettings
    from train.learning.evolution.strategies import JaxES

    actor = {"policy_0": {"kernel": np.zeros((12, 16), np.float32), "bias": np.zeros(16, np.float32)},
             "action": {"kernel": np.zeros((16, 2), np.float32), "bias": np.zeros(2, np.float32)}}  # fmt: skip
    env, env_params = make_gymnax_env("DWRPointStabilization-v2", T_con_range=(10.0, 11.0))
    settings = ESSettings(population_size=4, episodes=2, net_arch=(16,), normalize_observations=False)
    es = JaxES(settings, env, env_params, devices=1, initial_actor=actor, initial_source="runs/other-env")
    with pytest.raises(
        ConfigError, match=r"^--init-from 'runs/other-env': the saved actor's policy_0.kernel \(12, 16\)"
    ):
        es.init(0)


def test_what_es_cannot_start_from_is_refused_in_one_line(tmp_path: Path) -> None:
    from stable_baselines3 import SAC

    from dwr_gym.sb3 import make_sb3_vec_env
    from train.learning.evolution.init_from import saved_actor

    SAC("MlpPolicy", make_sb3_vec_env(num_envs=1, seed=0), device="cpu").save(tmp_path / "sac.zip")
    for path, message in ((tmp_path / "sac.zip", "is invalid with --algo es: not a PPO model"),
                          (tmp_path / "none", "does not exist")):  # fmt: skip
        with pytest.raises(ConfigError, match=message) as error:
            saved_actor(str(path))
        assert str(path) in str(error.value) and "\n" not in str(error.value)


@pytest.mark.slow
def test_cli_fine_tunes_a_saved_network_and_records_it(tmp_path: Path) -> None:
    import yaml

    from train.learning.agents import load_agent

    saved_ppo(tmp_path / "cloned")
    common = ("train", "--algo", "es", "--backend", "jax", "--eval-episodes", "3", "--no-progress", "--env",
              "DWRPointStabilization-v2", "--env-kwargs", "T_con_range=[10,11]", "--hyperparams", "population_size=4",
              "episodes=2", "--total-timesteps", "3000", "--eval-freq", "3000", "--init-from", str(tmp_path / "cloned"))  # fmt: skip
    done = cli(*common, "--run-dir", str(tmp_path / "run"))
    assert done.returncode == 0, done.stderr
    assert "from " + str(tmp_path / "cloned") + " ([24, 16], relu)" in done.stderr
    saved = yaml.safe_load((tmp_path / "run" / "config.yaml").read_text())
    assert saved["learned_from"] == "expert, then reward"
    assert saved["config"]["algo_kwargs"]["policy_kwargs"]["net_arch"] == [24, 16]
    _, policy = load_agent(tmp_path / "run")  # the exported agent has the saved architecture
    assert [
        layer.out_features for layer in policy.policy.mlp_extractor.policy_net if hasattr(layer, "out_features")
    ] == [24, 16]
    refused = cli(*common, "--residual", "--run-dir", str(tmp_path / "residual"))
    assert refused.returncode != 0
    assert "--init-from is invalid with --algo es --residual" in refused.stderr
