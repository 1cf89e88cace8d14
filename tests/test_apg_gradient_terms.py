"""The terms APG adds to the gradient only (``dwr-gym train --algo apg --backend jax``): the near misses' clip and
weight, the hold window before T_con (``hold_steps``, ``hold_fraction``) with its heading term, and the short T_con of
``short_T_con_share``; the return each update reports stays v2's."""

from __future__ import annotations

from typing import Any

import pytest

from train.learning.jitted.apg_settings import APGSettings

jax = pytest.importorskip("jax")


def short_apg(**kwargs: Any) -> Any:
    """An APG of 4 episodes an update on v2 at T_con 2-2.2 s (a network of 8 units, the state's clip 0.25)."""
    from dwr_gym.jax_env import make_gymnax_env
    from train.learning.jitted.apg import JaxAPG

    env, params = make_gymnax_env("DWRPointStabilization-v2", T_con_range=[2.0, 2.2])
    return JaxAPG(APGSettings(episodes=4, net_arch=(8,), state_grad_clip=0.25, **kwargs), env, params)


def test_a_near_miss_is_clipped_at_the_near_miss_clip_and_the_others_as_before() -> None:
    """With ``near_miss_clip`` an episode that ends outside the goal tolerance but within ``near_miss_distance`` is
    clipped at the near-miss clip (its gradient is the fixed near-miss clip's), the others at ``state_grad_clip``
    (theirs is the fixed clip's), and the return is the return."""
    from dwr_gym.jax_env import make_gymnax_env
    from train.learning.jitted.apg import JaxAPG

    env, params = make_gymnax_env("DWRPointStabilization-v2", T_con_range=[2.0, 2.2])

    def apg(**kwargs: Any) -> Any:
        return JaxAPG(APGSettings(episodes=4, net_arch=(8,), **kwargs), env, params)

    fixed, wide = apg(state_grad_clip=0.25), apg(state_grad_clip=16.0)
    state = fixed.init(0)
    state = state.replace(params=jax.tree.map(lambda x: x * 20.0 if x.ndim == 2 else x, state.params))
    _, at_fixed = fixed.update(state)
    _, at_wide = wide.update(state)
    everywhere = apg(state_grad_clip=0.25, near_miss_clip=16.0, near_miss_distance=100.0)  # every miss is near
    nowhere = apg(state_grad_clip=0.25, near_miss_clip=16.0, near_miss_distance=0.010001)  # none is
    _, near = everywhere.update(state)
    _, far = nowhere.update(state)
    assert float(at_fixed["return_mean"]) < 9.0  # (they miss: not one is at the goal, whose bonus is 10)
    assert float(near["return_mean"]) == float(far["return_mean"]) == float(at_fixed["return_mean"])
    assert float(near["grad_norm"]) == pytest.approx(float(at_wide["grad_norm"]), rel=1e-5)
    assert float(far["grad_norm"]) == pytest.approx(float(at_fixed["grad_norm"]), rel=1e-5)
    assert abs(float(at_wide["grad_norm"]) - float(at_fixed["grad_norm"])) > 0.1 * float(at_fixed["grad_norm"])


def test_a_near_miss_weighs_near_miss_weight_times_its_clipped_gradient() -> None:
    """With ``near_miss_weight`` w an episode that ends near the goal but not at it enters the update with w times its
    clipped gradient (at its own clip, ``near_miss_clip`` where set), the others as before, and the return is the
    return."""
    apg = short_apg
    plain = apg()
    state = plain.init(0)
    state = state.replace(params=jax.tree.map(lambda x: x * 20.0 if x.ndim == 2 else x, state.params))
    _, at_plain = plain.update(state)
    _, near = apg(near_miss_weight=3.0, near_miss_distance=100.0).update(state)  # every miss is near
    _, far = apg(near_miss_weight=3.0, near_miss_distance=0.010001).update(state)  # none is
    _, wide = apg(near_miss_clip=16.0, near_miss_distance=100.0).update(state)
    _, wide_near = apg(near_miss_clip=16.0, near_miss_weight=3.0, near_miss_distance=100.0).update(state)
    assert float(at_plain["return_mean"]) < 9.0  # (they miss)
    assert float(near["return_mean"]) == float(far["return_mean"]) == float(at_plain["return_mean"])
    assert float(near["grad_norm"]) == pytest.approx(3.0 * float(at_plain["grad_norm"]), rel=1e-5)
    assert float(far["grad_norm"]) == pytest.approx(float(at_plain["grad_norm"]), rel=1e-5)
    assert float(wide_near["grad_norm"]) == pytest.approx(3.0 * float(wide["grad_norm"]), rel=1e-5)


def test_hold_steps_adds_the_miss_before_t_con_to_the_gradient_only() -> None:
    """With ``hold_steps`` the update also follows the miss over the last steps before T_con: the gradient changes, the
    return does not; a larger ``hold_weight`` changes it more."""
    apg = short_apg
    plain = apg()
    state = plain.init(0)
    _, at_plain = plain.update(state)
    _, held = apg(hold_steps=10).update(state)
    _, heavy = apg(hold_steps=10, hold_weight=1000.0).update(state)
    assert float(held["return_mean"]) == float(heavy["return_mean"]) == float(at_plain["return_mean"])
    grads = [float(m["grad_norm"]) for m in (at_plain, held, heavy)]
    assert abs(grads[1] - grads[0]) > 1e-4 * grads[0] and abs(grads[2] - grads[0]) > abs(grads[1] - grads[0])


