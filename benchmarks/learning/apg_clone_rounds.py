"""What APG's open-loop teacher gives before any update: the cloned policy alone, after 1 and more DAgger rounds.

    python -m benchmarks run apg-clone-rounds --docs     # rounds 1, 3 and 6 of 256 episodes (about 25 min, 1 core)
    python -m benchmarks run apg-clone-rounds --rounds 1 2 --episodes 16 --iterations 50   # a quick look, printed
    python -m benchmarks run apg-clone-rounds --rounds 1 --clone-steps 16000 --json F   # the fit's length, into F

For each number of ``teacher_rounds`` (train/learning/jitted/apg_teacher.py), on DWRPointStabilization-v2 with
time-scaled actions (``--action-time-scale 10``, as the benchmark's apg-teacher-time-scaled entries) and apg.yml's
network: the teacher's lesson from seed 0, then the cloned policy's mean action played on ``--eval`` fresh episodes
(the same for every row): in time (at the goal at T_con), the return, the final distance and heading, per band of
T_con. ``--docs`` writes docs/rl_benchmark/apg_clone_rounds.json, from which the table ``apg-clone-rounds`` of
docs/rl-apg-levers.md is rendered.
"""

from __future__ import annotations

import itertools
import platform
import time
from pathlib import Path
from typing import Any

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import Schema, table
from benchmarks.core.record import write_json

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "rl_benchmark" / "apg_clone_rounds.json"
ENV_ID = "DWRPointStabilization-v2"
#: Bands of T_con [s] the in-time share is given for, besides all episodes.
BANDS: tuple[tuple[float, float], ...] = ((10.0, 20.0), (20.0, 40.0), (40.0, 60.0))


