"""The PPO loss alone: GAE against a loop, and the loss's parts on a small synthetic unroll."""

import jax
import jax.numpy as jnp
import numpy as np

from sgb.rl.agent import NetworkConfig, make_agent, tanh_gaussian_log_prob
from sgb.rl.losses import LossSettings, Unroll, gae, masked_mean
from sgb.rl.losses import ppo_loss as eager_ppo_loss
from sgb.rl.normalizer import init_normalizer, update

# the loss as training runs it, compiled whole (op by op it takes seconds a call)
ppo_loss = jax.jit(eager_ppo_loss, static_argnums=(4, 5))

SETTINGS = LossSettings(
    clip=0.3,
    value_coef=0.5,
    entropy_coef=1e-2,
    kl_coef=1e-3,
    discount=0.9,
    gae_lambda=0.8,
    reward_scaling=2.0,
    regime="ours",
    entropy_draw="reparameterised",
)


def test_gae_matches_a_loop():
    rng = np.random.default_rng(0)
    t = 6
    reward, value = rng.normal(size=(2, t))
    next_value = np.append(value[1:], rng.normal())  # V(s_{t+1}), as the unroll gives it
    done = np.array([0, 0, 1, 0, 0, 1.0])
    trunc = np.array([0, 0, 0, 0, 0, 1.0])
    adv, target = gae(*(jnp.asarray(x) for x in (reward, value, next_value, done, trunc)), 0.9, 0.8)
    lambda_return, policy_adv = np.zeros(t), np.zeros(t)
    for i in reversed(range(t)):
        terminal = done[i] * (1 - trunc[i])
        bootstrap = next_value[i] if i == t - 1 or done[i] else lambda_return[i + 1]
        policy_adv[i] = reward[i] + 0.9 * (1 - terminal) * bootstrap - value[i]
        # G_t = r_t + gamma * ((1 - lambda) V(s_{t+1}) + lambda G_{t+1}), cut at episode ends
        following = next_value[i] if i == t - 1 or done[i] else lambda_return[i + 1]
        mixed = (1 - 0.8) * next_value[i] + 0.8 * following
        lambda_return[i] = reward[i] + 0.9 * (1 - terminal) * mixed
    np.testing.assert_allclose(target, lambda_return, rtol=1e-5)
    np.testing.assert_allclose(adv, policy_adv, rtol=1e-5)


def _unroll_by(agent, params, normalizer, key, e=8, t=6):
    """An unroll of ``e`` individuals of ``agent`` over ``t`` synthetic steps, acting as the
    collecting policy does (so the ratio is 1 at ``params``)."""
    keys = jax.random.split(key, 6)
    individual = jax.vmap(agent.birth)(jax.random.split(keys[0], e))
    obs = jax.random.normal(keys[1], (e, t, agent.obs_size))
    actor = agent.actor.layers(params.actor, individual.actor)
    loc, scale = agent.policy(actor, normalizer, obs)
    u = loc + scale * jax.random.normal(keys[2], loc.shape)
    done = (jax.random.uniform(keys[3], (e, t)) < 0.2).astype(jnp.float32)
    valid = jnp.concatenate([jnp.ones((e, 1)), 1.0 - jnp.cumsum(done, axis=1)[:, :-1] > 0], 1)
    return Unroll(
        obs=obs,
        u=u,
        log_prob=tanh_gaussian_log_prob(u, loc, scale),
        reward=jax.random.normal(keys[4], (e, t)),
        done=done,
        truncation=jnp.zeros((e, t)),
        valid=valid.astype(jnp.float32),
        last_obs=jax.random.normal(keys[5], (e, agent.obs_size)),
        individual=individual,
    )


def _setup():
    network = NetworkConfig(hidden=(16, 16), cell_types=4, rho_init=-2.0)
    agent = make_agent(network, 3, 2)
    params = agent.init(jax.random.PRNGKey(0), jax.random.PRNGKey(1), network)
    obs = jax.random.normal(jax.random.PRNGKey(2), (50, 3)) * 2.0 + 1.0
    normalizer = update(init_normalizer(3), obs, jnp.ones(50))
    data = jax.jit(_unroll_by, static_argnums=0)(agent, params, normalizer, jax.random.PRNGKey(3))
    return agent, params, normalizer, data


