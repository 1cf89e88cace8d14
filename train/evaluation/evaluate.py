"""Every policy on every scenario set: rows of metrics, measured against the optimum of each episode."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Any

from baselines import plan_store
from baselines.expert import ExpertPolicy
from dwr_gym.disturbances import split_env_kwargs
from dwr_gym.params import EnvParams
from train.evaluation.optimum import OPTIMA, missing_optima, optimal_energies
from train.evaluation.rollout import Policy, RolloutResult, rollout
from train.evaluation.scenarios import Scenario, controller_for, make_scenario
from train.evaluation.side_process import PLANNERS, SideProcess, side_process_usable
from train.evaluation.stages import COLD_EPISODE_SECONDS, PLAN_SECONDS, StageClock, estimated_seconds


def evaluate(
    policies: dict[str, Policy | str],
    scenario: Scenario,
    *,
    record: bool = False,
    seed: int = 0,
    progress: bool = False,
    optimum: str = "none",
    clock: StageClock | None = None,
    stage_scenario: str | None = None,
    address: str | None = None,
) -> dict[str, RolloutResult]:
    """Run each policy on the scenario; a string value names a controller of :mod:`baselines`.

    ``optimum`` "pose" (or "position") also solves, or reads from the cache, the minimum energy of
    each episode to the goal pose (or position) by T_con, for the energy / optimal ratios. With ``clock`` each
    stage (the optimum, each policy) is timed and advances its one bar (:mod:`train.evaluation.stages`); then
    ``progress`` is ignored; the stages are timed under the scenario's name, or ``stage_scenario``. With ``address``
    the optima are solved as Ray tasks on that cluster (:func:`optimal_energies`), and each policy's rollout is one Ray
    task there (:meth:`RayPool.run_each`: the same rollout as here, so the same numbers).
    """
    if optimum not in OPTIMA:
        raise ValueError(f"optimum={optimum!r} is invalid: expected one of {', '.join(OPTIMA)}")
    clock = clock or StageClock(progress=False)
    stage_scenario = stage_scenario or scenario.name
    params = EnvParams.from_kwargs(**split_env_kwargs(scenario.env_kwargs)[0])
    optimal_energy, optimum_failures = _optimum(scenario, params, optimum, clock, stage_scenario, progress, address)
    if address is not None:  # each policy's rollout one Ray task (its wall time the worker's)
        results = _rollouts_on_ray(policies, params, scenario, record, seed, address, clock, stage_scenario)
        for result in results.values():
            result.optimal_energy, result.optimum_failures = optimal_energy, optimum_failures
        return results
    beside = running_beside(policies)  # (not on Ray: returned above)
    plain = {label: policy for label, policy in policies.items() if label in beside}
    side = None
    if plain:  # the costliest planner here, the others beside it
        # the planners first, the agents next (a network's call per step: the costlier), the laws last: this process
        # takes from the end
        order = sorted(plain, key=lambda label: (label not in PLANNERS, isinstance(plain[label], str)))
        side = SideProcess(
            {label: (_rollout_one, (label, plain[label], params, scenario, record, seed)) for label in order}
        )
    results = {}
    steps = max_steps(scenario, params)

    def run_here(label: str) -> None:
        weight = estimated_seconds(label, scenario.size, steps)
        with clock.stage(stage_scenario, label, weight, scenario.size) as advance:

            def on_step(fraction: float) -> None:
                advance(fraction)
                if side is not None:  # the side process's stages on the bar as they end there
                    results.update(_recorded(side.finished(), 0.0, clock, stage_scenario, scenario.size, steps))

            results[label] = _rollout_one(label, policies[label], params, scenario, record, seed,
                                          progress and not clock.shown, on_step)  # fmt: skip

    try:
        for label in policies:
            if side is None or label not in plain:
                run_here(label)
        while side is not None and (label := side.take()) is not None:  # the side process's jobs not started yet
            run_here(label)
        if side is not None:
            began = time.perf_counter()
            finished = side.results()
            results.update(
                _recorded(finished, time.perf_counter() - began, clock, stage_scenario, scenario.size, steps)
            )
    finally:
        if side is not None:
            side.close()
    for result in results.values():
        result.optimal_energy, result.optimum_failures = optimal_energy, optimum_failures
    return {label: results[label] for label in policies}


def _optimum(
    scenario: Scenario, params: EnvParams, optimum: str, clock: StageClock, stage_scenario: str, progress: bool,
    address: str | None,
) -> tuple[Any, list[str]]:  # fmt: skip
    """The optimum's energy of each episode of ``scenario`` (solved, or read from the cache) and its failures; (None,
    []) with ``optimum`` "none". Timed on ``clock`` as the stage "optimum"."""
    if optimum == "none":
        return None, []
    todo = len(missing_optima(params, scenario.starts, scenario.goals, scenario.T_cons, heading=optimum == "pose"))
    with clock.stage(stage_scenario, "optimum", todo * PLAN_SECONDS, todo) as advance:
        return optimal_energies(  # type: ignore[no-any-return]
            params, scenario.starts, scenario.goals, scenario.T_cons, heading=optimum == "pose",
            progress=progress and not clock.shown, description=f"{scenario.name}: optimum",
            on_solved=lambda done: advance(done / max(todo, 1)), address=address,
        )  # fmt: skip


def _rollouts_on_ray(
    policies: dict[str, Policy | str],
    params: EnvParams,
    scenario: Scenario,
    record: bool,
    seed: int,
    address: str,
    clock: StageClock,
    stage_scenario: str,
) -> dict[str, RolloutResult]:
    """Every policy's rollout of ``scenario`` as one Ray task on the cluster at ``address``, all at once."""
    from train.evaluation.ray_pool import RayPool

    steps = max_steps(scenario, params)
    pool = RayPool(address)
    try:
        began = time.perf_counter()
        finished = pool.run_each(_rollout_one, [(label, policy, params, scenario, record, seed)
                                                for label, policy in policies.items()])  # fmt: skip
        waited = time.perf_counter() - began
    finally:
        pool.shutdown()
    return _recorded(dict(zip(policies, finished, strict=True)), waited, clock, stage_scenario, scenario.size, steps)


