"""The one progress bar of compare and evaluate: its time left spans the stages, a redirected log gets plain lines,
and every stage's time reaches the rows and the closing line."""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from train.evaluation.stages import StageClock, format_seconds


class ManualTime:
    """A stand-in for ``time.perf_counter`` that moves only when told."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


@pytest.fixture
def manual_time(monkeypatch: pytest.MonkeyPatch) -> ManualTime:
    from train.evaluation import stages

    clock = ManualTime()
    monkeypatch.setattr(stages.time, "perf_counter", clock)
    return clock


def test_a_redirected_log_gets_a_plain_line_every_tenth_of_the_work_never_a_carriage_return(
    manual_time: ManualTime,
) -> None:
    log = io.StringIO()  # not a terminal
    clock = StageClock(progress=True, description="compare", file=log)
    clock.plan([(("random", name), 10.0) for name in ("ptc", "astolfi", "optimal")])
    for name in ("ptc", "astolfi", "optimal"):
        with clock.stage("random", name, 10.0, 100) as advance:
            for step in range(1, 101):
                manual_time.now += 0.1
                advance(step / 100)
    clock.close()
    text = log.getvalue()
    assert "\r" not in text
    lines = text.splitlines()
    assert len(lines) == 10 and lines[-1].startswith("compare: 100% after 30 s")
    assert all(line.startswith("compare: ") for line in lines)


def test_the_time_left_learns_each_policys_pace_from_its_stages_that_ended(manual_time: ManualTime) -> None:
    """Estimates off by a factor of each policy's own (a planner whose plans are stored, a slow network) still give
    the right time left once each policy has run once; a policy not run yet takes every policy's ratio."""
    clock = StageClock(progress=True, file=io.StringIO())
    sets = ("fig5", "random", "disturbed", "fault")
    clock.plan([((name, policy), 10.0) for name in sets for policy in ("optimal", "dagger", "ptc")])
    assert clock.left() == pytest.approx(120.0)  # nothing ran: the estimates
    for policy, seconds in (("optimal", 1.0), ("dagger", 40.0)):  # 10x faster, 4x slower than estimated
        with clock.stage("fig5", policy, 10.0, 5):
            manual_time.now += seconds
    # ptc has not run: 41 s for 20 estimated so far, 2.05 each
    assert clock.left() == pytest.approx(3 * 1.0 + 3 * 40.0 + 4 * 10.0 * 41.0 / 20.0)
    with clock.stage("fig5", "ptc", 10.0, 5) as advance:
        manual_time.now += 3.0
        advance(0.1)  # its first step (where a planner plans): not yet a pace
        assert clock.left() == pytest.approx(0.9 * 10.0 * 41.0 / 20.0 + 3 * 1.0 + 3 * 40.0 + 3 * 10.0 * 41.0 / 20.0)
        manual_time.now += 2.0
        advance(0.5)  # its own pace since its first step, once a tenth is done after it: 0.4 in 2 s, 2.5 s more
        assert clock.left() == pytest.approx(2.5 + 3 * 1.0 + 3 * 40.0 + 3 * 10.0 * 41.0 / 20.0)
        manual_time.now += 5.0  # it slowed down: 10 s in all, as estimated
    assert clock.left() == pytest.approx(3 * 1.0 + 3 * 40.0 + 3 * 10.0)
    clock.record("random", "ptc", 10.0, 1000, 10.0)  # ran in another process: done, counted where it ran
    assert clock.left() == pytest.approx(3 * 1.0 + 3 * 40.0 + 2 * 10.0)
    clock.close()


def test_stages_are_timed_even_when_interrupted_and_the_summary_names_the_slowest() -> None:
    clock = StageClock(progress=False)
    clock.plan(3.0)
    with clock.stage("random", "optimum", 1.0, 12):
        pass
    with pytest.raises(KeyboardInterrupt), clock.stage("random", "robust-pt", 1.0, 50):
        raise KeyboardInterrupt
    assert [(t.scenario, t.stage, t.size) for t in clock.times] == [
        ("random", "optimum", 12),
        ("random", "robust-pt", 50),
    ]
    line = clock.summary()
    assert line.startswith("time: ") and "optimum" in line and "12 plans" in line and "robust-pt" in line


