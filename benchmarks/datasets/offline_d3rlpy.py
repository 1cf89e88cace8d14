"""TD3+BC (Fujimoto and Gu 2021) of d3rlpy on a dwr-gym dataset, saved as a run ``dwr-gym evaluate`` loads.

    /work/venv-d3rlpy/bin/python -m benchmarks run offline-d3rlpy dwr-gym/robust-pt-nominal-v0 runs/td3bc

Runs in an interpreter with d3rlpy (which pins gymnasium 1.0.0: install it with ``pip install --no-deps d3rlpy``
and its other requirements beside dwr-gym; docs/datasets.md says how). d3rlpy's TD3+BC actor (10 -> 256 -> 256 ->
2, ReLU, tanh) is the actor of stable-baselines3's TD3 with ``net_arch [256, 256]``: its weights are copied into one
and saved as ``model.zip`` with a ``config.yaml``, so the agent is evaluated like any other.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from benchmarks.core.commands import parser_for


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("offline-d3rlpy", __doc__)
    parser.add_argument("dataset_id")
    parser.add_argument("run_dir", type=Path)
    parser.add_argument(
        "--steps",
        type=int,
        default=5_000,
        help="gradient steps (the paper: 1,000,000; 5,000 take 5 min on one CPU core)",
    )
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    import d3rlpy
    import numpy as np
    import torch
    import yaml
    from stable_baselines3 import TD3

    from dwr_gym.sb3 import make_sb3_vec_env
    from dwr_gym.serialization import env_kwargs_to_json
    from train.datasets.build import nominal
    from train.datasets.store import dataset_env, load_dataset, transitions
    from train.learning.config import TrainConfig

    torch.set_num_threads(1)
    d3rlpy.seed(args.seed)
    dataset = load_dataset(args.dataset_id)
    env_id, env_kwargs = dataset_env(dataset)
    data = transitions(dataset)
    # d3rlpy's MDPDataset takes flat arrays and cuts episodes at terminals or timeouts
    mdp = d3rlpy.dataset.MDPDataset(data["observations"], data["actions"], data["rewards"].astype(np.float32),
                                    data["terminals"].astype(np.float32), data["timeouts"].astype(np.float32))  # fmt: skip
    algo = d3rlpy.algos.TD3PlusBCConfig(batch_size=256).create(device="cpu")
    began = time.perf_counter()
    algo.fit(mdp, n_steps=args.steps, n_steps_per_epoch=args.steps, show_progress=False, save_interval=10**9,
             experiment_name="td3bc", with_timestamp=False, logger_adapter=d3rlpy.logging.NoopAdapterFactory())  # fmt: skip
    seconds = time.perf_counter() - began
    kwargs = nominal(env_kwargs)
    model = TD3("MlpPolicy", make_sb3_vec_env(1, seed=args.seed, **kwargs), seed=args.seed,
                device="cpu", policy_kwargs={"net_arch": [256, 256]})  # fmt: skip
    source = algo.impl.modules.policy.state_dict()
    with torch.no_grad():
        for actor in (model.policy.actor, model.policy.actor_target):
            for index, name in ((0, "_encoder._layers.0"), (2, "_encoder._layers.2"), (4, "_fc")):
                actor.mu[index].weight.copy_(source[f"{name}.weight"])
                actor.mu[index].bias.copy_(source[f"{name}.bias"])
    observations = torch.as_tensor(data["observations"][:256])
    expected = algo.predict(data["observations"][:256])
    copied = model.policy.actor(observations).detach().numpy()
    assert np.allclose(copied, expected, atol=1e-5), "the copied actor does not act as d3rlpy's"
    args.run_dir.mkdir(parents=True, exist_ok=True)
    model.save(args.run_dir / "model.zip")
    config = TrainConfig(algo="td3", env_id=env_id, env_kwargs=env_kwargs_to_json(kwargs), seed=args.seed,
                         run_dir=str(args.run_dir), progress=False,
                         algo_kwargs={"policy": "MlpPolicy", "policy_kwargs": {"net_arch": [256, 256]}})  # fmt: skip
    offline = {"library": f"d3rlpy {d3rlpy.__version__}", "algorithm": "TD3+BC", "dataset": args.dataset_id,
               "gradient_steps": args.steps, "batch_size": 256, "seconds": round(seconds, 1)}  # fmt: skip
    (args.run_dir / "config.yaml").write_text(yaml.safe_dump({"config": config.to_dict(), "offline": offline,
                                                              "learned_from": "dataset", "runtime": []},
                                                             sort_keys=False))  # fmt: skip
    print(json.dumps(offline))
    return 0