def test_at_the_collecting_parameters_the_loss_is_its_value_entropy_and_kl_parts():
    """Ratio 1 and normalised advantages: the clipped surrogate is 0, and the total is the
    weighted sum of the other parts; the KL part scales with its coefficient."""
    agent, params, normalizer, data = _setup()
    key = jax.random.PRNGKey(4)
    total, parts = ppo_loss(params, data, normalizer, key, agent, SETTINGS)
    assert abs(float(parts["policy"])) < 1e-6
    expected = (
        SETTINGS.value_coef * parts["value"]
        - SETTINGS.entropy_coef * parts["entropy"]
        + SETTINGS.kl_coef * parts["kl"]
    )
    np.testing.assert_allclose(total, expected, rtol=1e-6)
    assert float(parts["kl"]) > 0
    doubled, _ = ppo_loss(params, data, normalizer, key, agent, SETTINGS._replace(kl_coef=2e-3))
    np.testing.assert_allclose(doubled - total, 1e-3 * parts["kl"], rtol=1e-4)


def _normalised_advantages(agent, params, normalizer, data):
    """The advantages the loss uses, computed here from ``gae`` and the critic."""
    critic = agent.critic.layers(params.critic, data.individual.critic)
    values = agent.value(critic, normalizer, jnp.concatenate([data.obs, data.last_obs[:, None]], 1))
    adv, _ = gae(
        data.reward * SETTINGS.reward_scaling,
        values[:, :-1],
        values[:, 1:],
        data.done,
        data.truncation,
        SETTINGS.discount,
        SETTINGS.gae_lambda,
    )
    mean = masked_mean(adv, data.valid)
    return (adv - mean) / (jnp.sqrt(masked_mean((adv - mean) ** 2, data.valid)) + 1e-8)


POLICY_ONLY = SETTINGS._replace(value_coef=0.0, entropy_coef=0.0, kl_coef=0.0)


def test_at_ratio_one_the_ppo_gradient_is_the_policy_gradient():
    """The clip is inactive at ratio 1, so the surrogate's gradient in the actor is that of
    -mean(A * log pi(a|s)) with the normalised advantages held fixed."""
    agent, params, normalizer, data = _setup()
    key = jax.random.PRNGKey(4)
    ours = jax.jit(jax.grad(lambda p: ppo_loss(p, data, normalizer, key, agent, POLICY_ONLY)[0]))(
        params
    )
    adv = _normalised_advantages(agent, params, normalizer, data)

    def surrogate(actor_params):
        actor = agent.actor.layers(actor_params, data.individual.actor)
        loc, scale = agent.policy(actor, normalizer, data.obs)
        return -masked_mean(adv * tanh_gaussian_log_prob(data.u, loc, scale), data.valid)

    reference = jax.jit(jax.grad(surrogate))(params.actor)
    leaves = zip(
        jax.tree_util.tree_leaves(ours.actor), jax.tree_util.tree_leaves(reference), strict=True
    )
    for a, b in leaves:
        np.testing.assert_allclose(a, b, rtol=1e-4, atol=1e-7)
    assert max(float(jnp.abs(g).max()) for g in jax.tree_util.tree_leaves(ours.actor)) > 0


def test_beyond_the_clip_the_surrogate_is_the_clipped_one():
    """Every ratio at 2 (old log-probabilities lowered by log 2), clip 0.3: the policy part
    is -mean(min(2 A, 1.3 A)) over the valid steps."""
    agent, params, normalizer, data = _setup()
    shifted = data._replace(log_prob=data.log_prob - jnp.log(2.0))
    _, parts = ppo_loss(params, shifted, normalizer, jax.random.PRNGKey(4), agent, POLICY_ONLY)
    adv = _normalised_advantages(agent, params, normalizer, data)
    expected = -masked_mean(jnp.minimum(2.0 * adv, 1.3 * adv), data.valid)
    np.testing.assert_allclose(parts["policy"], expected, rtol=1e-5)
    assert abs(float(expected)) > 0.01