def _recorded(
    finished: dict[str, tuple[RolloutResult, float]], waited: float, clock: StageClock, stage_scenario: str,
    size: int, steps: int,
) -> dict[str, RolloutResult]:  # fmt: skip
    """The results of rollouts that ran in another process (each with its wall seconds there), their stages recorded
    on ``clock``; ``waited``, the seconds this process waited for them, counted once."""
    results = {}
    for label, (result, seconds) in finished.items():
        clock.record(stage_scenario, label, seconds, size, estimated_seconds(label, size, steps), waited)
        waited = 0.0
        results[label] = result
    return results


def _rollout_one(
    label: str,
    policy: Policy | str,
    params: EnvParams,
    scenario: Scenario,
    record: bool,
    seed: int,
    progress: bool = False,
    on_step: Callable[[float], None] | None = None,
) -> RolloutResult:
    """One policy (a controller's name makes it) on the scenario, its planner's failures counted."""
    if isinstance(policy, str):
        policy = ExpertPolicy(controller_for(policy, scenario, params), params.u_max, params.omega_max)
    # an agent's planner serves every set it runs on: this rollout's failures are those it adds
    failed_before = len(getattr(getattr(policy, "controller", None), "failures", ()))
    result = rollout(
        policy, params, scenario.starts, scenario.goals, record=record, seed=seed, progress=progress,
        description=f"{scenario.name}: {label}", T_con=scenario.T_cons, env_kwargs=scenario.env_kwargs,
        on_step=on_step,
    )  # fmt: skip
    controller = getattr(policy, "controller", None)
    result.planner_failures = len(getattr(controller, "failures", ())) - failed_before
    if hasattr(controller, "close"):
        controller.close()
    return result


