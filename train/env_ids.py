"""The env ids that dwr-gym's commands accept, and the keywords each is registered with.

``DWRPointStabilization-v1`` is the task, and every command's default: T_con drawn per episode in [10, 60] s,
starts 0.3-3 m away, and a reward whose optimum is the task (arrive by T_con with the least energy).
``DWRPointStabilization-v2`` is the same task held to T_con, whose return pays nothing for arriving early: the
env to learn from (gamma = 1). ``DWRPointStabilization-v0`` is the paper's original reward at T_con = 20 s, kept
bit for bit for reproduction.
"""

from __future__ import annotations

from typing import Any

TASK_ENV_ID = "DWRPointStabilization-v1"
PAPER_ENV_ID = "DWRPointStabilization-v0"
HELD_ENV_ID = "DWRPointStabilization-v2"
ENV_IDS: tuple[str, ...] = (TASK_ENV_ID, PAPER_ENV_ID, HELD_ENV_ID)
#: What a run whose config.yaml records no env id was trained on: every run before ids were recorded used v0.
UNRECORDED_ENV_ID = PAPER_ENV_ID
ENV_HELP = (
    f"env id: {TASK_ENV_ID} (the task: T_con drawn per episode, energy-optimal reward, ends on arrival), "
    f"{HELD_ENV_ID} (the same task held to T_con: what RL should learn from) or {PAPER_ENV_ID} "
    "(the paper's original reward at T_con = 20 s)"
)


def check_env_id(env_id: Any, flag: str = "--env") -> str:
    """``env_id`` without a ``dwr_gym:`` prefix, or a ValueError of one line naming the ids allowed."""
    text = str(env_id).removeprefix("dwr_gym:")
    if text not in ENV_IDS:
        raise ValueError(f"{flag} {env_id!r} is invalid: expected {TASK_ENV_ID} (the task), {HELD_ENV_ID} (the task "
                         f"held to T_con) or {PAPER_ENV_ID}")  # fmt: skip
    return text


def env_keywords(env_id: str, overrides: dict[str, Any] | None = None) -> dict[str, Any]:
    """The keywords ``env_id`` is registered with (v1's defaults, none for v0), then ``overrides``, whose JSON forms
    of a robot, disturbances and ``disturbance_distribution`` (``--env-kwargs disturbance_distribution='{}'``, as
    config.yaml records them) become the objects (:func:`dwr_gym.serialization.env_kwargs_from_json`)."""
    import gymnasium

    import dwr_gym  # noqa: F401  (registers the ids)
    from dwr_gym.serialization import env_kwargs_from_json

    return {**gymnasium.spec(check_env_id(env_id)).kwargs, **env_kwargs_from_json(dict(overrides or {}))}
