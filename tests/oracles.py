"""Second, naive computations of the measures the benchmark publishes: the oracles of tests/test_oracles*.py.

Each oracle plays *one* robot's episode through the env's own ``step`` (``gymnasium.make`` of the env id, one
``reset`` with the episode's start, goal and T_con), records every step, and computes each measure from its
definition in the docstrings in a plain loop over the recorded steps:

- in time: v0 and v1 end an episode on arrival, and it is in time when the robot arrived (within the tolerances)
  at or before T_con; v2 holds every episode to T_con, and it is in time when the robot is at the goal *at* T_con
  (not when it passed the goal earlier, nor when it left the arena);
- the constraint's cost: the env's ``info["cost"]`` summed over the episode is 1 where it is not in time, else 0;
- E/opt: the episode's energy over the minimum energy to its goal *pose* by its *own* T_con, over the episodes in
  time that have an optimum; final heading: |psi - psi_d| at the episode's end; energy: the sum of
  (u^2 + omega^2) dt; return: the sum of the env's rewards; the peaks of |u| and |omega|; the path: the sum of |u| dt;
- per set: the mean over its episodes; over seeds: the interquartile mean (the middle half after sorting) and the
  2.5 and 97.5 percentiles of the bootstrapped IQMs; the tables' cells, formatted from those.

Nothing here calls the pipeline's code that computes a measure (train.evaluation.rollout, train.reporting). A
disagreement is reported as the field, the episode (or set, or seed) and both values (:func:`assert_same`).

A new measure (say, a constraint cost's violation rate) goes in as a field of :class:`Measures` computed in
:func:`measure` from the recorded :class:`Step` (add what it needs to :class:`Step` from the step's info), a key
of :func:`set_metrics`, and a line of :data:`ROLLOUT_FIELDS` or the benchmark's METRICS that it is compared with.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import gymnasium
import numpy as np

import dwr_gym

HELD = "DWRPointStabilization-v2"
#: Relative tolerance of a float compared with the pipeline's: the single env computes one robot in Python floats,
#: the batched rollout in numpy arrays, and sums run in another order.
RTOL = 1e-9


@dataclass
class Step:
    """One recorded step of one robot: the time after it, the world pose, the velocities the robot had, the reward,
    the episode's end flags, and the env's running energy from its info."""

    time: float
    x: float
    y: float
    psi: float
    u: float
    omega: float
    reward: float
    terminated: bool
    truncated: bool
    energy_info: float
    cost: float  # the env's info["cost"]: the constraint's cost of this step


@dataclass
class Episode:
    """One robot's recorded episode on ``env_id``: its start and goal (world frame), T_con and the env's params."""

    env_id: str
    start: tuple[float, float, float]
    goal: tuple[float, float, float]
    T_con: float
    params: Any
    steps: list[Step] = field(default_factory=list)


class Recorder:
    """A policy (stable-baselines3's ``predict``) that records the actions it returns, one list per rollout (a
    rollout's first call has every ``episode_start`` True): what the oracle replays, one robot at a time, through the
    env's own ``step``. (Replaying the actions rather than calling the policy again keeps the two computations on one
    trajectory: the batched and the single env round their float64 arithmetic differently in the last bits, which
    a closed loop through float32 observations would amplify, and v0 and v1's shaping jumps with the azimuth near
    the goal.)"""

    def __init__(self, policy: Any) -> None:
        self.policy = policy
        self.rollouts: list[list[np.ndarray]] = []
        self.controller = getattr(policy, "controller", None)

    def predict(self, obs: Any, state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[Any, Any]:  # fmt: skip
        if episode_start is None or np.all(episode_start):
            self.rollouts.append([])
        actions, state = self.policy.predict(obs, state=state, episode_start=episode_start, deterministic=deterministic)
        self.rollouts[-1].append(np.array(actions, dtype=np.float32).reshape(-1, 2))
        return actions, state

    def robot(self, rollout: int, index: int) -> list[np.ndarray]:
        """The actions robot ``index`` of rollout ``rollout`` was given, step by step."""
        return [batch[index] for batch in self.rollouts[rollout]]


def play(
    env_id: str,
    actions: list[np.ndarray],
    start: Sequence[float],
    goal: Sequence[float],
    T_con: float,
    env_kwargs: dict[str, Any] | None = None,
) -> Episode:
    """Play one episode of ``env_id`` (its registered keywords, then ``env_kwargs``) from ``start`` to ``goal`` with
    prescribed time ``T_con`` and these ``actions``, recording every step of the env's own ``step``."""
    env = gymnasium.make(env_id, **(env_kwargs or {}))
    start3, goal3 = (tuple(float(v) for v in start), tuple(float(v) for v in goal))
    env.reset(seed=0, options={"start": start3, "goal": goal3, "T_con": float(T_con)})
    episode = Episode(env_id, start3, goal3, float(T_con), env.unwrapped.params)  # type: ignore[attr-defined]
    for action in actions:
        _, reward, terminated, truncated, info = env.step(action)
        x, y, psi = (float(v) for v in info["pose"])
        episode.steps.append(Step(float(info["time"]), x, y, psi, float(info["linear_velocity"]),
                                  float(info["angular_velocity"]), float(reward), terminated, truncated,
                                  float(info["energy"]), float(info["cost"])))  # fmt: skip
        if terminated or truncated:
            env.close()
            return episode
    raise AssertionError(
        f"{env_id} from {start3} by T_con {T_con}: the pipeline's rollout gave {len(actions)} "
        "actions, and the env's episode had not ended after them"
    )


