"""The learners of ``dwr-gym train``: one entry per algorithm and backend, the one place that says which exist.

A learner is a module with ``train(config, command=None, on_evaluation=None) -> Path`` (a trainer) that trains the
:class:`~train.learning.config.TrainConfig` it is given in the run directory of :mod:`train.learning.runs` and saves
``model.zip`` as a model of its entry's ``model`` class, so that every agent loads, evaluates and compares the same
way (:func:`train.learning.agents.load_agent`). :func:`train.learning.training.train` looks the learner up here and
calls it; ``--algo`` and ``--backend`` accept what is here (their help is written from it); the options every learner
does not implement (``--residual``, ``--init-from``) are refused here in one line; the hyperparameters are checked
against the model class's constructor, or by the entry's own ``hyperparams`` function.

Trainers by kind (:data:`KINDS`), each a package of :mod:`train.learning`: ``sb3`` (stable-baselines3 on torch, and
sbx-rl, which keeps its API on JAX), ``jitted`` (the PPO compiled whole with the functional JAX env, and the loop
every jitted trainer shares: :func:`train.learning.jitted.run.train_jitted`), ``evolution`` (evolution strategies on
that loop). The imitation learners of
:mod:`train.learning.imitation` (``dwr-gym imitate``, DAgger) are commands of their own, with their own options,
that write the same run directory and agent format. This module imports nothing of the project, so that the
configuration can read it.
"""

from __future__ import annotations

import importlib
import importlib.util
from dataclasses import dataclass
from typing import Any

KINDS: dict[str, str] = {
    "sb3": "stable-baselines3's API on the native vector env: SB3 on torch, or sbx-rl on JAX (train.learning.sb3)",
    "jitted": "a gradient learner compiled whole with the functional JAX env: PPO, and APG through its derivative "
    "(train.learning.jitted)",
    "evolution": "evolution strategies, on the loop of the jitted trainers (train.learning.evolution)",
}

SB3 = ("stable_baselines3",)
CONTRIB = ("stable_baselines3", "sb3_contrib")
SBX = ("stable_baselines3", "sbx", "flax")
JAX = ("stable_baselines3", "jax", "flax", "optax")
EVOSAX = (*JAX, "evosax")


@dataclass(frozen=True)
class Learner:
    """One algorithm on one backend: the module that trains it and what it supports."""

    algo: str
    """``--algo``."""
    backend: str
    """``--backend``."""
    kind: str
    """One of :data:`KINDS`."""
    trainer: str
    """The module whose ``train(config, command=None, on_evaluation=None) -> Path`` trains it."""
    model: str
    """``module:Class`` of the model its model.zip loads as (``Class.load(path)``)."""
    extra: str
    """The dwr-gym extra that installs what it needs."""
    requires: tuple[str, ...] = SB3
    """Modules it imports to train; a missing one is refused before any work, naming :attr:`extra`."""
    residual: bool = False
    """Whether it trains ``--residual`` agents."""
    init_from: bool = False
    """Whether it starts from a saved network (``--init-from``)."""
    hyperparams: str | None = None
    """``module:function`` that coerces its hyperparameters (a dict, returned checked; a ConfigError naming a bad one);
    None: they are the keywords of :attr:`model`'s constructor (``train.learning.hyperparams.check_algo_kwargs``)."""

    def check_options(self, config: Any) -> None:
        """Raise ValueError (one line) where ``config`` asks for what this learner does not implement."""
        for option, flag in (("residual", "--residual"), ("init_from", "--init-from")):
            if getattr(config, option, None) not in (None, False) and not getattr(self, option):
                able = [learner for learner in LEARNERS if getattr(learner, option)]
                raise ValueError(f"{flag} is invalid with --backend {self.backend} --algo {self.algo}: it is "
                                 f"implemented by {describe(able)}")  # fmt: skip

    def check_installed(self) -> None:
        """Raise ImportError naming the extra where a module it needs is not installed. Found, not imported: a
        trainer may have to set XLA's flags before jax is imported (``train.learning.evolution.trainer``)."""
        for module in self.requires:
            if importlib.util.find_spec(module) is None:
                raise ImportError(f'--backend {self.backend} --algo {self.algo} needs {module}, which is not '
                                  f'installed: pip install "dwr-gym[{self.extra}]"', name=module) from None  # fmt: skip

    def model_class(self) -> Any:
        """The class of its model.zip; ImportError naming the extra where its library is not installed."""
        module, name = self.model.split(":")
        try:
            return getattr(importlib.import_module(module), name)
        except ImportError as error:
            raise ImportError(f'--backend {self.backend} --algo {self.algo} needs {error.name or module}, which is '
                              f'not installed: pip install "dwr-gym[{self.extra}]"', name=module) from None  # fmt: skip

    def function(self, path: str) -> Any:
        """The function ``module:name`` (the trainer's ``train``, the hyperparameters' check)."""
        module, _, name = path.partition(":")
        return getattr(importlib.import_module(module), name)