def test_hold_heading_weight_adds_the_heading_before_t_con_to_the_gradient_only() -> None:
    """``hold_heading_weight`` adds the heading's error over the hold window to the update: the gradient changes
    with it (a larger weight more), the return does not."""

    def apg(**kwargs: Any) -> Any:
        return short_apg(hold_steps=10, **kwargs)

    plain = apg()
    state = plain.init(0)
    _, at_plain = plain.update(state)
    _, turned = apg(hold_heading_weight=1.0).update(state)
    _, heavy = apg(hold_heading_weight=1000.0).update(state)
    assert float(turned["return_mean"]) == float(heavy["return_mean"]) == float(at_plain["return_mean"])
    grads = [float(m["grad_norm"]) for m in (at_plain, turned, heavy)]
    assert abs(grads[1] - grads[0]) > 1e-4 * grads[0] and abs(grads[2] - grads[0]) > abs(grads[1] - grads[0])


def test_hold_fraction_is_the_window_of_a_share_of_each_t_con() -> None:
    """``hold_fraction`` sets the hold window as a share of each episode's own T_con: at T_con 2 s (40 control periods)
    a share of 0.25 is the window of ``hold_steps: 10`` (the same gradient), at 4 s it is 20 steps (another one); the
    return is v2's either way."""
    from dwr_gym.jax_env import make_gymnax_env
    from train.learning.jitted.apg import JaxAPG

    def update(T_con: float, **kwargs: Any) -> Any:
        env, params = make_gymnax_env("DWRPointStabilization-v2", T_con_range=[T_con, T_con])
        apg = JaxAPG(APGSettings(episodes=4, net_arch=(8,), state_grad_clip=0.25, **kwargs), env, params)
        return apg.update(apg.init(0))[1]

    steps, share = update(2.0, hold_steps=10), update(2.0, hold_fraction=0.25)
    assert float(share["grad_norm"]) == pytest.approx(float(steps["grad_norm"]), rel=1e-6)
    assert float(share["return_mean"]) == float(steps["return_mean"])
    longer_steps, longer_share = update(4.0, hold_steps=10), update(4.0, hold_fraction=0.25)
    assert float(longer_share["grad_norm"]) != pytest.approx(float(longer_steps["grad_norm"]), rel=1e-4)
    assert float(longer_share["grad_norm"]) == pytest.approx(float(update(4.0, hold_steps=20)["grad_norm"]), rel=1e-6)


def test_short_t_con_share_shortens_the_updates_episodes_only() -> None:
    """With ``short_T_con_share: 1`` and ``short_T_con_max`` at the range's low end every episode of an update has
    the lowest T_con (v2's episodes end at T_con: 40 steps each at 2 s), the schedule counts them so, and the
    validation episodes of ``keep_best`` keep the env's own draw."""
    from dwr_gym.jax_env import make_gymnax_env
    from train.learning.jitted.apg import JaxAPG

    env, params = make_gymnax_env("DWRPointStabilization-v2", T_con_range=[2.0, 4.0])

    def apg(**kwargs: Any) -> Any:
        return JaxAPG(APGSettings(episodes=8, net_arch=(8,), validation_episodes=8, **kwargs), env, params)

    plain, short = apg(), apg(short_T_con_share=1.0, short_T_con_max=1.0)
    assert short.short_params.T_con_range == (2.0, 2.0)  # (clamped to the env's range)
    state = plain.init(0)
    assert int(short.update(state)[1]["steps"]) == 8 * 40 < int(plain.update(state)[1]["steps"])
    assert short.mean_episode_steps() == 40.0 < plain.mean_episode_steps()
    assert int(short.validate(state)[1]["steps"]) == int(plain.validate(state)[1]["steps"]) > 8 * 40


def test_hold_bonus_adds_a_slope_near_the_goal_tolerance_to_the_gradient_only() -> None:
    """``hold_bonus`` adds a sigmoid of the distance, centred at the goal tolerance, over the hold window: the return
    does not change; where every robot is far from the goal in the window (a fresh policy barely moves in 2 s from
    starts 0.3 m away or more) a narrow sigmoid leaves the gradient as it is, and a wide one (its slope reaching them)
    changes it, a larger weight more."""

    def apg(**kwargs: Any) -> Any:
        return short_apg(hold_steps=10, **kwargs)

    plain = apg()
    state = plain.init(0)
    _, at_plain = plain.update(state)
    _, narrow = apg(hold_bonus=10.0, hold_bonus_width=0.001).update(state)
    _, wide = apg(hold_bonus=10.0, hold_bonus_width=1.0).update(state)
    _, heavy = apg(hold_bonus=1000.0, hold_bonus_width=1.0).update(state)
    assert float(narrow["return_mean"]) == float(wide["return_mean"]) == float(at_plain["return_mean"])
    grads = [float(m["grad_norm"]) for m in (at_plain, narrow, wide, heavy)]
    assert grads[1] == pytest.approx(grads[0], rel=1e-6)
    assert abs(grads[2] - grads[0]) > 1e-4 * grads[0] and abs(grads[3] - grads[0]) > abs(grads[2] - grads[0])