def wrap(angle: float) -> float:
    """An angle in [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def distance(episode: Episode, step: Step) -> float:
    """The robot's distance to its goal after ``step``."""
    return math.hypot(step.x - episode.goal[0], step.y - episode.goal[1])


def heading_error(episode: Episode, step: Step) -> float:
    """|psi - psi_d| after ``step``, in [0, pi]."""
    return abs(wrap(step.psi - episode.goal[2]))


def at_goal(episode: Episode, step: Step) -> bool:
    """Within the goal's tolerances (the distance, and the heading where the env has a heading tolerance)."""
    p = episode.params
    inside = distance(episode, step) <= p.goal_tolerance
    return inside and (p.heading_tolerance is None or heading_error(episode, step) <= p.heading_tolerance)


def by_T_con(episode: Episode, step: Step) -> bool:
    """Whether ``step`` ends at or before T_con (the clock counts whole control periods)."""
    return step.time <= episode.T_con + 1e-9


@dataclass
class Measures:
    """What the oracle measures of one episode."""

    in_time: bool
    arrived: bool
    arrival_time: float  # NaN where the robot never arrived
    final_distance: float
    final_heading: float
    energy: float
    episode_return: float
    left_arena: bool
    reached_and_left: bool  # at the goal at some step before T_con, not at its end
    late_arrival: bool  # first at the goal after T_con
    cost: float  # the env's summed info["cost"] (the deadline's violation: 1 exactly where not in time)
    peak_linear_velocity: float  # max |u| over the steps [m/s]
    peak_angular_velocity: float  # max |omega| over the steps [rad/s]
    path_length: float  # the sum of |u| dt [m]