def test_stages_of_a_second_process_count_once_in_the_wall_time(ticking_clock: object, monkeypatch) -> None:
    from train.evaluation import stages

    monkeypatch.setattr(stages.time, "perf_counter", lambda: ticking_clock.time())  # type: ignore[attr-defined]
    clock = StageClock(progress=False)  # read at 10
    clock.plan(3.0)
    with clock.stage("random", "optimal", 1.0, 40):  # 20 to 30: 10 s here
        pass
    # ptc (25 s) and astolfi (5 s) ran in the second process beside it; 6 s more were waited for them afterwards
    clock.record("random", "ptc", 25.0, 40, 1.0, waited=6.0)
    clock.record("random", "astolfi", 5.0, 40, 1.0)
    assert clock.seconds("random", "ptc") == 25.0
    line = clock.summary()  # read at 40: 30 s in all, of which 16 s of policies' wall time, 14 s the rest
    assert "policies 16 s (ptc 25 s, optimal 10 s, astolfi 5 s each; some in another process)" in line
    assert line.endswith("the rest (loading, figures, files) 14 s")


def test_seconds_read_as_a_person_would_say_them() -> None:
    assert [format_seconds(s) for s in (42.0, 210.0, 7200.0, float("nan"))] == ["42 s", "3.5 min", "2.0 h", "?"]


def test_evaluate_rows_carry_each_stage_time_and_the_command_ends_with_one_time_line(tmp_path: Path) -> None:
    env = {**os.environ, "MPLBACKEND": "Agg"}
    result = subprocess.run([sys.executable, "-m", "train.cli", "evaluate", "--controllers", "ptc", "--scenarios",
                             "paper-fig5", "--optimum", "none", "--out", str(tmp_path)],
                            capture_output=True, text=True, env=env, timeout=600)  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip().splitlines()[-1].startswith("time: ")
    assert "\r" not in result.stderr  # output captured, not a terminal: lines, not a bar
    (row,) = json.loads((tmp_path / "evaluation.json").read_text())
    assert row["seconds"] >= 0.0 and row["optimum_seconds"] >= 0.0


def test_a_set_run_in_two_processes_takes_the_longer_of_this_ones_stages_and_half_of_all(
    manual_time: ManualTime,
) -> None:
    clock = StageClock(progress=True, file=io.StringIO())
    clock.plan([(("random", "optimal"), 10.0), (("random", "ptc"), 4.0), (("fault", "optimal"), 2.0),
                (("fault", "ptc"), 10.0), (("fault", "astolfi"), 4.0)], beside={"ptc", "astolfi"})  # fmt: skip
    assert clock.left() == pytest.approx(10.0 + 8.0)  # random: the planner's 10 s; fault: half of 16 s
    with clock.stage("random", "optimal", 10.0, 5) as advance:
        manual_time.now += 5.0
        advance(0.5)  # 5 s more here, 4 s beside: 5 s
        assert clock.left() == pytest.approx(5.0 + 8.0)
        manual_time.now += 5.0
    clock.record("random", "ptc", 4.0, 5, 4.0)
    assert clock.left() == pytest.approx(8.0)
    clock.close()


def test_a_policys_pace_is_learned_apart_on_disturbed_sets(manual_time: ManualTime) -> None:
    """optimal plans once per episode on a nominal set and re-plans on a disturbed one: its nominal pace is used on
    a disturbed set only until a disturbed stage has ended."""
    clock = StageClock(progress=True, file=io.StringIO())
    sets = {"random": "nominal", "disturbed": "disturbed", "fault": "disturbed"}
    clock.plan([((name, "optimal"), 10.0) for name in sets], groups=sets)
    with clock.stage("random", "optimal", 10.0, 5):
        manual_time.now += 1.0  # 0.1 of its estimate
    assert clock.left() == pytest.approx(2 * 1.0)
    with clock.stage("disturbed", "optimal", 10.0, 5):
        manual_time.now += 30.0  # 3 times its estimate
    assert clock.ratio("optimal", "fault") == pytest.approx(3.0) and clock.ratio("optimal", "random") == 0.1
    assert clock.left() == pytest.approx(30.0)
    clock.close()


def test_a_planners_estimate_follows_the_set_and_whether_its_plans_are_stored() -> None:
    from train.evaluation.stages import COLD_EPISODE_SECONDS, DEFAULT_EPISODE_SECONDS, estimated_seconds

    cold = {name: estimated_seconds("robust-pt", 1000, 0, name, cold=True) for name in ("random", "fault", "noise")}
    assert cold["fault"] > cold["noise"] > cold["random"]  # robust-pt re-plans most where a wheel fails
    assert estimated_seconds("robust-pt", 1000, 0, "random", cold=False) < cold["random"]
    assert estimated_seconds("robust-pt", 10, 0, "paper-fig5", cold=True) == pytest.approx(
        10 * COLD_EPISODE_SECONDS["robust-pt"]["random"]
    )  # a set not measured: as the random one
    assert estimated_seconds("ptc", 100, 10, "fault", cold=True) == pytest.approx(
        100 * DEFAULT_EPISODE_SECONDS + 10 * 5e-4
    )


