"""Evolution strategies on the functional JAX env (``--algo es --backend jax``): the settings, the strategies
(evosax, one jitted generation split over the host's devices) and the trainer on the jitted run of ``jitted.run``."""
