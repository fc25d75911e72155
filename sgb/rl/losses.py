"""The PPO loss of an SGB (or vanilla) actor-critic: a pure function of parameters and data.

Loss = PPO clip loss + c1 * 0.5 * squared value error - c2 * entropy + c3 * KL of the
actor's and critic's genomes. The entropy is that of the squashed action tanh(u),
estimated at one draw of u: reparameterised (``entropy_draw="reparameterised"``, as Brax's
PPO does), or, as the authors' ``dist_entropy`` draws it with ``torch.normal(loc, scale)``,
which passes no gradient to loc or scale, a constant to the optimiser
(``"detached"``: of the entropy only its Gaussian part, the sum of log scale, is
trained; a defect of their code, kept as an option to train as they did). Advantages by
GAE.

Under our regime each unroll's individual is rebuilt from its kept noise *under the
current genome*, so the ratio pi_new(a|s) / pi_old(a|s) compares the same individual
(same noise draw) before and after the genome update, as reparameterised sampling
allows; advantages are normalised over the valid steps, and a truncated step bootstraps
from the state it reached. Under the authors' regime (``RL/models.py``,
``BayesianAgent.loss``) the minibatch's actor and critic are one fresh draw each, so the
ratio compares two different draws; advantages are not normalised; a truncated step's
advantage and value error are zero (their environments reset on the spot, as Brax's
``compute_gae`` assumes).
"""

from typing import NamedTuple

import jax
import jax.numpy as jnp

from sgb.noise import standard_normal
from sgb.rl.agent import Agent, Individual, Params, tanh_gaussian_entropy, tanh_gaussian_log_prob
from sgb.rl.normalizer import Normalizer


class LossSettings(NamedTuple):
    """The loss's coefficients (``sgb.rl.ppo.PPOConfig`` has their meaning and defaults)."""

    clip: float
    value_coef: float
    entropy_coef: float
    kl_coef: float
    discount: float
    gae_lambda: float
    reward_scaling: float
    regime: str  # "ours" or "authors"
    entropy_draw: str  # "reparameterised" or "detached"


class Unroll(NamedTuple):
    """What E environments played over T steps, each by one individual."""

    obs: jnp.ndarray  # (E, T, obs)
    u: jnp.ndarray  # (E, T, act) pre-tanh actions
    log_prob: jnp.ndarray  # (E, T)
    reward: jnp.ndarray
    done: jnp.ndarray
    truncation: jnp.ndarray
    valid: jnp.ndarray
    last_obs: jnp.ndarray  # (E, obs)
    individual: Individual  # the players' noise, leading axis E; None for vanilla


def gae(reward, value, next_value, done, truncation, discount, lam, bootstrap_truncated=True):
    """Policy advantages and value targets along the last axis (time).

    The value targets are the lambda-returns G_t = V(s_t) + A_t, with A_t the GAE(lambda)
    advantages. The policy's advantage is the one-step advantage towards the next
    lambda-return, r_t + discount * G_{t+1} - V(s_t) = delta_t + discount * A_{t+1}, as
    Brax's PPO computes it (measured on the Ant: GAE(lambda) itself left two of three
    seeds standing at 2M steps). ``value``/``next_value``: V(s_t), V(s_{t+1}); terminal
    steps (done and not truncated) do not bootstrap; truncated steps bootstrap from
    s_{t+1}; the last step's G_{t+1} is V(s_{t+1}). With ``bootstrap_truncated=False``
    (s_{t+1} unknown: the environment was reset) a truncated step's advantage is 0 and its
    value target V(s_t), as in Brax.
    """
    terminal = done * (1.0 - truncation)
    delta = reward + discount * (1.0 - terminal) * next_value - value
    if not bootstrap_truncated:
        delta = delta * (1.0 - truncation)

    def back(carry, x):
        d, nd = x
        carry = d + discount * lam * nd * carry
        return carry, carry

    xs = (jnp.moveaxis(delta, -1, 0), jnp.moveaxis(1.0 - done, -1, 0))
    _, adv = jax.lax.scan(back, jnp.zeros(delta.shape[:-1]), xs, reverse=True)
    adv = jnp.moveaxis(adv, 0, -1)
    next_adv = jnp.concatenate([adv[..., 1:], jnp.zeros_like(adv[..., :1])], axis=-1)
    return delta + discount * (1.0 - done) * next_adv, adv + value


