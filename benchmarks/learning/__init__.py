"""Learning: what the learned agents reach on the task, and why (levers, sweeps, diagnosis, residuals, timing)."""
