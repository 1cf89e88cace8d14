"""The report of the ``throughput`` benchmark (docs/throughput.md): its goals and its lines, from its JSON alone."""

from __future__ import annotations

from typing import Any


def verdict(ok: bool) -> str:
    return "met" if ok else "not met"


def goals(results: dict[str, Any]) -> list[str]:
    """The env-speed and busy-machine goals, each with the measured figure."""
    lines = []
    quiet = results["quiet"]
    if "4096" in quiet["vector"]:
        rates = quiet["vector"]["4096"]
        lines += [
            f"the env-speed goal: vector env, float64, N = 4096, >= 10 M env-steps/s: {rates['f64'] / 1e6:.2f} M -> "
            f"{verdict(rates['f64'] >= 1e7)}",
            f"the busy-machine goal: vector env, float64, N = 4096, quiet, >= 0.5x CartPoleVectorEnv: "
            f"{rates['f64/cart']:.2f}x -> "
            f"{verdict(rates['f64/cart'] >= 0.5)}",
        ]
        if "loaded" in results:
            loaded = results["loaded"]["vector"]["4096"]["f64/cart"]
            lines.append(
                f"the busy-machine goal: vector env, float64, N = 4096, {results['load_processes']} busy processes, "
                ">= 0.4x "
                f"CartPoleVectorEnv: {loaded:.2f}x -> {verdict(loaded >= 0.4)}"
            )
    single = quiet["single"]["gym.make"]["ratio"]
    lines.append("the busy-machine goal: single env step through gym.make, quiet, <= 1.5x CartPole-v1's: "
                 f"{single:.2f}x -> "
                 f"{verdict(single <= 1.5)}")  # fmt: skip
    threshold = results["machine"]["torch_min_size"]
    for condition in ("quiet", "loaded"):
        if condition not in results:
            continue
        ratios = {int(n): rates["f64/numpy"] for n, rates in results[condition]["vector"].items()}
        same = [r for n, r in ratios.items() if n < threshold]  # the same code runs on both paths: the noise
        floor = min([1.0, *same])
        worst = min((n for n in ratios if n >= threshold), key=ratios.__getitem__, default=None)
        if worst is not None:
            noise = (
                f"; below N = {threshold} both run the same code and measure {min(same):.2f}x-{max(same):.2f}x"
                if same
                else ""
            )
            lines.append(
                f"the busy-machine goal: vector env not slower than its numpy-only path, {condition}: "
                "slowest float64/numpy-only "
                f"ratio {ratios[worst]:.2f}x (N = {worst}){noise} -> {verdict(ratios[worst] >= floor)}"
            )
    return lines


