"""The learners' conventions against second, naive computations: the direction and size of each gradient term an
APG option adds (the gradient of the documented surrogate, from a plain loop over the env's own steps), the JAX
residual's initial head scale (SB3's), ES's return of a candidate (the env's own episode return of the same
actions), and which fresh episode the optimistic auto-reset hands each ended robot."""

from __future__ import annotations

import inspect
from typing import Any

import numpy as np
import pytest

jax = pytest.importorskip("jax")
pytest.importorskip("flax")

import jax.numpy as jnp  # noqa: E402

from dwr_gym.jax_env import make_gymnax_env  # noqa: E402
from train.learning.jitted.apg_settings import APGSettings  # noqa: E402


def apg_of(**kwargs: Any) -> Any:
    """APG on v2 at T_con 2-2.2 s (44 steps at most), a network of 8 units, the state's gradient unclipped (so that
    each term's gradient adds to the others' exactly)."""
    from train.learning.jitted.apg import JaxAPG

    env, params = make_gymnax_env("DWRPointStabilization-v2", T_con_range=[2.0, 2.2])
    return JaxAPG(APGSettings(episodes=2, net_arch=(8,), state_grad_clip=0.0, **kwargs), env, params)


def window_penalty(apg: Any, params: Any, stats: Any, key: Any, term: Any, hold: float | None) -> Any:
    """The surrogate an option documents, in a plain loop over the env's steps: the mean over the last ``hold``
    steps up to T_con of ``term(state after the step)``,
    of the episode APG plays from ``key``."""
    key_reset, key_steps = jax.random.split(key)
    _, state = apg.env.reset_env(key_reset, apg.env_params)
    alive, total = jnp.asarray(True), 0.0
    for t in range(apg.max_steps):
        action = apg.act(params, state.observation, stats)
        _, after, _, done, _ = apg.env.step_env(jax.random.fold_in(key_steps, t), state, action, apg.env_params)
        in_window = after.step_count > after.prescribed_steps - hold
        total = total + jnp.where(alive & in_window, term(after) / hold, 0.0)
        state = jax.tree.map(lambda new, old, alive=alive: jnp.where(alive, new, old), after, state)
        alive = alive & ~done
    return total


def flat(tree: Any) -> np.ndarray:
    return np.concatenate([np.ravel(np.asarray(leaf, np.float64)) for leaf in jax.tree.leaves(tree)])


TERMS: dict[str, tuple[dict[str, Any], dict[str, Any], Any, float | None]] = {
    # option: (the settings with it, without it, the per-step term it charges (the return loses it), its window)
    "hold_steps": ({"hold_steps": 10, "hold_weight": 1000.0}, {}, lambda s: 1000.0 * s.distance, 10.0),
    "hold_heading_weight": ({"hold_steps": 10, "hold_heading_weight": 1000.0}, {"hold_steps": 10},
                            lambda s: 1000.0 * 2.0 * jnp.abs(jnp.sin(0.5 * s.psi)), 10.0),
}  # fmt: skip


@pytest.mark.parametrize("option", list(TERMS))
def test_each_apg_option_adds_the_gradient_of_its_documented_charge(option: str) -> None:
    """An episode's gradient with the option minus without it is minus the gradient of the charge the option
    documents (the return loses it): the same direction and size, from a second computation; a flipped sign points
    the other way. The return itself is v2's either way."""
    with_it, without, term, hold = TERMS[option]
    apg, plain = apg_of(**with_it), apg_of(**without)
    state = apg.init(0)
    params = jax.tree.map(lambda x: x * 3.0 if x.ndim == 2 else x, state.params)  # a policy that moves the robots
    key = jax.random.PRNGKey(7)

    def episode_return(learner: Any) -> Any:
        return jax.value_and_grad(lambda p: learner.episode(p, state.obs_stats, key)[0])(params)

    (value, grad), (plain_value, plain_grad) = episode_return(apg), episode_return(plain)
    assert float(value) == pytest.approx(float(plain_value), rel=1e-6)
    added = flat(grad) - flat(plain_grad)
    expected = -flat(jax.grad(lambda p: window_penalty(apg, p, state.obs_stats, key, term, hold))(params))
    assert np.linalg.norm(expected) > 1e-3 * np.linalg.norm(flat(plain_grad))  # the term is there to be seen
    cosine = float(added @ expected / (np.linalg.norm(added) * np.linalg.norm(expected)))
    size = float(np.linalg.norm(added) / np.linalg.norm(expected))
    assert cosine > 0.999 and size == pytest.approx(1.0, rel=1e-2), (
        f"{option}: the gradient it adds has cosine {cosine:.4f} with the oracle's and {size:.4f} times its norm"
    )


