"""Reporting: the tables printed, the CSV and JSON written, and the figures, from rows and rollouts that
:mod:`train.evaluation` and :mod:`train.learning` computed."""
