"""The learners from an expert's actions, commands of their own that write the run directory and agent format of
``dwr-gym train``: behaviour cloning of the optimum (``cloning``, ``dwr-gym imitate``), DAgger on minimum-energy plans
and its hand-over to an analytic law (``dagger``, ``handover``), DAgger under disturbances (``robust_dagger``,
``robust_agent``)."""