_SB3 = "train.learning.sb3.trainer"
# fmt: off
LEARNERS: tuple[Learner, ...] = (
    Learner("ppo", "sb3", "sb3", _SB3, "stable_baselines3:PPO", "train", residual=True, init_from=True),
    Learner("sac", "sb3", "sb3", _SB3, "stable_baselines3:SAC", "train", residual=True, init_from=True),
    Learner("td3", "sb3", "sb3", _SB3, "stable_baselines3:TD3", "train", residual=True, init_from=True),
    Learner("tqc", "sb3", "sb3", _SB3, "sb3_contrib:TQC", "train", CONTRIB, residual=True, init_from=True),
    Learner("crossq", "sb3", "sb3", _SB3, "sb3_contrib:CrossQ", "train", CONTRIB, residual=True, init_from=True),
    Learner("sac", "sbx", "sb3", _SB3, "sbx:SAC", "sbx", SBX),
    Learner("td3", "sbx", "sb3", _SB3, "sbx:TD3", "sbx", SBX),
    Learner("tqc", "sbx", "sb3", _SB3, "sbx:TQC", "sbx", SBX),
    Learner("crossq", "sbx", "sb3", _SB3, "sbx:CrossQ", "sbx", SBX),
    Learner("ppo", "jax", "jitted", "train.learning.jitted.trainer", "stable_baselines3:PPO", "jax", JAX,
            residual=True),
    Learner("es", "jax", "evolution", "train.learning.evolution.trainer", "stable_baselines3:PPO", "es", EVOSAX,
            residual=True, init_from=True, hyperparams="train.learning.evolution.settings:check_es_kwargs"),
    Learner("apg", "jax", "jitted", "train.learning.jitted.apg_trainer", "stable_baselines3:PPO", "jax", JAX,
            residual=True, hyperparams="train.learning.jitted.apg_settings:check_apg_kwargs"),
)
# fmt: on
"""Every learner of ``dwr-gym train``; a new one is a line here and its trainer module."""

ALGORITHMS: tuple[str, ...] = tuple(dict.fromkeys(learner.algo for learner in LEARNERS))
BACKENDS: tuple[str, ...] = tuple(dict.fromkeys(learner.backend for learner in LEARNERS))


def describe(learners: tuple[Learner, ...] | list[Learner]) -> str:
    """``--backend sb3 (ppo, sac) or --backend jax (ppo)``: the learners grouped by backend."""
    by_backend: dict[str, list[str]] = {}
    for learner in learners:
        by_backend.setdefault(learner.backend, []).append(learner.algo)
    return " or ".join(f"--backend {backend} ({', '.join(algos)})" for backend, algos in by_backend.items())


def find_learner(algo: str, backend: str) -> Learner:
    """The learner of ``algo`` on ``backend``; ValueError (one line) naming the backends that train ``algo``."""
    for learner in LEARNERS:
        if (learner.algo, learner.backend) == (algo, backend):
            return learner
    if algo not in ALGORITHMS:
        raise ValueError(f"--algo {algo!r} is invalid: expected one of {', '.join(ALGORITHMS)}")
    if backend not in BACKENDS:
        raise ValueError(f"--backend {backend!r} is invalid: expected one of {', '.join(BACKENDS)}")
    trained_by = [learner.backend for learner in LEARNERS if learner.algo == algo]
    on_backend = [learner.algo for learner in LEARNERS if learner.backend == backend]
    raise ValueError(f"--algo {algo!r} is invalid with --backend {backend}: {backend} trains {', '.join(on_backend)}; "
                     f"{algo} trains with --backend {' or '.join(trained_by)}")  # fmt: skip


BACKEND_NOTES = {"sb3": "stable-baselines3 on torch", "sbx": "sbx-rl: stable-baselines in JAX",
                 "jax": "compiled whole with the JAX env"}  # fmt: skip
"""What ``--backend``'s help says of each backend (a backend not here: its kind's line of :data:`KINDS`)."""


def options_help() -> tuple[str, str]:
    """The help of ``--algo`` and ``--backend``, written from :data:`LEARNERS`."""
    by_algo = {algo: [learner.backend for learner in LEARNERS if learner.algo == algo] for algo in ALGORITHMS}
    algo = "algorithm: " + ", ".join(f"{name} ({'/'.join(backends)})" for name, backends in by_algo.items())
    backends = []
    for backend in BACKENDS:
        learners = [learner for learner in LEARNERS if learner.backend == backend]
        extras = list(dict.fromkeys(learner.extra for learner in learners))
        note = BACKEND_NOTES.get(backend, KINDS[learners[0].kind])
        backends.append(f"{backend} ({note}, extra{'s' if len(extras) > 1 else ''} {', '.join(map(repr, extras))})")
    return algo, "training library: " + ", ".join(backends)


__all__ = [
    "ALGORITHMS",
    "BACKENDS",
    "BACKEND_NOTES",
    "KINDS",
    "LEARNERS",
    "Learner",
    "describe",
    "find_learner",
    "options_help",
]