def measure(episode: Episode) -> Measures:
    """Every measure of one episode, from its recorded steps and the definitions (module docstring)."""
    held = episode.env_id.endswith("-v2")
    arrival_time = math.nan
    in_time = False
    energy = 0.0
    total = 0.0
    reached_before_end = False
    for index, step in enumerate(episode.steps):
        energy += (step.u * step.u + step.omega * step.omega) * episode.params.dt
        total += step.reward
        here = at_goal(episode, step)
        if here and math.isnan(arrival_time):
            arrival_time = step.time
        last = index == len(episode.steps) - 1
        if here and not last and by_T_con(episode, step):
            reached_before_end = True
        if held:  # v2: at the goal at T_con itself, the last whole control period by T_con (an episode that left
            # the arena ends before it)
            at_T_con = last and episode.T_con - episode.params.dt + 1e-9 < step.time <= episode.T_con + 1e-9
            in_time = in_time or (here and at_T_con)
        else:  # v0, v1: arrived at or before T_con
            in_time = in_time or (here and by_T_con(episode, step))
    end = episode.steps[-1]
    return Measures(
        in_time=in_time,
        arrived=not math.isnan(arrival_time),
        arrival_time=arrival_time,
        final_distance=distance(episode, end),
        final_heading=heading_error(episode, end),
        energy=energy,
        episode_return=total,
        left_arena=distance(episode, end) > episode.params.arena_radius,
        reached_and_left=reached_before_end and not in_time,
        late_arrival=not math.isnan(arrival_time) and arrival_time > episode.T_con + 1e-9,
        cost=sum(step.cost for step in episode.steps),
        peak_linear_velocity=max(abs(step.u) for step in episode.steps),
        peak_angular_velocity=max(abs(step.omega) for step in episode.steps),
        path_length=sum(abs(step.u) * episode.params.dt for step in episode.steps),
    )


def v2_rewards(episode: Episode) -> list[float]:
    """v2's reward of each step from its definition (dwr_gym's V2_DEFAULTS): the progress d_before - d_after (the
    distance as potential, 0 at the end), -energy_weight (u^2 + omega^2) dt; where the episode ends, the miss
    -terminal_distance_weight d (inside the tolerance too), the heading heading_weight (cos psi - 1), the arrival
    bonus at the goal at T_con, and on leaving the arena its penalty plus the energy of the rest at full commands."""
    p = episode.params
    before = math.hypot(episode.start[0] - episode.goal[0], episode.start[1] - episode.goal[1])
    rewards = []
    for step in episode.steps:
        d = distance(episode, step)
        ended = step.terminated
        reward = before - (0.0 if ended else d) - p.energy_weight * (step.u**2 + step.omega**2) * p.dt
        if ended:
            psi = wrap(step.psi - episode.goal[2])
            reward += -p.terminal_distance_weight * d + p.heading_weight * (math.cos(psi) - 1.0)
            if at_goal(episode, step) and by_T_con(episode, step):
                reward += p.arrival_bonus
            if d > p.arena_radius:
                rest = math.floor(episode.T_con / p.dt + 1e-9) - round(step.time / p.dt)  # the periods left by T_con
                reward -= p.arena_penalty + rest * p.dt * p.energy_weight * (p.u_max**2 + p.omega_max**2)
        rewards.append(reward)
        before = d
    return rewards


# --- the optimum -------------------------------------------------------------------------------------------------


def goal_frame(start: Sequence[float], goal: Sequence[float]) -> tuple[float, float, float]:
    """The start pose in its goal's frame."""
    dx, dy = start[0] - goal[0], start[1] - goal[1]
    c, s = math.cos(goal[2]), math.sin(goal[2])
    return c * dx + s * dy, -s * dx + c * dy, wrap(start[2] - goal[2])


def stand_in_optimum(start: Sequence[float], goal: Sequence[float], T_con: float, heading: bool) -> float:
    """A stand-in for the minimum energy of one episode: a known function of its goal-frame start, its own T_con and
    whether the goal's heading counts, so that a test sees *which* optimum each E/opt divides by (the CasADi solve
    itself is tested in test_optimal.py)."""
    x, y, psi = goal_frame(start, goal)
    return (0.05 + x * x + y * y + (0.3 * abs(psi) if heading else 0.0)) * 4.0 / T_con


def stand_in_optimal_energies(params: Any, starts: Any, goals: Any, T_cons: Any = None, *, heading: bool = True,
                              **_: Any) -> tuple[np.ndarray, list[str]]:  # fmt: skip
    """:func:`train.evaluation.optimum.optimal_energies` with :func:`stand_in_optimum` in place of the solve."""
    T = [params.T_con] * len(starts) if T_cons is None else list(T_cons)
    values = [stand_in_optimum(s, g, float(t), heading) for s, g, t in zip(starts, goals, T, strict=True)]
    return np.array(values), []


