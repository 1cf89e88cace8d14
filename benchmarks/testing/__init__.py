"""Testing: how good the tests are (fuzzing, reliability, golden rollouts, mutation score, planted bugs)."""