def evaluate_sets(
    policies: dict[str, Policy | str],
    scenarios: list[str] | tuple[str, ...],
    n: int,
    seed: int,
    env_kwargs: dict[str, Any],
    progress: bool = False,
    optimum: str = "none",
    T_cons: list[float] | None = None,
    n_optimal: int | None = None,
    on_rows: Callable[[list[dict[str, Any]]], None] | None = None,
    clock: StageClock | None = None,
    address: str | None = None,
    more: Sequence[tuple[dict[str, Policy | str], dict[str, Any]]] = (),
) -> list[dict[str, Any]]:
    """Evaluate policies on named scenario sets, at each prescribed time of ``T_cons`` (default: the set's own).
    ``more``: further groups of policies, each with its own env keywords (an agent on the env id it was trained on),
    on the same sets made with those keywords; their rows follow the first group's, and their stages share the
    first group's two processes.

    With ``n_optimal``, the ``optimal`` controller (which re-plans from the measured pose once a disturbance pushes
    the robot off its plan, a CasADi solve each time) runs on the disturbed sets' first ``n_optimal`` episodes only.

    Returns one row per (scenario, T_con, policy): the keys ``scenario``, ``T_con``, ``policy``, those
    of :meth:`RolloutResult.summary`, ``optimum_note``, why the first episode without an optimum has none,
    ``seconds``, the wall time of the policy on the set, and ``optimum_seconds``, that of the set's optima (0 when
    cached). ``on_rows`` receives the rows so far after each (scenario, T_con): what an interrupted command still
    reports. With ``clock`` the stages advance its one bar (:class:`StageClock`), planned here before the first; with
    ``address`` the optima are solved as Ray tasks on that cluster.
    """
    from train.evaluation.disturbance_sets import ROBUSTNESS_SETS

    own = clock is None
    clock = clock or StageClock(progress=progress)
    blocks: list[tuple[dict[str, Policy | str], Scenario]] = []  # (policies, set) in the order of the rows
    beside = running_beside(policies, address)  # (the further groups' stages, where there are two processes, all)
    for group, group_kwargs in [(policies, env_kwargs), *((dict(g), k) for g, k in more if g)]:
        chosen = []
        for name in scenarios:
            for T_con in T_cons or [None]:
                # a prescribed time asked for replaces the env's range of them (v1 draws T_con per episode)
                kwargs = group_kwargs if T_con is None else {**group_kwargs, "T_con": T_con, "T_con_range": None}
                chosen.append(make_scenario(name, n=n, seed=seed, env_kwargs=kwargs))
        groups = {scenario.name: "disturbed" if scenario.name in ROBUSTNESS_SETS else "nominal" for scenario in chosen}
        clock.plan(planned_seconds(group, chosen, optimum, n_optimal),
                   beside=beside if group is policies else frozenset(group) if beside else frozenset(),
                   groups=groups)  # fmt: skip
        blocks += [(group, scenario) for scenario in chosen]
    if beside and blocks:  # two processes over every set's stages
        with plan_store.opened():
            try:
                return _evaluate_sets_beside(blocks, seed, optimum, n_optimal, clock, on_rows)
            finally:
                if own:
                    clock.close()
    rows = []
    try:
        with plan_store.opened():  # the planners' plans, kept for the next command (what they solved, also on Ctrl-C)
            for group, scenario in blocks:
                before = {stage: clock.seconds(scenario.name, stage) for stage in ("optimum", *group)}
                results = evaluate_subset(group, scenario, seed, progress, optimum, n_optimal, clock, address)
                took = {
                    stage: round(clock.seconds(scenario.name, stage) - seconds, 2) for stage, seconds in before.items()
                }
                for label, result in results.items():
                    rows.append(_set_row(scenario, label, result, took[label], took["optimum"]))
                if on_rows is not None:
                    on_rows(list(rows))
    finally:
        if own:
            clock.close()
    return rows


def _set_row(scenario: Scenario, label: str, result: RolloutResult, seconds: float, optimum_seconds: float
             ) -> dict[str, Any]:  # fmt: skip
    """The row of one policy on one scenario set (see :func:`evaluate_sets`)."""
    note = result.optimum_failures[0] if result.optimum_failures else ""
    drawn = scenario.T_cons is not None
    T_row = float("nan") if drawn else result.params.T_con  # nan: drawn per episode, in T_con_range
    T_range = list(result.params.T_con_range or (min(scenario.T_cons), max(scenario.T_cons))) if drawn else None  # type: ignore[arg-type]
    return {"scenario": scenario.name, "T_con": T_row, "policy": label, **result.summary(), "optimum_note": note,
            "T_con_range": T_range, "seconds": seconds, "optimum_seconds": optimum_seconds}  # fmt: skip


