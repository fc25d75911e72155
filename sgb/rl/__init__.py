"""Reinforcement learning with SGB actor-critics: Brax environments and variants, PPO, populations.

Modules: ``envs`` (environments, long-leg Ant, niches), ``agent`` (vanilla and SGB
actor-critic, births, the policy), ``losses`` (the PPO loss), ``normalizer``
(observation statistics), ``ppo`` (training), ``population`` (innate returns of N
individuals and of the mean network), ``checkpoints`` (save/load trained agents),
``render`` (pictures). Importing the package loads nothing; ``envs`` loads Brax and
MuJoCo.
"""
