"""The learners of stable-baselines3's API: SB3 on torch (``--backend sb3``) and sbx-rl on JAX (``--backend sbx``),
on the native vector env, with RL fine-tuning of a saved network (``--init-from``)."""
