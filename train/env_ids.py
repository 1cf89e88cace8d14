"""The env ids that dwr-gym's commands accept, and the keywords each is registered with.

``DWRPointStabilization-v2`` is every command's default: the task held to T_con (T_con drawn per episode in
[10, 60] s, starts 0.3-3 m away, and a return that pays being at the goal pose at T_con less the energy, nothing
for arriving early), the env to learn from (gamma = 1). It is the newest version, so Gymnasium does not warn
when it is made. ``DWRPointStabilization-v1`` is the same task ending on arrival, whose optimum is the task
(arrive by T_con with the least energy): the env of the agents and tables made before v2, which keep their own id.
``DWRPointStabilization-v0`` is the paper's original reward at T_con = 20 s, kept bit for bit for reproduction.
"""

from __future__ import annotations

from typing import Any

TASK_ENV_ID = "DWRPointStabilization-v1"
PAPER_ENV_ID = "DWRPointStabilization-v0"
HELD_ENV_ID = "DWRPointStabilization-v2"
#: Every command's default env: the newest id, so nothing run by default prints Gymnasium's "out of date" warning.
DEFAULT_ENV_ID = HELD_ENV_ID
ENV_IDS: tuple[str, ...] = (HELD_ENV_ID, TASK_ENV_ID, PAPER_ENV_ID)
#: What a run whose config.yaml records no env id was trained on: every run before ids were recorded used v0.
UNRECORDED_ENV_ID = PAPER_ENV_ID
ENV_HELP = (
    f"env id: {HELD_ENV_ID} (the task held to T_con: T_con drawn per episode, the pose at T_con less the energy), "
    f"{TASK_ENV_ID} (the same task ending on arrival, energy-optimal reward) or {PAPER_ENV_ID} "
    "(the paper's original reward at T_con = 20 s)"
)


def check_env_id(env_id: Any, flag: str = "--env") -> str:
    """``env_id`` without a ``dwr_gym:`` prefix, or a ValueError of one line naming the ids allowed."""
    text = str(env_id).removeprefix("dwr_gym:")
    if text not in ENV_IDS:
        raise ValueError(f"{flag} {env_id!r} is invalid: expected {HELD_ENV_ID} (the task held to T_con, the default), "
                         f"{TASK_ENV_ID} (the task ending on arrival) or {PAPER_ENV_ID} (the paper's reward)")  # fmt: skip
    return text


def env_keywords(env_id: str, overrides: dict[str, Any] | None = None) -> dict[str, Any]:
    """The keywords ``env_id`` is registered with (v2's or v1's defaults, none for v0), then ``overrides``, whose JSON forms
    of a robot, disturbances and ``disturbance_distribution`` (``--env-kwargs disturbance_distribution='{}'``, as
    config.yaml records them) become the objects (:func:`dwr_gym.serialization.env_kwargs_from_json`)."""
    import gymnasium

    import dwr_gym  # noqa: F401  (registers the ids)
    from dwr_gym.serialization import env_kwargs_from_json

    return {**gymnasium.spec(check_env_id(env_id)).kwargs, **env_kwargs_from_json(dict(overrides or {}))}
