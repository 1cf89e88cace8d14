"""Learning: ``dwr-gym train``'s learners (the registry :mod:`train.learning.learners`, the trainers by kind in
``sb3``, ``jitted`` and ``evolution``), the imitation learners (``imitation``), and what they all share: the
configuration, the hyperparameters, the run directory, the agents, residual policies and the sweeps."""