def render(results: dict[str, Any]) -> list[str]:
    """The lines of the report, from the JSON alone."""
    m = results["machine"]
    torch = f"torch {m['torch']} ({m['torch_threads']} threads by default)" if m["torch"] else "no torch"
    conditions = ["quiet"] + (["loaded"] if "loaded" in results else [])
    load = results["load_processes"]
    label = {"quiet": "quiet", "loaded": f"loaded ({load} busy processes)"}
    lines = [
        f"machine: {m['cpu']}, {m['cores']} cores; Python {m['python']}, numpy {m['numpy']}, "
        f"gymnasium {m['gymnasium']}, {torch}",
        f"computed by torch for large float64 arrays: {', '.join(m['torch_functions']) or 'none'}"
        + (" (quick run)" if results["quick"] else ""),
        "",
        "== summary: " + " | ".join(label[c] for c in conditions) + " ==",
    ]
    rows = [
        ("single env step / CartPole-v1's (gym.make)", lambda r: r["single"]["gym.make"]["ratio"], "x"),
        ("single env step / CartPole-v1's (unwrapped)", lambda r: r["single"]["unwrapped"]["ratio"], "x"),
        ("vector float64, N = 4096 / CartPoleVectorEnv", lambda r: r["vector"]["4096"]["f64/cart"], "x"),
        ("vector float64, N = 4096 / numpy-only path", lambda r: r["vector"]["4096"]["f64/numpy"], "x"),
        ("vector float64, N = 4096 [M env-steps/s]", lambda r: r["vector"]["4096"]["f64"] / 1e6, " M"),
        ("CartPoleVectorEnv, N = 4096 [M env-steps/s]", lambda r: r["vector"]["4096"]["cart"] / 1e6, " M"),
    ]
    for title, get, unit in rows:
        lines.append(f"{title:<46}" + "".join(f"{get(results[c]):>12.2f}{unit:<2}" for c in conditions))

    for condition in conditions:
        r = results[condition]
        lines += [
            "",
            f"== {label[condition]}: float64 kernels at N = 4096: us per call (median of single calls, mean over "
            "all), process CPU s per wall s ==",
        ]
        backends = [b[: -len(": median")] for b in next(iter(r["kernels"].values())) if b.endswith(": median")]
        lines.append(f"{'':<8}" + "".join(f"{b:>26}" for b in backends))
        lines.append(f"{'':<8}" + "   median     mean cpu/wall" * len(backends))
        for name, costs in r["kernels"].items():
            cells = (f"{costs[b + ': median']:>9.1f}{costs[b + ': mean']:>9.1f}{costs[b + ': cpu/wall']:>8.2f}"
                     for b in backends)  # fmt: skip
            lines.append(f"{name:<8}" + " ".join(cells))

        lines += ["", f"== {label[condition]}: one step of a single env, fixed seeded action, reset at episode ends =="]
        for kind, s in r["single"].items():
            lines.append(f"{kind:>10}: ours {s['ours_us']:6.1f} us, CartPole-v1 {s['cartpole_us']:6.1f} us, ratio "
                         f"{s['ratio']:5.2f}x (episodes of {s['ours_episode_steps']:.0f} and "
                         f"{s['cartpole_episode_steps']:.1f} steps)")  # fmt: skip

        lines += [
            "",
            f"== {label[condition]}: vector envs, M env-steps/s (median); numpy-only: DWR_GYM_TORCH=0; "
            "torch 1 thr: torch.set_num_threads(1); ratios paired (f64/numpy: adjacent steps) ==",
            f"{'N':>6} {'float64':>8} {'torch 1 thr':>11} {'numpy-only':>10} {'float32':>8} {'Sync(ours)':>10} "
            f"{'CartPoleVec':>11} {'f64/Cart':>8} {'f64/numpy':>9} {'f32/Cart':>8}",
        ]
        for n, v in r["vector"].items():
            lines.append(
                f"{n:>6} {v['f64'] / 1e6:>8.2f} {v['f64_torch1'] / 1e6:>11.2f} {v['numpy'] / 1e6:>10.2f} "
                f"{v['f32'] / 1e6:>8.2f} {v['sync'] / 1e6:>10.3f} {v['cart'] / 1e6:>11.2f} {v['f64/cart']:>8.2f} "
                f"{v['f64/numpy']:>9.2f} {v['f32/cart']:>8.2f}"
            )

    a = results["autoreset"]
    lines += [
        "",
        "== quiet: autoreset modes, N = 4096, T_con = 2 s and dt = 0.1 s (every episode ends within 30 steps) ==",
    ]
    for dtype in ("float64", "float32"):
        next_step, same_step = a[f"next_step/{dtype}"], a[f"same_step/{dtype}"]
        lines.append(f"{dtype}: NEXT_STEP (default) {next_step / 1e6:.2f} M, SAME_STEP {same_step / 1e6:.2f} M, "
                     f"ratio {next_step / same_step:.2f}")  # fmt: skip
    c = results["crossover"]
    lines += [
        "",
        "== quiet: float64 step with torch's functions at every size / numpy-only, adjacent steps (TORCH_MIN_SIZE) ==",
        f"{'N':>24}" + "".join(f"{n:>7}" for n in c["this_cpu"]),
        f"{'this CPU':>24}" + "".join(f"{r:>7.2f}" for r in c["this_cpu"].values()),
    ]
    if c["without_avx512"]:
        ratios = c["without_avx512"]["ratios"]
        lines.append(f"{'AVX512 switched off':>24}" + "".join(f"{r:>7.2f}" for r in ratios.values())
                     + f"   (torch computes {', '.join(c['without_avx512']['torch_functions'])})")  # fmt: skip
    p = results["ptc"]
    lines += [
        "",
        "== quiet: PTC law on the `random` scenario set (10,000 start poses, default T_con and dt) ==",
        f"median {p['seconds']:.2f} s, success rate {p['success_rate']:.4f}",
        "",
        "== goals ==",
        *goals(results),
    ]
    return lines
