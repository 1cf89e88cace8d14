"""Robustness: the deadline under disturbances, for the controllers and the agents."""
