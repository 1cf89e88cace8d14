"""Learning: stable-baselines3 training, residual and hand-over policies, DAgger and imitation of the
optimum, and the sweeps of ``dwr-gym sweep``."""