def test_the_jax_residual_starts_at_sb3s_scale_of_its_fresh_head() -> None:
    """The JAX residual's head starts as SB3's residual agents do (zero_init_last_layer's gain of its fresh kernel,
    its bias 0), so that both backends start at the same distance from their expert."""
    from train.learning.jitted.residual import near_zero_head
    from train.learning.residual import zero_init_last_layer

    gain = inspect.signature(zero_init_last_layer).parameters["gain"].default
    kernel = jax.random.normal(jax.random.PRNGKey(0), (8, 2))
    params = {"params": {"action": {"kernel": kernel, "bias": jnp.ones(2)}, "hidden": {"kernel": jnp.ones((3, 8))}}}
    head = near_zero_head(params)["params"]
    np.testing.assert_allclose(np.asarray(head["action"]["kernel"]), gain * np.asarray(kernel), rtol=1e-6)
    assert not np.asarray(head["action"]["bias"]).any()
    np.testing.assert_array_equal(np.asarray(head["hidden"]["kernel"]), np.ones((3, 8)))


def test_es_return_of_a_candidate_is_the_envs_own_episode_return() -> None:
    """Each candidate's return on each of a generation's episodes is the sum of the env's own rewards when that
    candidate acts in that episode, step by step until it ends (nothing after); the candidates differ."""
    pytest.importorskip("evosax")
    from train.learning.evolution.settings import ESSettings
    from train.learning.evolution.strategies import JaxES

    env, env_params = make_gymnax_env("DWRPointStabilization-v1", T_con_range=(2.0, 2.2))
    es = JaxES(ESSettings(population_size=2, episodes=3, net_arch=(8,)), env, env_params, devices=1)
    state = es.init(0)
    mean = es.actor(es.mean_params(state))
    actors = [mean, jax.tree.map(lambda x: x * 4.0 + 0.1, mean)]
    population = jax.tree.map(lambda *xs: jnp.stack(xs), *actors)
    key = jax.random.PRNGKey(3)
    returns, _, _ = jax.jit(es.play)(population, state, key)
    # the episodes of a generation's key, as play documents: every candidate on the same starts and step keys
    key_reset, key_steps = jax.random.split(key)
    starts = jax.vmap(env.reset_env, in_axes=(0, None))(jax.random.split(key_reset, 3), env_params)[1]
    step_keys = jax.random.split(key_steps, 3)
    fixed = {k: v for k, v in state.params["params"].items() if k not in mean}
    step = jax.jit(env.step_env)
    rows = []
    for c, actor in enumerate(actors):
        act = jax.jit(lambda o, actor=actor: es.act({"params": {**fixed, **actor}}, o, state.obs_stats))
        for e in range(3):
            s = jax.tree.map(lambda x, e=e: x[e], starts)
            total, done, t = 0.0, False, 0
            while not done:
                _, s, reward, ended, _ = step(jax.random.fold_in(step_keys[e], t), s, act(s.observation), env_params)
                total, done, t = total + float(reward), bool(ended), t + 1
            rows.append((c, e, total, float(returns[c, e])))
    wrong = [f"candidate {c} episode {e}: env {want!r}, ES {got!r}" for c, e, want, got in rows
             if got != pytest.approx(want, rel=1e-5, abs=1e-4)]  # fmt: skip
    assert not wrong, "\n".join(wrong)
    assert len({round(got, 3) for *_, got in rows}) > 3  # candidates and episodes differ


def test_the_autoreset_hands_the_kth_ended_robot_fresh_episode_k() -> None:
    """With r > 1, the k-th robot (in index order) whose episode ended takes fresh episode k mod num_envs // r, the
    fresh episodes being the env's initial states of the step key's reset half split in num_envs // r; the other
    robots step on. Checked robot by robot against a plain loop, at steps where fewer, as many and more robots end
    than there are fresh episodes."""
    import dwr_gym
    from dwr_gym.jax_env.autoreset import OptimisticResetVecEnv

    n = 16
    env, params = make_gymnax_env(dwr_gym.ENV_ID, T_con_range=(0.5, 1.0))
    batched = OptimisticResetVecEnv(env, n, reset_ratio=4)  # 4 fresh episodes a step
    step = jax.jit(batched.step)
    initial = jax.jit(jax.vmap(env.func_env.initial, in_axes=(0, None)))
    _, state = batched.reset(jax.random.PRNGKey(0), params)
    counts = set()
    for t in range(40):
        key = jax.random.PRNGKey(100 + t)
        action = jax.random.uniform(jax.random.PRNGKey(t), (n, 2), minval=-1.0, maxval=1.0)
        _, after, _, done, _ = step(key, state, action, params)
        fresh = initial(jax.random.split(jax.random.split(key)[1], batched.num_resets), params)
        ended = np.flatnonzero(np.asarray(done))
        counts.add(min(len(ended), batched.num_resets + 1))
        fields = {name: (np.asarray(getattr(after, name)), np.asarray(getattr(fresh, name)))
                  for name in ("x", "y", "psi", "T_con")}  # fmt: skip
        for k, robot in enumerate(ended):
            for field, (robots, episodes) in fields.items():
                got, want = float(robots[robot]), float(episodes[k % batched.num_resets])
                assert got == want, f"step {t}: robot {robot}, the {k}-th to end: {field} {got}, fresh episode {want}"
        state = after
    assert {1, batched.num_resets + 1} <= counts  # one robot alone and more than the fresh episodes both occurred
