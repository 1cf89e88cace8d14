"""Loading trained agents (a run directory or its model .zip) as policies, and the ones shipped with dwr-gym."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from train.learning.runs import MODEL_FILE, AgentLoadError, find_run_dir, load_config

PRETRAINED_DIR = Path(__file__).resolve().parent.parent / "pretrained"
#: The agents shipped with dwr-gym, by the name ``--agents`` accepts (their directories' names with dashes): one per
#: row of the leaderboard that ships one (train.reporting.leaderboard.ROWS, each trained on the env id of its
#: config.yaml), then the paper's reward's record (:data:`PAPER_AGENTS`).
PRETRAINED = {
    "apg-v2": PRETRAINED_DIR / "apg_v2",
    "apg-residual-ptc-v2": PRETRAINED_DIR / "apg_residual_ptc_v2",
    "ppo-jax-v1": PRETRAINED_DIR / "ppo_jax_v1",
    "es-v1": PRETRAINED_DIR / "es_v1",
    "robust": PRETRAINED_DIR / "robust",
    "ppo": PRETRAINED_DIR / "ppo",
    "residual-ppo": PRETRAINED_DIR / "residual_ppo",
}
#: The agents learned from the paper's reward (v0): its record, compared only when named (``--agents ppo``).
PAPER_AGENTS = ("ppo", "residual-ppo")
#: Agents shipped before, no longer in the package (their numbers stay in the results JSONs under docs/): the new
#: name of a renamed one, else None.
RETIRED = {
    "apg-hold-heading10-time-scaled-30min-v2": "apg-v2",
    "apg-residual-v2": "apg-residual-ptc-v2",
    "es-arena50-v1": "es-v1",
    **dict.fromkeys(
        ("apg-hold-heading-time-scaled-30min-v2", "apg-hold-time-scaled-30min-v2", "apg-near-miss-time-scaled-30min-v2",
         "apg-teacher-time-scaled-30min-v2", "apg-teacher-time-scaled-v2", "apg-teacher-v2", "dagger",
         "dagger-handover", "es-residual-v2", "es-time-scaled-v2", "ppo-jax-fixed-noise-v2", "ppo-v1",
         "residual-ppo-astolfi-v1", "residual-ppo-jax-v2", "residual-ppo-v1", "sac-tuned-v1", "tqc-tuned-v1"),
    ),
}  # fmt: skip


#: What of a composite agent ``load_agent`` returns: the whole agent, the network alone, or (for a robust agent)
#: the network with the analytic finish of ``robust-pt`` but without its planner.
PARTS = ("whole", "network", "no-plan")


def load_agent(path: str | Path, part: str = "whole") -> tuple[str, Any]:
    """(label, policy) for a saved agent: a run directory (its model.zip) or a .zip inside a run.

    ``part`` (one of :data:`PARTS`) takes a composite agent apart, to report the network alone beside the whole.
    """
    from train.learning.config import ConfigError
    from train.learning.hyperparams import algorithm_class
    from train.learning.training_env import as_policy

    path = Path(path)
    if part not in PARTS:
        raise AgentLoadError(f"part={part!r} is invalid: expected one of {', '.join(PARTS)}")
    if not path.exists():
        raise AgentLoadError(f"agent {str(path)!r} is invalid: no such file or directory")
    model_path = path / MODEL_FILE if path.is_dir() else path
    if not model_path.is_file():
        raise AgentLoadError(f"agent {str(path)!r} is invalid: no {MODEL_FILE} in it")
    if model_path.suffix != ".zip":
        raise AgentLoadError(f"agent {str(path)!r} is invalid: it is not a model .zip; expected a run directory "
                             f"or a model .zip in one")  # fmt: skip
    try:
        run_dir = find_run_dir(path if path.is_dir() else path.parent)
    except AgentLoadError:
        raise AgentLoadError(f"agent {str(path)!r} is invalid: no config.yaml beside it or above it") from None
    try:
        config = load_config(run_dir)
        model = algorithm_class(config.algo, config.backend).load(model_path, device="cpu")
    except (ConfigError, ValueError, KeyError, OSError) as error:
        raise AgentLoadError(f"agent {str(path)!r} could not be loaded: {error}") from error
    label = run_dir.name.replace("_", "-") if path.is_dir() else f"{run_dir.name}/{model_path.stem}"
    normalizer = None
    if config.normalize_obs:
        from train.learning.wrappers import load_obs_norm

        try:
            normalizer = load_obs_norm(model, model_path)
        except (OSError, KeyError, ValueError) as error:
            raise AgentLoadError(f"agent {str(path)!r} could not be loaded: {error}") from error
    policy = as_policy(model, config, normalizer)
    if part == "network":
        return f"{label} (network alone)", policy
    handover = load_extra(run_dir).get("handover")
    if handover:  # a network that hands over to an analytic law for the finish (imitation.handover.HandoverPolicy)
        from train.learning.imitation.handover import make_handover_policy

        try:
            policy = make_handover_policy(
                policy, handover["expert"], config.env_params(), handover["distance"],
                handover["time_fraction"], handover.get("speed_margin", 0.0),
            )  # fmt: skip
        except (KeyError, TypeError, ValueError) as error:
            raise AgentLoadError(f"agent {str(path)!r} has an invalid handover section: {error}") from error
    robust = load_extra(run_dir).get("robust_agent")
    if robust is not None:  # robust-pt whose cruise is the network (train.learning.imitation.robust_dagger)
        from train.learning.imitation.robust_agent import agent

        if part == "no-plan":
            robust, label = {**robust, "plan": False}, f"{label} (no planner)"
        try:
            policy = agent(policy, config.env_params(), **robust)
        except (TypeError, ValueError, ImportError) as error:
            raise AgentLoadError(f"agent {str(path)!r} has an invalid robust_agent section: {error}") from error
    return label, policy


def trained_env_id(path: str | Path) -> str:
    """The env id an agent was trained on (its config.yaml's ``env_id``; v0 for runs that recorded none)."""
    path = Path(path)
    return load_config(find_run_dir(path if path.is_dir() else path.parent)).env_id


def load_extra(run_dir: Path) -> dict[str, Any]:
    """The sections of a run's config.yaml besides the TrainConfig (``dagger``, ``handover``, ...)."""
    import yaml

    data = yaml.safe_load((run_dir / "config.yaml").read_text())
    return data if isinstance(data, dict) else {}


def pretrained_paths() -> dict[str, Path]:
    """The agents shipped with the package that are present in this installation."""
    return {name: path for name, path in PRETRAINED.items() if (path / "model.zip").is_file()}


def default_agents() -> dict[str, Path]:
    """The shipped agents that commands run when given none: the leaderboard's, not :data:`PAPER_AGENTS`."""
    return {name: path for name, path in pretrained_paths().items() if name not in PAPER_AGENTS}


def shipped_agent(given: str) -> Path | None:
    """The shipped agent that ``--agents`` names by its name (``apg-v2``) or its directory in the repository
    (``train/pretrained/apg_v2``, wherever the package is installed), else None."""
    path = Path(given)
    if path.parent.parts not in ((), ("train", "pretrained")):
        return None
    return pretrained_paths().get(path.name.replace("_", "-"))


def not_shipped_note(given: str) -> str:
    """Why ``given``, a path that does not exist, is not an agent of dwr-gym, and the agents that are: one line."""
    name = Path(given).stem.replace("_", "-")
    shipped = ", ".join(pretrained_paths()) or "none"
    if RETIRED.get(name):
        why = f"{name} is shipped as {RETIRED[name]} now"
    elif name in RETIRED:
        why = f"{name} is no longer shipped (its numbers stay in the results under docs/)"
    else:
        why = "no such file or directory"
    return f"{why}; the agents shipped with dwr-gym (a name or train/pretrained/NAME): {shipped}"


__all__ = [
    "PAPER_AGENTS",
    "PARTS",
    "PRETRAINED",
    "PRETRAINED_DIR",
    "RETIRED",
    "AgentLoadError",
    "default_agents",
    "find_run_dir",
    "load_agent",
    "load_extra",
    "not_shipped_note",
    "pretrained_paths",
    "shipped_agent",
    "trained_env_id",
]