def masked_mean(x: jnp.ndarray, mask: jnp.ndarray) -> jnp.ndarray:
    """Mean of ``x`` over the entries where ``mask`` is 1 (0 if there are none)."""
    return jnp.sum(x * mask) / jnp.maximum(jnp.sum(mask), 1.0)


def entropy_estimate(
    loc: jnp.ndarray, scale: jnp.ndarray, key: jax.Array, draw: str
) -> jnp.ndarray:
    """One-draw estimate of the squashed action's entropy (nats), summed over the last axis
    of ``loc``, ``scale`` (..., act): at u = loc + scale * eps, eps from ``key``;
    ``draw="detached"`` passes no gradient through u (the authors' ``torch.normal``)."""
    u = loc + scale * standard_normal(key, loc.shape)
    if draw == "detached":
        u = jax.lax.stop_gradient(u)
    return tanh_gaussian_entropy(scale, u)


def ppo_loss(
    params: Params,
    data: Unroll,
    normalizer: Normalizer,
    key: jax.Array,
    agent: Agent,
    settings: LossSettings,
) -> tuple[jnp.ndarray, dict]:
    """The PPO loss of ``data`` under ``params``, a scalar, and its parts by name (policy,
    value, entropy, kl, total). ``key`` draws the entropy's action and the KL's Monte Carlo
    terms (and, under the authors' regime, the minibatch's fresh draw:
    ``agent.birth(fold_in(key, 1))``). Differentiable in ``params``."""
    authors = settings.regime == "authors"
    individual = agent.birth(jax.random.fold_in(key, 1)) if authors else data.individual
    actor = agent.actor.layers(params.actor, individual.actor)
    critic = agent.critic.layers(params.critic, individual.critic)
    all_obs = jnp.concatenate([data.obs, data.last_obs[:, None]], axis=1)
    values = agent.value(critic, normalizer, all_obs)
    loc, scale = agent.policy(actor, normalizer, data.obs)
    log_prob = tanh_gaussian_log_prob(data.u, loc, scale)
    adv, target = gae(
        data.reward * settings.reward_scaling,
        jax.lax.stop_gradient(values[:, :-1]),
        jax.lax.stop_gradient(values[:, 1:]),
        data.done,
        data.truncation,
        settings.discount,
        settings.gae_lambda,
        bootstrap_truncated=not authors,
    )
    if not authors:
        mean_adv = masked_mean(adv, data.valid)
        std_adv = jnp.sqrt(masked_mean((adv - mean_adv) ** 2, data.valid)) + 1e-8
        adv = (adv - mean_adv) / std_adv
    ratio = jnp.exp(log_prob - data.log_prob)
    clipped = jnp.clip(ratio, 1 - settings.clip, 1 + settings.clip)
    policy_loss = -masked_mean(jnp.minimum(ratio * adv, clipped * adv), data.valid)
    value_loss = 0.5 * masked_mean((values[:, :-1] - target) ** 2, data.valid)
    k_entropy, k_actor, k_critic = jax.random.split(key, 3)
    entropy = masked_mean(
        entropy_estimate(loc, scale, k_entropy, settings.entropy_draw), data.valid
    )
    kl = agent.actor.kl(params.actor, k_actor) + agent.critic.kl(params.critic, k_critic)
    total = (
        policy_loss
        + settings.value_coef * value_loss
        - settings.entropy_coef * entropy
        + settings.kl_coef * kl
    )
    parts = {"total": total, "policy": policy_loss, "value": value_loss, "entropy": entropy}
    return total, {**parts, "kl": kl}
