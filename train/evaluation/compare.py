"""``dwr-gym compare``'s measurements: trained agents against the PTC expert and the other laws, on the same
scenarios, and the recorded Figure 5 rollouts that its figures draw."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from baselines import plan_store
from dwr_gym.disturbances import split_env_kwargs
from dwr_gym.params import EnvParams
from train.evaluation.evaluate import evaluate, evaluate_sets, max_steps, running_beside
from train.evaluation.rollout import RolloutResult
from train.evaluation.scenarios import make_scenario
from train.evaluation.stages import FIGURES, StageClock, estimated_seconds

TRAJECTORY_SCENARIO = "paper-fig5"


def compare(
    agents: dict[str, Any],
    controllers: list[str],
    scenarios: list[str],
    n: int,
    seed: int,
    env_kwargs: dict[str, Any] | None = None,
    progress: bool = True,
    optimum: str = "none",
    T_cons: list[float] | None = None,
    n_optimal: int | None = None,
    on_rows: Callable[[list[dict[str, Any]]], None] | None = None,
    clock: StageClock | None = None,
    address: str | None = None,
    elsewhere: Sequence[tuple[dict[str, Any], dict[str, Any]]] = (),
) -> tuple[list[dict[str, Any]], dict[str, RolloutResult], tuple[str, ...]]:
    """Evaluate agents and controllers on each scenario set (at each T_con).

    ``elsewhere``: more agents, each group (agents by label, env keywords) on the same sets made with its own env's
    keywords (an agent on the env id it was trained on; the controllers run on ``env_kwargs``'s).

    Returns the rows, every policy's recorded rollouts from Figure 5's starts, and those starts' labels;
    ``on_rows`` receives the rows so far after each scenario set (:func:`evaluate_sets`); ``clock`` times the stages
    and shows one bar across them (:class:`StageClock`; default: one of its own, closed at the end); with ``address``
    the optima are solved as Ray tasks on that cluster.
    """
    policies: dict[str, Any] = {**agents, **{name: name for name in controllers}}
    runs = [(policies, env_kwargs or {}), *((dict(group), kwargs) for group, kwargs in elsewhere if group)]
    own = clock is None
    clock = clock or StageClock(progress=progress)
    trajectory_scenarios = [make_scenario(TRAJECTORY_SCENARIO, env_kwargs=kwargs) for _, kwargs in runs]
    # the recorded rollouts of the figures, the last stages: planned now, so that the time left counts them
    for (group, _), scenario in zip(runs, trajectory_scenarios, strict=True):
        steps = max_steps(scenario, EnvParams.from_kwargs(**split_env_kwargs(scenario.env_kwargs)[0]))
        clock.plan([((FIGURES, label), estimated_seconds(label, scenario.size, steps)) for label in group],
                   beside=running_beside(group))  # fmt: skip
    recorded: dict[str, RolloutResult] = {}
    try:
        with plan_store.opened():  # the planners' plans, kept for the next command (what they solved, also on Ctrl-C)
            # every group's sets in one run of evaluate_sets: their stages share its two processes
            rows = evaluate_sets(runs[0][0], scenarios, n, seed, runs[0][1], progress, optimum=optimum,
                                 T_cons=T_cons, n_optimal=n_optimal, on_rows=on_rows, clock=clock, address=address,
                                 more=runs[1:])  # fmt: skip
            for (group, _), scenario in zip(runs, trajectory_scenarios, strict=True):
                recorded.update(evaluate(group, scenario, record=True, clock=clock, stage_scenario=FIGURES))
    finally:
        if own:
            clock.close()
    return rows, recorded, trajectory_scenarios[0].labels