def _evaluate_sets_beside(
    blocks: list[tuple[dict[str, Policy | str], Scenario]],
    seed: int,
    optimum: str,
    n_optimal: int | None,
    clock: StageClock,
    on_rows: Callable[[list[dict[str, Any]]], None] | None,
) -> list[dict[str, Any]]:
    """:func:`evaluate_sets` on two processes, its (policies, set) ``blocks`` in the order of the rows: every (set,
    policy) rollout is one job of one queue, which a forked
    process (:class:`SideProcess`) and this one take in turn from its front, so that both cores work to the end,
    across the sets (a set's planner no longer waits for the set before to end). In each set the planners come first
    (the costliest first), then the agents, then the laws; this process solves the optima of a set before its first
    job of that set. The rows come set by set, as the jobs of a set are all done (``on_rows``: what an interrupted
    command still reports). Each rollout is the one :func:`evaluate` runs: the same numbers to the last digit."""
    units: list[dict[str, tuple[Policy | str, Scenario]]] = []
    chosen = [scenario for _, scenario in blocks]
    for policies, scenario in blocks:
        units.append({label: (policy, optimal_set(scenario, n_optimal) if label == "optimal" else scenario)
                      for label, policy in policies.items()})  # fmt: skip
    params = [EnvParams.from_kwargs(**split_env_kwargs(scenario.env_kwargs)[0]) for scenario in chosen]

    def cost(label: str, k: int) -> tuple[bool, bool, float]:
        policy, own = units[k][label]
        planner = label in PLANNERS
        estimate = estimated_seconds(label, own.size, max_steps(own, params[k]), own.name, cold=True)
        return not planner, isinstance(policy, str), -estimate

    order = [(k, label) for k in range(len(chosen)) for label in sorted(units[k], key=lambda label: cost(label, k))]
    side = SideProcess({key: (_rollout_one, (key[1], units[key[0]][key[1]][0], params[key[0]],
                                              units[key[0]][key[1]][1], False, seed)) for key in order})  # fmt: skip
    done: dict[tuple[int, str], tuple[RolloutResult, float]] = {}
    optima: dict[tuple[int, int], tuple[tuple[Any, list[str]], float]] = {}  # by (set, episodes): its seconds
    rows: list[dict[str, Any]] = []

    def solve_optima(k: int) -> None:  # the optima of set k (and of its shorter head for 'optimal'), once
        for own in {id(own): own for _, own in units[k].values()}.values():
            if (k, own.size) not in optima:
                before = clock.seconds(own.name, "optimum")
                found = _optimum(own, params[k], optimum, clock, own.name, False, None)
                optima[(k, own.size)] = (found, clock.seconds(own.name, "optimum") - before)

    def collect(finished: dict[Any, tuple[RolloutResult, float]], waited: float = 0.0) -> None:
        for (k, label), (result, seconds) in finished.items():
            own = units[k][label][1]
            clock.record(own.name, label, seconds, own.size, estimated_seconds(label, own.size, max_steps(own, params[k])), waited)  # fmt: skip
            waited = 0.0
            done[(k, label)] = (result, seconds)

    def run_here(key: tuple[int, str]) -> None:
        k, label = key
        policy, own = units[k][label]
        solve_optima(k)
        with clock.stage(own.name, label, estimated_seconds(label, own.size, max_steps(own, params[k])), own.size) as advance:  # fmt: skip

            def on_step(fraction: float) -> None:
                advance(fraction)
                collect(side.finished())

            began = time.perf_counter()
            result = _rollout_one(label, policy, params[k], own, False, seed, False, on_step)
        done[key] = (result, time.perf_counter() - began)

    try:
        for k, scenario in enumerate(chosen):
            keys = [(k, label) for label in units[k]]
            while any(key not in done for key in keys):
                key = side.take(first=True)
                if key is not None:
                    run_here(key)
                    continue
                solve_optima(k)
                began = time.perf_counter()
                finished = side.results(set(keys))  # nothing waits: the rest of this set runs beside
                collect(finished, time.perf_counter() - began)
            solve_optima(k)
            for label in units[k]:
                result, seconds = done[(k, label)]
                own = units[k][label][1]
                result.optimal_energy, result.optimum_failures = optima[(k, own.size)][0]
                rows.append(_set_row(scenario, label, result, round(seconds, 2),
                                     round(optima[(k, scenario.size)][1], 2)))  # fmt: skip
            if on_rows is not None:
                on_rows(list(rows))
    finally:
        side.close()
    return rows


