"""The env's float64 results are pinned: seeded rollouts equal the recorded ones to 1e-12 (the env-speed's speed work
must not change them). Re-record with ``python -m benchmarks run golden-rollouts --write`` only for a new env version."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.testing import golden_rollouts


@pytest.mark.filterwarnings("ignore:.*out of date")
@pytest.mark.parametrize(
    ("num_envs", "torch"), [(16, "auto"), (2048, "auto"), (1024, "all"), (1024, "off")]
)  # numpy's functions below dwr_gym.model.TORCH_MIN_SIZE (2048); from it torch's for model.TORCH_FUNCTIONS ("auto": sin
# and cos on CPUs where numpy has SIMD tanh, arcsin and arctan2; "all": all five, as on other CPUs, here from 1024 robots),
# or none (DWR_GYM_TORCH=0)
def test_seeded_rollouts_equal_the_record_to_1e_12(num_envs: int, torch: str, monkeypatch: pytest.MonkeyPatch) -> None:
    from dwr_gym import model

    if torch == "off":
        monkeypatch.setattr(model, "_torch", False)
    elif torch == "all":
        pytest.importorskip("torch")
        monkeypatch.setattr(model, "TORCH_FUNCTIONS", frozenset(("sin", "cos", "tanh", "arcsin", "arctan2")))
        monkeypatch.setattr(model, "TORCH_MIN_SIZE", num_envs)
    assert (num_envs >= model.TORCH_MIN_SIZE) == (torch != "off" and num_envs > 16)  # each case takes its path
    script = golden_rollouts
    golden = np.load(script.PATH)
    arrays = script.rollouts(num_envs)
    assert sorted(arrays) == sorted(golden.files)
    for key in golden.files:
        new, old = arrays[key], golden[key]
        if key.endswith("/single"):  # columns: 10 features, reward, terminated, truncated, energy, pose (3)
            np.testing.assert_allclose(new[:, :10], old[:, :10], rtol=0, atol=2e-6, err_msg=key)
            new, old = new[:, 10:], old[:, 10:]
        # the float32 features may move by one float32 rounding step; everything computed in float64 by 1e-12
        atol = 2e-6 if key.endswith("/obs") else 1e-12
        np.testing.assert_allclose(new, old, rtol=0, atol=atol, err_msg=key)
