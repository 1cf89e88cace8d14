"""The hyperparameters of ``dwr-gym train --algo es --backend jax`` (:mod:`train.learning.evolution.strategies`), under the names
of train/hyperparams/es.yml; checked here, before jax is imported, so bad values end the command in one line.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any

from dwr_gym.validation import as_bool, as_choice, as_float, as_int
from train.learning.config import ConfigError
from train.learning.jitted.policy import actor_hyperparameters, network_fields

#: evosax's class of each strategy (evosax 0.3), by the name the YAML gives it.
STRATEGIES: dict[str, str] = {
    "open_es": "Open_ES",  # OpenAI-ES, Salimans et al. 2017: Adam on the search gradient of centered ranks
    "snes": "SNES",  # separable natural ES, Wierstra et al. 2014: per-parameter step sizes adapted
    "pgpe": "PGPE",  # parameter-exploring policy gradients, Sehnke et al. 2010, with ClipUp
    "sep_cma_es": "Sep_CMA_ES",  # CMA-ES with a diagonal covariance, Ros and Hansen 2008
    "cma_es": "CMA_ES",  # full CMA-ES, Hansen 2001: a (parameters x parameters) covariance, slow past ~1000
}
#: Strategies that sample mirrored pairs (theta + sigma z, theta - sigma z): PGPE always, OpenAI-ES and SNES
#: when ``antithetic`` (SNES's through :class:`train.learning.evolution.strategies.MirroredSNES`).
ANTITHETIC: dict[str, tuple[bool, ...]] = {"open_es": (True, False), "snes": (True, False), "pgpe": (True,),
                                           "sep_cma_es": (False,), "cma_es": (False,)}  # fmt: skip
#: YAML keys of the ES, with their defaults; ``policy_kwargs`` (the network) is read as the jitted PPO's.
ES_DEFAULTS: dict[str, Any] = {
    "strategy": "open_es", "population_size": 64, "episodes": 8, "sigma": 0.05, "learning_rate": 0.01,
    "antithetic": True,
}  # fmt: skip
MAX_POPULATION = 65536


@dataclass(frozen=True)
class ESSettings:
    """One ES run's hyperparameters, named as in train/hyperparams/es.yml."""

    strategy: str = "open_es"
    """evosax strategy: open_es, snes, pgpe, sep_cma_es or cma_es (:data:`STRATEGIES`)."""
    population_size: int = 64
    """Candidates (perturbed policies) per generation; even with antithetic sampling (mirrored pairs)."""
    episodes: int = 8
    """Episodes each candidate plays per generation: the same starts and T_con for all (common random numbers)."""
    sigma: float = 0.05
    """Standard deviation of the parameter perturbations (the initial one for the strategies that adapt it)."""
    learning_rate: float = 0.01
    """Step size of the mean: Adam's for open_es, ClipUp's for pgpe, SGD's on the natural gradient for snes;
    the CMA-ES variants move their mean by their own rule and do not read it."""
    antithetic: bool = True
    """Sample mirrored pairs theta +- sigma z (open_es, snes; pgpe always does)."""
    net_arch: tuple[int, ...] = (64, 64)
    activation: str = "tanh"
    ortho_init: bool = True
    normalize_observations: bool = True
    """Scale observations by the running mean and deviation of those the candidates visited (Salimans et al.);
    folded into the first layer on export."""

    @classmethod
    def from_algo_kwargs(cls, algo_kwargs: dict[str, Any]) -> ESSettings:
        """The settings of resolved hyperparameters; an unknown key or a bad value is a ConfigError of one line."""
        values, policy = actor_hyperparameters(algo_kwargs, ES_DEFAULTS, "ES")
        try:
            strategy = as_choice("strategy", values["strategy"], STRATEGIES)
            antithetic = as_bool("antithetic", values["antithetic"])
            population = as_int("population_size", values["population_size"], 2, MAX_POPULATION, text=True)
            settings = cls(
                strategy=strategy, population_size=population,
                episodes=as_int("episodes", values["episodes"], 1, 4096, text=True),
                sigma=as_float("sigma", values["sigma"], 0.0, 100.0, low_inclusive=False, text=True),
                learning_rate=as_float("learning_rate", values["learning_rate"], 0.0, 100.0, low_inclusive=False,
                                       text=True),
                antithetic=antithetic, **network_fields(policy, "ES"),
            )  # fmt: skip
        except ValueError as error:
            raise ConfigError(str(error)) from None
        if antithetic not in ANTITHETIC[strategy]:
            allowed = "true" if antithetic is False else "false"
            raise ConfigError(f"antithetic={str(antithetic).lower()} is invalid with strategy={strategy!r}: "
                              f"expected antithetic={allowed}")  # fmt: skip
        if antithetic and population % 2:
            raise ConfigError(f"population_size={population} is invalid with antithetic sampling: expected an even "
                              "number (mirrored pairs), or antithetic=false")  # fmt: skip
        return settings

    def ppo_settings(self) -> Any:
        """The jitted PPO's settings of the same network, whose actor is the ES policy (train.learning.jitted.policy)."""
        from train.learning.jitted.policy import actor_network_settings

        return actor_network_settings(self)

    def as_dict(self) -> dict[str, Any]:
        return {f.name: getattr(self, f.name) for f in fields(self)}


def check_es_kwargs(params: dict[str, Any]) -> dict[str, Any]:
    """``params`` with its ES values coerced (for config.yaml), or a ConfigError; called by resolve_hyperparams."""
    settings = ESSettings.from_algo_kwargs(params)
    return {**params, **{k: getattr(settings, k) for k in ES_DEFAULTS}}
