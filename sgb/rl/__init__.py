"""Reinforcement learning with SGB actor-critics: Brax environments and variants, PPO, populations.

Modules: ``envs`` (environments, long-leg Ant, niches), ``networks`` (vanilla
and SGB actor/critic, individuals), ``normalizer`` (observation statistics),
``ppo`` (training), ``population`` (innate returns of N individuals and of
the mean network), ``checkpoints`` (save/load trained agents).
"""