def measure(
    rounds: int,
    episodes: int,
    iterations: int,
    n_eval: int,
    time_scale: float,
    clone_steps: int = 4000,
    net_arch: tuple[int, ...] = (64, 64),
) -> dict[str, Any]:
    """The lesson of ``rounds`` rounds (seed 0), fitted in ``clone_steps`` steps on a network of ``net_arch``, and its
    cloned policy on ``n_eval`` fresh episodes (key 123)."""
    import jax
    import jax.numpy as jnp
    import numpy as np

    from dwr_gym.jax_env import make_gymnax_env
    from train.learning.jitted.apg import JaxAPG
    from train.learning.jitted.apg_settings import APGSettings
    from train.learning.jitted.apg_teacher import clone_from_teacher
    from train.learning.time_scale import TimeScaledGymnaxEnv

    env, env_params = make_gymnax_env(ENV_ID)
    env = TimeScaledGymnaxEnv(env, time_scale) if time_scale else env
    settings = APGSettings(teacher_episodes=episodes, teacher_iterations=iterations, teacher_rounds=rounds,
                           clone_steps=clone_steps, net_arch=net_arch)  # fmt: skip
    apg = JaxAPG(settings, env, env_params)
    start = time.time()
    state, lesson = clone_from_teacher(apg, apg.init(0), progress=True)
    seconds = time.time() - start

    def play(key: Any) -> tuple[Any, Any]:
        _, first = env.reset_env(key, env_params)

        def one_step(carry: tuple[Any, Any, Any], _: Any) -> tuple[tuple[Any, Any, Any], None]:
            st, alive, total = carry
            action = apg.act(state.params, st.observation, state.obs_stats)
            _, after, reward, done, _ = env.step_env(jax.random.PRNGKey(0), st, action, env_params)
            st = jax.tree.map(lambda new, old: jnp.where(alive, new, old), after, st)
            return (st, alive & ~done, total + jnp.where(alive, reward, 0.0)), None

        carry = (first, jnp.asarray(True), jnp.asarray(0.0, jnp.float32))
        (final, _, total), _ = jax.lax.scan(one_step, carry, None, length=apg.max_steps)
        return final, total

    final, returns = jax.jit(jax.vmap(play))(jax.random.split(jax.random.PRNGKey(123), n_eval))
    success, T_con = np.asarray(final.is_success), np.asarray(final.T_con)
    observed = np.asarray(final.observation)  # (distance, cos and sin of the azimuth, of the heading, ...)
    distance, heading = observed[:, 0], np.abs(np.arctan2(observed[:, 4], observed[:, 3]))
    bands = {
        f"{low:g}-{high:g}": float(np.mean(success[(T_con >= low) & (T_con < high + 1e-9)])) for low, high in BANDS
    }
    return {"rounds": rounds, "clone_steps": clone_steps, "net_arch": list(net_arch), "episodes": episodes,
            "iterations": iterations, "lesson_steps": lesson["steps"],
            "pairs": lesson["pairs"], "teacher_in_time": lesson["teacher_in_time"], "clone_loss": lesson["clone_loss"],
            "seconds": round(seconds), "in_time": float(np.mean(success)), "in_time_by_T_con": bands,
            "return": float(np.mean(returns)), "final_distance_median": float(np.median(distance)),
            "final_heading": float(np.mean(heading))}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("apg-clone-rounds", __doc__)
    parser.add_argument("--rounds", type=int, nargs="+", default=[1, 3, 6], help="teacher_rounds to measure (1 3 6)")
    parser.add_argument("--episodes", type=int, default=256, help="teacher_episodes, a round (default: 256)")
    parser.add_argument("--iterations", type=int, default=400, help="teacher_iterations (default: 400)")
    parser.add_argument("--eval", type=int, default=512, help="fresh episodes the clone is played on (default: 512)")
    parser.add_argument("--time-scale", type=float, default=10.0, help="--action-time-scale; 0: none (default: 10)")
    parser.add_argument("--clone-steps", type=int, nargs="+", default=[4000], help="clone_steps to measure (4000)")
    parser.add_argument("--net-arch", nargs="+", default=["64x64"], help="networks to measure, as 64x64 (64x64)")
    parser.add_argument("--json", type=Path, default=None, help="write the rows to this JSON file")
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} (and its table)")
    args = parser.parse_args(argv)
    arches = []
    for text in args.net_arch:
        try:
            arches.append(tuple(int(width) for width in text.split("x")))
        except ValueError:
            parser.error(f"--net-arch {text!r} is invalid: expected widths joined by x, such as 64x64")
        if min(arches[-1]) < 1:
            parser.error(f"--net-arch {text!r} is invalid: expected widths >= 1")
    if min(args.clone_steps) < 1:
        parser.error(f"--clone-steps {args.clone_steps} is invalid: expected integers >= 1")
    for name in ("episodes", "iterations", "eval"):
        if getattr(args, name) < 1:
            parser.error(f"--{name} {getattr(args, name)} is invalid: expected an integer >= 1")
    if min(args.rounds) < 1:
        parser.error(f"--rounds {args.rounds} is invalid: expected integers >= 1")
    if args.time_scale < 0:
        parser.error(f"--time-scale {args.time_scale} is invalid: expected a number >= 0")
    rows = []
    for rounds, steps, arch in itertools.product(args.rounds, args.clone_steps, arches):
        rows.append(measure(rounds, args.episodes, args.iterations, args.eval, args.time_scale, steps, arch))
        print({k: (round(v, 3) if isinstance(v, float) else v) for k, v in rows[-1].items()}, flush=True)
    data = {"env_id": ENV_ID, "action_time_scale": args.time_scale, "eval_episodes": args.eval, "rows": rows,
            "machine": {"python": platform.python_version(), "platform": platform.platform()}}  # fmt: skip
    if args.docs:
        write_json(JSON_PATH, data)
    if args.json is not None:
        write_json(args.json, data)
    return 0


SCHEMA = Schema({"env_id": str, "action_time_scale": float, "eval_episodes": int, "rows": list, "machine": dict})
BLOCKS = (table("apg-clone-rounds", SCHEMA),)
