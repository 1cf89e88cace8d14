"""The terms APG adds to the gradient only (``dwr-gym train --algo apg --backend jax``): the near misses' clip and the
hold window before T_con (``hold_steps``) with its heading term; the return each update reports stays v2's."""

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
