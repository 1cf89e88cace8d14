"""The batched rollout's edges and the scenario sets' arguments: a discounted return, a robot that ends at its first
step, the fraction of the steps each ``on_step`` receives, the bar, the seed, bad shapes and sizes, E/opt where the
optimum is zero, and the controllers made for a scenario."""

from __future__ import annotations

import dataclasses
import re
from typing import Any

import numpy as np
import pytest

from dwr_gym.params import EnvParams
from tests import oracles
from tests.test_oracles import V1, Scripted
from train.env_ids import env_keywords
from train.evaluation.rollout import rollout
from train.evaluation.scenarios import controller_for, make_scenario


class Creep:
    """A tenth of u_max straight ahead: 2.5 mm a step at the default dt, so a robot at its goal stays inside the 1 cm
    tolerance for its first step."""

    def predict(
        self, observation: Any, state: Any = None, episode_start: Any = None, deterministic: bool = True
    ) -> tuple[Any, Any]:
        return np.tile(np.array([0.1, 0.0], np.float32), (len(observation), 1)), None


#: one robot at its goal (arrives at its first step), one 0.5 m behind it (arrives at 9.8 s, step 196)
STARTS = np.array([[0.0, 0.0, 0.0], [-0.5, 0.0, 0.0]])


def test_a_robot_that_ends_at_its_first_step_has_its_one_command_change_as_its_rate() -> None:
    result = rollout(Creep(), EnvParams(), STARTS, np.zeros((2, 3)))
    np.testing.assert_allclose(result.arrival_time, [0.05, 9.8])
    # one change of the command, 0 -> 0.05 m/s in 0.05 s (1 m/s^2), over the steps each robot took: 1 and 196
    np.testing.assert_allclose(result.command_rate_rms, [1.0, np.sqrt(1.0 / 196)], rtol=1e-6)
    np.testing.assert_allclose(result.velocity_rate_rms, result.command_rate_rms)  # the ideal robot does as commanded


class Constant:
    """The same action for every robot at every step."""

    def __init__(self, u: float, omega: float) -> None:
        self.action = np.array([u, omega], np.float32)

    def predict(
        self, observation: Any, state: Any = None, episode_start: Any = None, deterministic: bool = True
    ) -> tuple[Any, Any]:
        return np.tile(self.action, (len(observation), 1)), None


def test_actions_beyond_the_action_space_are_measured_as_the_env_clips_them() -> None:
    """(3, -2.5) is (1, -1) to the env: the same command rate, peaks, path and energy as (1, -1) itself."""
    beyond = rollout(Constant(3.0, -2.5), EnvParams(), STARTS, np.zeros((2, 3)))
    clipped = rollout(Constant(1.0, -1.0), EnvParams(), STARTS, np.zeros((2, 3)))
    for name in ("command_rate_rms", "velocity_rate_rms", "peak_linear_velocity", "peak_angular_velocity",
                 "path_length", "energy"):  # fmt: skip
        np.testing.assert_array_equal(getattr(beyond, name), getattr(clipped, name), err_msg=name)
    assert clipped.command_rate_rms[0] > 0.0


def test_on_step_receives_the_fraction_of_the_horizons_steps_done_before_each_step() -> None:
    fractions: list[float] = []
    rollout(Creep(), EnvParams(), STARTS, np.zeros((2, 3)), on_step=fractions.append)
    horizon = 600  # 1.5 x 20 s / 0.05 s
    assert fractions == pytest.approx([k / horizon for k in range(196)]), (len(fractions), fractions[:3])


def test_a_discounted_return_is_the_envs_rewards_discounted_step_by_step() -> None:
    fixed = {"T_con": 10.0, "T_con_range": None}
    kwargs = {**env_keywords(V1), **fixed}
    starts = np.array([[-0.3, 0.1, 0.2], [0.4, -0.2, 1.0], [0.9, 0.5, -2.0]])
    policy = oracles.Recorder(Scripted(0.3))
    result = rollout(policy, EnvParams.from_kwargs(**kwargs), starts, np.zeros_like(starts), discount=0.9)
    for i, start in enumerate(starts):
        episode = oracles.play(V1, policy.robot(0, i), start, (0.0, 0.0, 0.0), 10.0, fixed)
        expected = sum(0.9**k * step.reward for k, step in enumerate(episode.steps))
        assert result.episode_return[i] == pytest.approx(expected, rel=1e-9, abs=1e-12), (i, len(episode.steps))
    undiscounted = rollout(Scripted(0.3), EnvParams.from_kwargs(**kwargs), starts, np.zeros_like(starts))
    for i, start in enumerate(starts):  # the default: the plain sum
        episode = oracles.play(V1, policy.robot(0, i), start, (0.0, 0.0, 0.0), 10.0, fixed)
        expected = sum(step.reward for step in episode.steps)
        assert undiscounted.episode_return[i] == pytest.approx(expected, rel=1e-9, abs=1e-12), i