def use_stand_in_optimum(monkeypatch: Any) -> None:
    """Make the pipeline's evaluation use :func:`stand_in_optimal_energies` (nothing solved, nothing cached)."""
    import train.evaluation.evaluate as evaluate

    monkeypatch.setattr(evaluate, "optimal_energies", stand_in_optimal_energies)
    monkeypatch.setattr(evaluate, "missing_optima", lambda *args, **kwargs: set())


# --- the sets ----------------------------------------------------------------------------------------------------


def draw_set(env_id: str, n: int, seed: int, T_con: float | None = None) -> list[tuple[tuple[float, ...], float]]:
    """The benchmark's set of ``n`` episodes of ``env_id`` drawn with ``seed`` (docs/rl-benchmark.md): n start poses
    (each three uniforms of one generator), then each episode's T_con uniform in the env's range from the same
    generator, or ``T_con`` for all; the goal is the origin. Returns (start, T_con) per episode."""
    from dwr_gym import core
    from train.env_ids import env_keywords

    kwargs = env_keywords(env_id)
    if T_con is not None:
        kwargs = {**kwargs, "T_con": T_con, "T_con_range": None}
    params = dwr_gym.EnvParams.from_kwargs(**kwargs)
    rng = np.random.default_rng(seed)
    starts = [tuple(core.sample_start(rng, params)) for _ in range(n)]
    if T_con is None and params.T_con_range is None:  # (v0: one T_con for every episode)
        T_con = params.T_con
        return [(start, float(T_con)) for start in starts]
    T_cons = [T_con] * n if T_con is not None else rng.uniform(*params.T_con_range, size=n).tolist()
    return list(zip(starts, [float(t) for t in T_cons], strict=True))


def play_set(env_id: str, recorder: Recorder, rollout: int, episodes: list[tuple[tuple[float, ...], float]],
             fixed: bool) -> list[Episode]:  # fmt: skip
    """Every episode of a drawn set with the actions of the recorder's ``rollout``, one robot at a time (a fixed
    T_con set is made with that T_con, as the benchmark's per-T_con sets are)."""
    if len(recorder.rollouts[rollout][0]) != len(episodes):
        raise AssertionError(f"rollout {rollout}: {len(recorder.rollouts[rollout][0])} robots, the set has "
                             f"{len(episodes)} episodes")  # fmt: skip
    played = []
    for index, (start, T_con) in enumerate(episodes):
        kwargs = {"T_con": T_con, "T_con_range": None} if fixed else None
        played.append(play(env_id, recorder.robot(rollout, index), (*start,), (0.0, 0.0, 0.0), T_con, kwargs))
    return played


def set_metrics(episodes: list[Episode], optimum: Callable[[Episode], float] | None = None) -> dict[str, Any]:
    """The benchmark's metrics of a set (train.evaluation.benchmark.METRICS' names) and its mean return: means over
    the episodes; E/opt over those in time with a positive optimum (None when there is none)."""
    measures = [measure(e) for e in episodes]
    n = len(measures)
    ratios = []
    for episode, m in zip(episodes, measures, strict=True):
        if m.in_time and optimum is not None:
            best = optimum(episode)
            if math.isfinite(best) and best > 0.0:
                ratios.append(m.energy / best)
    return {
        "in_time": sum(m.in_time for m in measures) / n,
        "energy_ratio": sum(ratios) / len(ratios) if ratios else None,
        "final_heading": sum(m.final_heading for m in measures) / n,
        "energy": sum(m.energy for m in measures) / n,
        "return": sum(m.episode_return for m in measures) / n,
    }


def pose_optimum(episode: Episode) -> float:
    """The stand-in optimum of an episode: to its goal pose, by its own T_con."""
    return stand_in_optimum(episode.start, episode.goal, episode.T_con, heading=True)


# --- over seeds ----------------------------------------------------------------------------------------------------


def iqm(values: Sequence[float]) -> float:
    """The interquartile mean: sorted, a quarter (rounded down) dropped at each end, the rest averaged."""
    ordered = sorted(values)
    cut = len(ordered) // 4
    middle = ordered[cut : len(ordered) - cut]
    return sum(middle) / len(middle)


