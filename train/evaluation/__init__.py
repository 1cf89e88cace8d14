"""Evaluation: scenario sets, batched rollouts and their metrics, the optimum, and what ``compare``,
``reproduce`` and ``robustness`` measure. Nothing here prints, plots or parses arguments."""