def test_starts_and_goals_given_as_integers_roll_out_as_their_floats() -> None:
    as_floats = rollout(Creep(), EnvParams(), np.array([[-1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    as_ints = rollout(Creep(), EnvParams(), [[-1, 0, 0]], [[0, 1, 0]])  # type: ignore[arg-type]
    for field in ("arrival_time", "final_distance", "final_heading_error", "energy", "path_length"):
        np.testing.assert_array_equal(getattr(as_ints, field), getattr(as_floats, field), err_msg=field)


def test_a_rollout_is_quiet_unless_asked_then_its_bar_counts_steps_and_is_erased(
    capsys: pytest.CaptureFixture[str],
) -> None:
    rollout(Creep(), EnvParams(), STARTS, np.zeros((2, 3)))
    assert capsys.readouterr().err == ""
    rollout(Creep(), EnvParams(), STARTS, np.zeros((2, 3)), progress=True)
    bar = capsys.readouterr().err
    assert bar.startswith("\rrollout: ") and "step/s" in bar, repr(bar[:120])
    assert not bar.endswith("\n") and bar.rstrip(" \r").endswith("]"), repr(bar[-120:])  # erased: no line left


def test_a_rollouts_default_seed_is_0() -> None:
    noisy = EnvParams(observation_noise=0.01, actuation_noise=0.05)
    energies = {seed: rollout(Creep(), noisy, STARTS, np.zeros((2, 3)), seed=seed).energy for seed in (0, 1)}
    default = rollout(Creep(), noisy, STARTS, np.zeros((2, 3))).energy
    np.testing.assert_array_equal(default, energies[0])
    assert not np.array_equal(energies[0], energies[1]), energies


@pytest.mark.parametrize(
    ("starts", "goals"),
    [(np.zeros(3), np.zeros(3)), (np.zeros((2, 4)), np.zeros((2, 4))), (np.zeros((2, 3)), np.zeros((3, 3)))],
    ids=["one-pose", "four-columns", "more-goals"],
)
def test_starts_and_goals_other_than_two_n_by_3_arrays_are_refused_naming_their_shapes(
    starts: np.ndarray, goals: np.ndarray
) -> None:
    message = f"starts {starts.shape} and goals {goals.shape} are invalid: expected two (N, 3) arrays"
    with pytest.raises(ValueError, match=re.escape(message)):
        rollout(Creep(), EnvParams(), starts, goals)


def test_e_opt_is_nan_where_the_episode_was_late_or_its_optimum_is_zero_or_unknown() -> None:
    base = rollout(Creep(), EnvParams(), np.zeros((5, 3)), np.zeros((5, 3)))
    assert base.energy_ratio().shape == (5,) and np.isnan(base.energy_ratio()).all()  # no optimum asked for
    plain = base.summary()
    assert (
        plain["energy_ratio_episodes"] == 0.0
        and np.isnan([plain["energy_ratio_mean"], plain["optimal_energy_mean"]]).all()
    )
    result = dataclasses.replace(
        base,
        success=np.array([True, True, True, False, True]),
        energy=np.array([0.1, 1.0, 3.0, 3.0, 3.0]),
        optimal_energy=np.array([0.0, 0.5, 2.0, 2.0, np.nan]),
    )
    np.testing.assert_array_equal(result.energy_ratio(), [np.nan, 2.0, 1.5, np.nan, np.nan])
    summary = result.summary()
    assert summary["energy_ratio_episodes"] == 2.0 and summary["energy_ratio_mean"] == 1.75
    assert summary["energy_ratio_max"] == 2.0
    assert summary["optimal_energy_mean"] == pytest.approx(4.5 / 4)  # over the episodes with an optimum


class Freezes:
    """A planning controller's ``freeze``: the robots whose episodes ended, after each step."""

    def __init__(self) -> None:
        self.masks: list[list[bool]] = []

    def freeze(self, ended: np.ndarray) -> None:
        self.masks.append(ended.tolist())


def test_a_planning_controller_is_told_after_each_step_which_robots_episodes_ended() -> None:
    policy = Creep()
    policy.controller = Freezes()  # type: ignore[attr-defined]
    rollout(policy, EnvParams(), STARTS, np.zeros((2, 3)))
    masks = policy.controller.masks  # type: ignore[attr-defined]
    assert len(masks) == 196 and masks[0] == [True, False] and masks[-1] == [True, True], (len(masks), masks[:2])
    assert masks[-2] == [True, False]  # robot 1 arrives at the last step


@pytest.mark.parametrize("n", [0, -1, True, 2.5, "3"])
def test_a_random_set_of_a_bad_size_is_refused_naming_it(n: Any) -> None:
    for name in ("random", "fault"):
        with pytest.raises(ValueError, match=re.escape(f"n={n!r} is invalid: expected an integer >= 1")):
            make_scenario(name, n=n)
    assert make_scenario("random", n=1).size == make_scenario("fault", n=1).size == 1


def test_a_controller_made_for_a_scenario_takes_the_envs_T_con_dt_and_limits_the_sets_gains_then_overrides() -> None:
    params = EnvParams(T_con=30.0, dt=0.1, u_max=0.3, omega_max=1.5)
    fig7 = make_scenario("paper-fig7")
    ptc = controller_for("ptc", fig7, params).params
    assert (ptc.T_con, ptc.K1, ptc.K2, ptc.K) == (30.0, 2.5, 40.0, 1.2), ptc
    conventional = controller_for("conventional-ptc", fig7, params).params
    assert (conventional.T_con, conventional.K1, conventional.K2) == (30.0, 2.5, 40.0), conventional
    assert controller_for("fabregas", fig7, params).params.dt == 0.1
    for name in ("optimal", "robust-pt"):
        planner = controller_for(name, fig7, params).params
        assert (planner.T_con, planner.dt, planner.u_max, planner.omega_max) == (30.0, 0.1, 0.3, 1.5), planner
    assert controller_for("ptc", fig7, params, K1=3.0).params.K1 == 3.0  # the caller's keywords win


def test_a_robot_standing_on_the_arenas_bound_has_not_left_it() -> None:
    """The env ends an episode beyond the arena's radius, not on it: a robot standing still there runs to the horizon
    and is counted as missing its goal, not as gone."""

    class Still(Creep):
        def predict(self, observation: Any, *args: Any, **kwargs: Any) -> tuple[Any, Any]:
            return np.zeros((len(observation), 2), np.float32), None

    params = EnvParams(T_con=2.0)
    result = rollout(Still(), params, np.array([[-params.arena_radius, 0.0, 0.0]]), np.zeros((1, 3)))
    assert result.final_distance[0] == params.arena_radius and not result.left_arena[0] and not result.success[0]


def test_the_paper_sets_keep_their_own_T_con_whatever_range_is_asked() -> None:
    for name, T_con in (("paper-fig5", 20.0), ("paper-fig7", 70.0)):
        scenario = make_scenario(name, env_kwargs={"T_con_range": (5.0, 9.0), "dt": 0.01})
        assert scenario.env_kwargs == {"T_con": T_con, "dt": 0.01} and scenario.T_cons is None, scenario.env_kwargs
        assert scenario.name == name


def test_a_random_set_has_100_episodes_drawn_with_seed_0_by_default() -> None:
    default = make_scenario("random")
    assert default.size == 100 and default.name == "random" and default.labels == ()
    np.testing.assert_array_equal(default.starts, make_scenario("random", n=100, seed=0).starts)


def test_with_observation_noise_the_first_observation_is_noisy_too() -> None:
    seen: list[np.ndarray] = []

    class Looks(Creep):
        def predict(self, observation: Any, *args: Any, **kwargs: Any) -> tuple[Any, Any]:
            seen.append(np.array(observation))
            return super().predict(observation)

    rollout(Looks(), EnvParams(observation_noise=0.01), STARTS, np.zeros((2, 3)))
    noisy = seen[0]
    seen.clear()
    rollout(Looks(), EnvParams(), STARTS, np.zeros((2, 3)))
    assert not np.allclose(noisy, seen[0]), (noisy, seen[0])