def percentile(values: Sequence[float], q: float) -> float:
    """The q-th percentile, linear between the closest ranks (numpy's default)."""
    ordered = sorted(values)
    rank = q / 100.0 * (len(ordered) - 1)
    low = math.floor(rank)
    high = min(low + 1, len(ordered) - 1)
    return ordered[low] + (rank - low) * (ordered[high] - ordered[low])


def iqm_interval(values: Sequence[float | None], seed: int = 0, reps: int = 2000) -> dict[str, Any]:
    """The IQM of the finite values and the 95 % percentile interval of the IQMs of ``reps`` resamples with
    replacement (the resampled indices drawn as one (reps, n) array of numpy's generator of ``seed``)."""
    data = [float(v) for v in values if v is not None and math.isfinite(v)]
    if not data:
        return {"iqm": None, "low": None, "high": None, "n": 0}
    draws = np.random.default_rng(seed).integers(0, len(data), (reps, len(data)))
    boots = [iqm([data[int(i)] for i in row]) for row in draws]
    return {"iqm": iqm(data), "low": percentile(boots, 2.5), "high": percentile(boots, 97.5), "n": len(data)}


def cell(interval: dict[str, Any], digits: int) -> str:
    """A table's cell: IQM [low, high], or '-' where undefined."""
    if interval["iqm"] is None:
        return "-"
    return f"{interval['iqm']:.{digits}f} [{interval['low']:.{digits}f}, {interval['high']:.{digits}f}]"


# --- comparing -----------------------------------------------------------------------------------------------------


def same(expected: Any, got: Any) -> bool:
    """Equal, or both floats equal to RTOL (None and NaN alike)."""
    if expected is None or got is None or (isinstance(expected, float) and math.isnan(expected)):
        return (expected is None or (isinstance(expected, float) and math.isnan(expected))) and (
            got is None or (isinstance(got, float) and math.isnan(got)))  # fmt: skip
    if isinstance(expected, bool) or isinstance(got, bool | np.bool_):
        return bool(expected) == bool(got)
    if isinstance(expected, float | int):
        return math.isclose(float(expected), float(got), rel_tol=RTOL, abs_tol=1e-9)
    return bool(expected == got)


def assert_same(rows: list[tuple[str, str, Any, Any]]) -> None:
    """Fail, listing every (where, field, oracle's value, pipeline's value) that disagrees."""
    wrong = [f"{where}: {name}: oracle {expected!r}, pipeline {got!r}" for where, name, expected, got in rows
             if not same(expected, got)]  # fmt: skip
    assert not wrong, f"{len(wrong)} of {len(rows)} values disagree:\n" + "\n".join(wrong[:40])


#: RolloutResult's per-episode arrays -> the oracle's Measures field they must equal
ROLLOUT_FIELDS: dict[str, str] = {
    "success": "in_time",
    "arrived": "arrived",
    "arrival_time": "arrival_time",
    "final_distance": "final_distance",
    "final_heading_error": "final_heading",
    "energy": "energy",
    "episode_return": "episode_return",
    "left_arena": "left_arena",
    "peak_linear_velocity": "peak_linear_velocity",
    "peak_angular_velocity": "peak_angular_velocity",
    "path_length": "path_length",
}


def rollout_rows(where: str, episodes: list[Episode], result: Any) -> list[tuple[str, str, Any, Any]]:
    """(episode, field, oracle, pipeline) of every per-episode field of a RolloutResult."""
    rows = []
    for i, episode in enumerate(episodes):
        m = measure(episode)
        for name, mine in ROLLOUT_FIELDS.items():
            rows.append((f"{where} episode {i} (T_con {episode.T_con:.3f})", name, getattr(m, mine),
                         getattr(result, name)[i].item()))  # fmt: skip
    return rows


def metric_rows(where: str, expected: dict[str, Any], got: dict[str, Any]) -> list[tuple[str, str, Any, Any]]:
    """(set, metric, oracle, pipeline) of the metrics the pipeline wrote."""
    return [(where, name, expected[name], got[name]) for name in got if name in expected]