def optimal_set(scenario: Scenario, n_optimal: int | None) -> Scenario:
    """The episodes ``optimal`` runs on: a disturbed set's first ``n_optimal`` (where it has more), else the set."""
    from train.evaluation.disturbance_sets import ROBUSTNESS_SETS

    n = n_optimal
    if n is None or scenario.name not in ROBUSTNESS_SETS or scenario.size <= n:
        return scenario
    return replace(scenario, starts=scenario.starts[:n], goals=scenario.goals[:n], labels=scenario.labels[:n],
                   T_cons=None if scenario.T_cons is None else scenario.T_cons[:n])  # fmt: skip


def running_beside(policies: dict[str, Policy | str], address: str | None = None) -> frozenset[str]:
    """The policies :func:`evaluate` runs in a second process while it runs the costliest planner (by its cold cost
    per episode): every other, where there is a planner and a second process is usable (:func:`side_process_usable`),
    not on Ray; else none. :func:`evaluate_sets` then runs every set's stages on both processes."""
    planners = [label for label in policies if label in PLANNERS]
    if address is None and planners and side_process_usable():
        here = max(planners, key=lambda label: sum(COLD_EPISODE_SECONDS.get(label, {}).values()))
        return frozenset(label for label in policies if label != here)
    return frozenset()


def planned_seconds(
    policies: dict[str, Policy | str], scenarios: list[Scenario], optimum: str, n_optimal: int | None
) -> list[tuple[tuple[str, str], float]]:
    """The estimated wall seconds of each stage of evaluating ``policies`` on ``scenarios`` (the optima not cached
    yet, then each policy on each set), as ((scenario, stage), seconds) in the order they run: what the bar plans, so
    that its time left spans every stage."""
    # the planners solve every plan (minutes, where a second run takes seconds); without planners, no store to look at
    cold = not PLANNERS.isdisjoint(policies) and not plan_store.has_plans()
    todo: set[tuple[str, str]] = set()
    planned: list[tuple[tuple[str, str], float]] = []
    for scenario in scenarios:
        params = EnvParams.from_kwargs(**split_env_kwargs(scenario.env_kwargs)[0])
        if optimum != "none":
            new = missing_optima(params, scenario.starts, scenario.goals, scenario.T_cons, heading=optimum == "pose")
            planned.append(((scenario.name, "optimum"), len(new - todo) * PLAN_SECONDS))
            todo |= new
        for label in policies:
            episodes = optimal_set(scenario, n_optimal).size if label == "optimal" else scenario.size
            estimate = estimated_seconds(label, episodes, max_steps(scenario, params), scenario.name, cold)
            planned.append(((scenario.name, label), estimate))
    return planned


def max_steps(scenario: Scenario, params: EnvParams) -> int:
    """The most steps a rollout of ``scenario`` takes: to the horizon of its longest T_con."""
    T_con = params.T_con if scenario.T_cons is None else float(max(scenario.T_cons))
    return math.ceil(params.horizon_factor * T_con / params.dt)


def evaluate_subset(
    policies: dict[str, Policy | str],
    scenario: Scenario,
    seed: int,
    progress: bool,
    optimum: str,
    n_optimal: int | None,
    clock: StageClock | None = None,
    address: str | None = None,
) -> dict[str, RolloutResult]:
    """:func:`evaluate`, with ``optimal`` on the first ``n_optimal`` episodes where the set is a disturbed one."""
    head = optimal_set(scenario, n_optimal)
    if "optimal" not in policies or head is scenario:
        return evaluate(policies, scenario, seed=seed, progress=progress, optimum=optimum, clock=clock, address=address)
    others = evaluate({k: v for k, v in policies.items() if k != "optimal"}, scenario, seed=seed, progress=progress,
                      optimum=optimum, clock=clock, address=address)  # fmt: skip
    optimal = evaluate({"optimal": policies["optimal"]}, head, seed=seed, progress=progress, optimum=optimum,
                       clock=clock, address=address)  # fmt: skip
    return {label: optimal["optimal"] if label == "optimal" else others[label] for label in policies}
