"""Training: how fast `dwr-gym train` and the JAX learners run, what a run costs, and retraining the shipped agents."""
