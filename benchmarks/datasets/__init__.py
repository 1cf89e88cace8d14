"""Datasets: the offline suite, its baselines, and how fast a dataset is made."""