def test_a_first_run_plans_the_planners_cold_and_a_second_run_warm(tmp_path: Path, monkeypatch) -> None:
    pytest.importorskip("casadi")
    from baselines import plan_store
    from train.env_ids import env_keywords
    from train.evaluation.evaluate import planned_seconds
    from train.evaluation.scenarios import make_scenario

    monkeypatch.setenv("DWR_GYM_CACHE", str(tmp_path))
    scenario = make_scenario("random", n=10, seed=0, env_kwargs=env_keywords("DWRPointStabilization-v1"))
    policies = {"robust-pt": "robust-pt", "ptc": "ptc"}
    first = dict(planned_seconds(policies, [scenario], "none", None))
    plan_store.default_directory().mkdir(parents=True)
    (plan_store.default_directory() / "1-0.npz").write_bytes(b"")  # what an earlier command wrote
    second = dict(planned_seconds(policies, [scenario], "none", None))
    assert first[("random", "robust-pt")] > second[("random", "robust-pt")]
    assert first[("random", "ptc")] == second[("random", "ptc")]


def synthetic_compare(seed: int) -> list[tuple[str, str, float, float, float]]:
    """Stages as compare runs them, (set, policy, estimate, true seconds, share of them in the first step): each
    estimate (:func:`estimated_seconds`) off by the machine's factor, the policy's and the set's; a planner's time
    mostly in its first step, where it solves every robot's plan."""
    import numpy as np

    from train.evaluation.stages import estimated_seconds

    rng = np.random.default_rng(seed)
    sets = {"paper-fig5": (8, 2000), "paper-fig7": (4, 7000), "random": (1000, 9000), "disturbed": (1000, 9000),
            "fault": (1000, 9000), "delay": (1000, 9000), "noise": (1000, 9000)}  # fmt: skip
    planners = ("optimal", "robust-pt", "robust")
    policies = [*planners, "ptc", "astolfi", "pt-astolfi", *(f"agent-{i}" for i in range(6))]
    machine = rng.uniform(0.5, 3.0)
    by_policy = {policy: rng.uniform(0.5, 2.0) for policy in policies}
    stages = []
    for name, (episodes, steps) in sets.items():
        by_set = rng.uniform(0.8, 1.25)
        for policy in policies:
            n = 50 if policy == "optimal" and name not in ("paper-fig5", "paper-fig7", "random") else episodes
            estimate = estimated_seconds(policy, n, steps, name)
            true = estimate * machine * by_policy[policy] * by_set * rng.uniform(0.9, 1.1)
            stages.append((name, policy, estimate, true, 0.7 if policy in planners else 0.01))
    return stages


@pytest.mark.parametrize("seed", range(5))
def test_the_share_done_never_goes_back_and_the_time_left_after_a_fifth_is_within_1_5x_the_truth(
    manual_time: ManualTime, seed: int
) -> None:
    stages = synthetic_compare(seed)
    clock = StageClock(progress=True, file=io.StringIO())
    clock.plan([((name, policy), estimate) for name, policy, estimate, _, _ in stages])
    total = sum(true for *_, true, _ in stages)
    shown, worst = 0.0, 0.0
    for name, policy, estimate, true, first in stages:
        with clock.stage(name, policy, estimate, 100) as advance:
            for step in range(1, 51):  # the first step, then 49 of the same cost
                manual_time.now += true * (first if step == 1 else (1.0 - first) / 49)
                advance(step / 50)
                assert clock.fraction >= shown  # the bar never goes back
                shown = clock.fraction
                truth = total - manual_time.now
                if shown >= 0.2 and truth > 1.0:
                    worst = max(worst, clock.left() / truth)
    assert clock.fraction == pytest.approx(1.0)
    assert worst <= 1.5, f"the time left said {worst:.2f}x the truth after 20 %"
    clock.close()


def test_a_stages_label_on_the_bar_has_no_leading_comma() -> None:
    class Terminal(io.StringIO):
        def isatty(self) -> bool:
            return True

    screen = Terminal()
    clock = StageClock(progress=True, file=screen)
    clock.plan([(("random", "robust"), 1.0)])
    with clock.stage("random", "robust", 1.0, 10) as advance:
        advance(0.5)
        clock._bar.refresh()
    clock.close()
    drawn = screen.getvalue()
    assert "| random: robust [" in drawn and ", random" not in drawn
