"""The gradient learner compiled whole with the functional JAX env (``--algo ppo --backend jax``: the network, PPO,
the residual on a jitted expert), and what every jitted trainer shares: XLA's set-up (``setup``), the run of a
trainer in the run directory (``run``) and the export of its policy as an SB3 model (``export``)."""
