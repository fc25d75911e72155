"""PPO for vanilla and SGB actor-critics on Brax environments.

One training iteration:

1. *Births.* Every parallel environment whose episode ended during the last
   unroll is reset, and a new individual is born for it: from a fresh PRNG
   key, the weight noise of its actor and critic is drawn once
   (``sgb.rl.networks.draw_noise``) and kept for its whole life. Its weights
   are that noise under the current genome (``sgb.rl.networks.individuals``).
   So an individual lives exactly one episode, and each of the ``num_envs``
   environments runs its own individual.
2. *Unroll.* Each environment runs ``unroll_length`` steps. Actions are
   tanh(u), u ~ N(loc, scale) from the individual's actor. An environment
   whose episode ends waits, masked out, until the unroll is over (no
   auto-reset), so one unroll of one environment is always played by one
   individual. Episodes are cut at ``episode_length`` steps (truncation:
   the value of the last state is bootstrapped).
3. *Update.* ``num_epochs`` passes over the unrolls in ``num_minibatches``
   minibatches of environments. Each unroll's individual is rebuilt from its
   kept noise *under the current genome*: the PPO ratio
   pi_new(a|s) / pi_old(a|s) compares the same individual (same noise draw)
   before and after the genome update, as reparameterised sampling allows.
   Loss = PPO clip loss + c1 * 0.5 * squared value error - c2 entropy
   + c3 (KL of the actor and critic genomes, ``sgb.rl.networks.network_kl``:
   per type pair, so its cost is that of the tables). The entropy is that of
   the squashed action tanh(u), estimated at one reparameterised draw (as
   Brax's PPO does). Advantages by GAE, normalised over the valid steps.

The vanilla network is the special case with no sampling and no KL.
"""

import time
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import optax
from tqdm.auto import tqdm

from sgb import resume, validation
from sgb.divergence import Guard, likely_cause
from sgb.noise import standard_normal
from sgb.rl.envs import EnvSpec, make_env
from sgb.rl.networks import (
    MLP,
    NetworkConfig,
    Noise,
    action_distribution,
    draw_noise,
    forward,
    individuals,
    network_kl,
    sgb_layers,
    tanh_gaussian_entropy,
    tanh_gaussian_log_prob,
)
from sgb.rl.normalizer import Normalizer, init_normalizer, normalize, update
from sgb.rl.population import compiled_network, population_returns


@dataclass(frozen=True)
class PPOConfig:
    """Hyperparameters of one PPO run; steps are environment steps summed over environments."""

    env: EnvSpec = field(default_factory=EnvSpec)
    network: NetworkConfig = field(default_factory=NetworkConfig)
    total_steps: int = 200_000
    num_envs: int = 128
    unroll_length: int = 16
    num_minibatches: int = 4
    num_epochs: int = 4
    learning_rate: float = 3e-4
    clip: float = 0.3
    value_coef: float = 0.5
    entropy_coef: float = 1e-2
    kl_coef: float = 1e-6
    discount: float = 0.97
    gae_lambda: float = 0.95
    reward_scaling: float = 10.0
    episode_length: int = 1000
    num_evals: int = 5
    eval_individuals: int = 32

    def __post_init__(self) -> None:
        validation.instance("env", self.env, EnvSpec)
        validation.instance("network", self.network, NetworkConfig)
        for name in (
            "total_steps",
            "num_envs",
            "unroll_length",
            "num_minibatches",
            "num_epochs",
            "episode_length",
            "num_evals",
            "eval_individuals",
        ):
            validation.integer(name, getattr(self, name))
        validation.positive("learning_rate", self.learning_rate)
        validation.positive("clip", self.clip)
        validation.in_range("discount", self.discount, 0.0, 1.0, low_open=True)
        validation.in_range("gae_lambda", self.gae_lambda, 0.0, 1.0)
        validation.positive("reward_scaling", self.reward_scaling)
        for name in ("value_coef", "entropy_coef", "kl_coef"):
            validation.non_negative(name, getattr(self, name))
        if self.num_envs % self.num_minibatches:
            raise ValueError(
                f"num_envs={self.num_envs} must be a multiple of num_minibatches="
                f"{self.num_minibatches}"
            )

    @property
    def steps_per_iteration(self) -> int:
        return self.num_envs * self.unroll_length

    @property
    def iterations(self) -> int:
        return max(1, self.total_steps // self.steps_per_iteration)


def compiled_config(config: PPOConfig) -> PPOConfig:
    """``config`` as the static argument of the compiled training step.

    The settings that the step never reads (the initial spread ``rho_init``, used only
    by ``init_state``, and the run's length and evaluations) are set to their defaults,
    so runs that differ only in them share one compilation.
    """
    defaults = PPOConfig()
    return replace(
        config,
        network=compiled_network(config.network),
        total_steps=defaults.total_steps,
        num_evals=defaults.num_evals,
        eval_individuals=defaults.eval_individuals,
    )


class Params(NamedTuple):
    actor: dict
    critic: dict


class TrainState(NamedTuple):
    params: Params
    opt_state: optax.OptState
    normalizer: Normalizer
    env_state: object
    steps: jnp.ndarray  # (E,) steps into the current episode
    finished: jnp.ndarray  # (E,) 1.0 where the episode ended
    actor_noise: Noise | None  # per SGB layer (E, n_in, n_out), drawn at each birth
    critic_noise: Noise | None  # None for vanilla networks
    key: jax.Array


class Unroll(NamedTuple):
    obs: jnp.ndarray  # (E, T, obs)
    u: jnp.ndarray  # (E, T, act) pre-tanh actions
    log_prob: jnp.ndarray  # (E, T)
    reward: jnp.ndarray
    done: jnp.ndarray
    truncation: jnp.ndarray
    valid: jnp.ndarray
    last_obs: jnp.ndarray  # (E, obs)
    actor_noise: Noise | None  # per SGB layer (E, n_in, n_out); None for vanilla
    critic_noise: Noise | None


@dataclass
class TrainResult:
    """Trained parameters, observation statistics and the learning curve."""

    config: PPOConfig
    params: Params
    normalizer: Normalizer
    eval_steps: list[int]
    eval_returns: list[float]
    train_steps_per_s: float
    wall_time_s: float


def _models(config: PPOConfig):
    env = make_env(config.env)
    n_obs = env.observation_size
    return env, MLP(config.network, 2 * env.action_size, n_obs), MLP(config.network, 1, n_obs)


def _births(
    ts: TrainState, config: PPOConfig, fresh: jnp.ndarray, key: jax.Array
) -> tuple[Noise | None, Noise | None]:
    """Actor and critic noise with a new individual for every ``fresh`` environment.

    Only newborns draw, one after another; the others keep their noise.
    The individual born from key k has the actor of ``draw_noise(actor, ., k)`` and
    the critic of ``draw_noise(critic, ., fold_in(k, 1))``.
    """
    _, actor, critic = _models(config)
    if not config.network.sgb:
        return None, None

    def draw(k: jax.Array) -> tuple[Noise, Noise]:
        return (
            draw_noise(actor, ts.params.actor, k),
            draw_noise(critic, ts.params.critic, jax.random.fold_in(k, 1)),
        )

    keys = jax.random.split(key, config.num_envs)
    born = jnp.nonzero(fresh, size=config.num_envs, fill_value=0)[0]

    def renew(j, noise):
        i = born[j]
        return jax.tree_util.tree_map(lambda n, d: n.at[i].set(d), noise, draw(keys[i]))

    # in place, over the newborns only: the others cost nothing
    return jax.lax.fori_loop(0, jnp.sum(fresh), renew, (ts.actor_noise, ts.critic_noise))


def gae(reward, value, next_value, done, truncation, discount, lam):
    """Policy advantages and value targets along the last axis (time).

    The value targets are the lambda-returns G_t = V(s_t) + A_t, with A_t the GAE(lambda)
    advantages. The policy's advantage is the one-step advantage towards the next
    lambda-return, r_t + discount * G_{t+1} - V(s_t) = delta_t + discount * A_{t+1}, as
    Brax's PPO computes it (measured on the Ant: GAE(lambda) itself left two of three
    seeds standing at 2M steps). ``value``/``next_value``: V(s_t), V(s_{t+1}); terminal
    steps (done and not truncated) do not bootstrap; truncated steps bootstrap from
    s_{t+1}; the last step's G_{t+1} is V(s_{t+1}).
    """
    terminal = done * (1.0 - truncation)
    delta = reward + discount * (1.0 - terminal) * next_value - value

    def back(carry, x):
        d, nd = x
        carry = d + discount * lam * nd * carry
        return carry, carry

    xs = (jnp.moveaxis(delta, -1, 0), jnp.moveaxis(1.0 - done, -1, 0))
    _, adv = jax.lax.scan(back, jnp.zeros(delta.shape[:-1]), xs, reverse=True)
    adv = jnp.moveaxis(adv, 0, -1)
    next_adv = jnp.concatenate([adv[..., 1:], jnp.zeros_like(adv[..., :1])], axis=-1)
    return delta + discount * (1.0 - done) * next_adv, adv + value


def _masked_mean(x, mask):
    return jnp.sum(x * mask) / jnp.maximum(jnp.sum(mask), 1.0)


def _loss(params: Params, data: Unroll, normalizer: Normalizer, key: jax.Array, config: PPOConfig):
    _, actor, critic = _models(config)
    a_layers = individuals(actor, params.actor, data.actor_noise)
    c_layers = individuals(critic, params.critic, data.critic_noise)
    obs = normalize(normalizer, data.obs)
    all_obs = jnp.concatenate([obs, normalize(normalizer, data.last_obs)[:, None]], axis=1)
    values = forward(c_layers, all_obs)[..., 0]
    loc, scale = action_distribution(forward(a_layers, obs))
    log_prob = tanh_gaussian_log_prob(data.u, loc, scale)
    reward = data.reward * config.reward_scaling
    adv, target = gae(
        reward,
        jax.lax.stop_gradient(values[:, :-1]),
        jax.lax.stop_gradient(values[:, 1:]),
        data.done,
        data.truncation,
        config.discount,
        config.gae_lambda,
    )
    mean_adv = _masked_mean(adv, data.valid)
    std_adv = jnp.sqrt(_masked_mean((adv - mean_adv) ** 2, data.valid)) + 1e-8
    adv = (adv - mean_adv) / std_adv
    ratio = jnp.exp(log_prob - data.log_prob)
    clipped = jnp.clip(ratio, 1 - config.clip, 1 + config.clip)
    policy_loss = -_masked_mean(jnp.minimum(ratio * adv, clipped * adv), data.valid)
    value_loss = 0.5 * _masked_mean((values[:, :-1] - target) ** 2, data.valid)
    k_entropy, k_actor, k_critic = jax.random.split(key, 3)
    u = loc + scale * standard_normal(k_entropy, loc.shape)  # reparameterised, for the entropy
    entropy = _masked_mean(tanh_gaussian_entropy(scale, u), data.valid)
    kl = network_kl(actor, params.actor, k_actor) + network_kl(critic, params.critic, k_critic)
    total = (
        policy_loss
        + config.value_coef * value_loss
        - config.entropy_coef * entropy
        + config.kl_coef * kl
    )
    metrics = {"total": total, "policy": policy_loss, "value": value_loss, "entropy": entropy}
    return total, {**metrics, "kl": kl}


def _optimizer(config: PPOConfig) -> optax.GradientTransformation:
    return optax.adam(config.learning_rate)


def _init_params(config: PPOConfig, key_actor: jax.Array, key_critic: jax.Array) -> Params:
    env, actor, critic = _models(config)
    dummy = jnp.zeros((1, env.observation_size))
    return Params(
        {"params": actor.init({"params": key_actor, "sample": key_actor}, dummy)["params"]},
        {"params": critic.init({"params": key_critic, "sample": key_critic}, dummy)["params"]},
    )


def init_params(config: PPOConfig, seed: int) -> Params:
    """Initial actor and critic parameters for ``seed``, as ``init_state`` makes them."""
    validation.instance("config", config, PPOConfig)
    _, ka, kc, _, _ = jax.random.split(jax.random.PRNGKey(validation.seed("seed", seed)), 5)
    return _init_params(config, ka, kc)


def init_state(config: PPOConfig, seed: int) -> TrainState:
    """Initial parameters, optimizer, environments and individuals for ``seed``."""
    validation.instance("config", config, PPOConfig)
    env, actor, critic = _models(config)
    key = jax.random.PRNGKey(validation.seed("seed", seed))
    key, ka, kc, kr, ki = jax.random.split(key, 5)
    params = _init_params(config, ka, kc)
    env_state = jax.jit(jax.vmap(env.reset))(jax.random.split(kr, config.num_envs))
    # strong types, as the training step returns them (weak types would force a recompile)
    env_state = jax.tree_util.tree_map(_strong, env_state)
    e = config.num_envs
    ts = TrainState(
        params=params,
        opt_state=_optimizer(config).init(params),
        normalizer=init_normalizer(env.observation_size),
        env_state=env_state,
        steps=jnp.zeros(e),
        finished=jnp.zeros(e),
        actor_noise=None,
        critic_noise=None,
        key=key,
    )
    if not config.network.sgb:
        return ts

    def zeros(model: MLP) -> Noise:
        return [jnp.zeros((e, *shape)) for shape in sgb_layers(model).values()]

    ts = ts._replace(actor_noise=zeros(actor), critic_noise=zeros(critic))
    actor_noise, critic_noise = jax.jit(_births, static_argnums=1)(
        ts, compiled_config(config), jnp.ones(e, bool), ki
    )
    return ts._replace(actor_noise=actor_noise, critic_noise=critic_noise)


def _unroll(ts: TrainState, config: PPOConfig) -> tuple[TrainState, Unroll]:
    env, actor, _ = _models(config)
    key, k_reset, k_birth, k_act = jax.random.split(ts.key, 4)
    e = config.num_envs
    fresh = ts.finished > 0

    def reset(env_state):
        resets = jax.vmap(env.reset)(jax.random.split(k_reset, e))

        def pick(new, old):
            return jnp.where(fresh.reshape((e,) + (1,) * (old.ndim - 1)), new, old)

        return jax.tree_util.tree_map(pick, resets, env_state)

    env_state = jax.lax.cond(jnp.any(fresh), reset, lambda env_state: env_state, ts.env_state)
    actor_noise, critic_noise = _births(ts, config, fresh, k_birth)
    steps = jnp.where(fresh, 0.0, ts.steps)
    layers = individuals(actor, ts.params.actor, actor_noise)

    def step(carry, k):
        state, steps, finished = carry
        loc, scale = action_distribution(forward(layers, normalize(ts.normalizer, state.obs)))
        u = loc + scale * standard_normal(k, loc.shape)
        log_prob = tanh_gaussian_log_prob(u, loc, scale)
        nstate = jax.vmap(env.step)(state, jnp.tanh(u))
        steps = steps + 1.0
        truncation = jnp.where(steps >= config.episode_length, 1.0 - nstate.done, 0.0)
        done = jnp.maximum(nstate.done, truncation)
        valid = 1.0 - finished
        out = (state.obs, u, log_prob, nstate.reward, done, truncation, valid)
        return (nstate, steps, jnp.maximum(finished, done)), out

    carry = (env_state, steps, jnp.zeros(e))
    keys = jax.random.split(k_act, config.unroll_length)
    (env_state, steps, finished), out = jax.lax.scan(step, carry, keys)
    out = [jnp.swapaxes(x, 0, 1) for x in out]
    data = Unroll(*out, last_obs=env_state.obs, actor_noise=actor_noise, critic_noise=critic_noise)
    ts = ts._replace(
        env_state=env_state,
        steps=steps,
        finished=finished,
        actor_noise=actor_noise,
        critic_noise=critic_noise,
        key=key,
    )
    return ts, data


def _sgd(ts: TrainState, data: Unroll, config: PPOConfig):
    optimizer = _optimizer(config)
    key, k_perm = jax.random.split(ts.key)
    grad_fn = jax.value_and_grad(_loss, has_aux=True)

    def minibatch(carry, xs):
        params, opt_state = carry
        idx, k = xs
        batch = jax.tree_util.tree_map(lambda x: x[idx], data)
        (_, metrics), grads = grad_fn(params, batch, ts.normalizer, k, config)
        updates, opt_state = optimizer.update(grads, opt_state, params)
        return (optax.apply_updates(params, updates), opt_state), metrics

    def epoch(carry, k):
        k_perm, k_entropy = jax.random.split(k)
        perm = jax.random.permutation(k_perm, config.num_envs)
        keys = jax.random.split(k_entropy, config.num_minibatches)
        return jax.lax.scan(minibatch, carry, (perm.reshape(config.num_minibatches, -1), keys))

    carry = (ts.params, ts.opt_state)
    (params, opt_state), metrics = jax.lax.scan(
        epoch, carry, jax.random.split(k_perm, config.num_epochs)
    )
    metrics = jax.tree_util.tree_map(jnp.mean, metrics)
    return ts._replace(params=params, opt_state=opt_state, key=key), metrics


@partial(jax.jit, static_argnames=("config", "n"))
def train_iterations(ts: TrainState, config: PPOConfig, n: int):
    """``n`` PPO iterations (unroll, normaliser update, SGD) in one jitted call; the
    metrics of every iteration, shape (n,) each."""

    def body(ts, _):
        ts, data = _unroll(ts, config)
        ts = ts._replace(normalizer=update(ts.normalizer, data.obs, data.valid))
        return _sgd(ts, data, config)

    ts, metrics = jax.lax.scan(body, ts, None, n)
    # Brax's step returns a few weakly typed leaves; strong types keep the next call's
    # signature equal to this one's, so it does not compile again.
    ts = ts._replace(env_state=jax.tree_util.tree_map(_strong, ts.env_state))
    return ts, metrics


def _check_divergence(
    guard: Guard, metrics: dict, params: Params, done: int, config: PPOConfig
) -> None:
    """Raise ``TrainingDiverged`` naming the first iteration (after ``done`` earlier ones)
    whose loss is not finite or blew up (``guard``), or the first non-finite parameter."""
    losses = np.asarray(metrics["total"])
    step = config.steps_per_iteration
    guard.losses(losses, (done + 1) * step, step)
    guard.params(params, (done + len(losses)) * step)


def _guard(holder: dict) -> Guard:
    """The divergence guard of a PPO run whose current state is ``holder["ts"]``: its
    likely causes are observations holding nan or inf, rho overflow, or the learning rate."""

    def cause() -> str:
        ts = holder["ts"]
        stats = {"the observations' running mean": ts.normalizer.mean}
        stats["their running squared deviations"] = ts.normalizer.m2
        return likely_cause(data=stats, params=ts.params)

    return Guard("PPO loss", cause=cause)


def _strong(x: jnp.ndarray) -> jnp.ndarray:
    """``x`` with the same dtype but no weak type."""
    return jnp.asarray(x, dtype=x.dtype)


def evaluate(config: PPOConfig, params: Params, normalizer: Normalizer, seed: int) -> float:
    """Mean innate return of ``eval_individuals`` individuals, one full episode each."""
    validation.instance("config", config, PPOConfig)
    validation.instance("params", params, Params)
    returns = population_returns(
        config.env,
        config.network,
        params.actor,
        normalizer,
        config.eval_individuals,
        1,
        config.episode_length,
        seed=seed,
    )
    return float(np.mean(returns))


def train(
    config: PPOConfig,
    seed: int = 0,
    progress: bool = True,
    state_file: str | Path | None = None,
    label: str = "PPO",
) -> TrainResult:
    """Train with PPO; evaluates ``num_evals`` times, the last one after the final update.

    Runs ``num_evals`` chunks of ``iterations // num_evals`` iterations (so
    the steps trained are ``total_steps`` rounded down to a whole number of
    chunks).
    ``train_steps_per_s`` counts environment steps of training only (after the
    first, compiling, chunk of each sitting; evaluations excluded).

    With ``state_file``, the whole training state is saved there after every chunk
    (``sgb.resume``), and a call that finds the file continues from it: killed and
    started again, the run ends with the result of an uninterrupted one. The file is
    left in place (a finished one makes the call return at once); the caller removes it
    once the result is kept. A state file that is damaged, or holds parameters that are
    not finite, is a ``sgb.validation.CorruptFile`` naming it. ``label`` names the run on
    its progress bar. Training stops (``sgb.divergence.TrainingDiverged``) when the loss
    is not finite or its magnitude exceeds ``sgb.divergence.BLOWUP_FACTOR`` times that of
    the first one of this call.
    """
    start = time.perf_counter()
    ts = init_state(config, seed)
    run = {"config": repr(config), "seed": seed}
    done = {
        "chunks": 0,
        "eval_steps": [],
        "eval_returns": [],
        "timed_steps": 0,
        "timed_s": 0.0,
        "wall_time_s": 0.0,
    }
    if state_file is not None and Path(state_file).exists():
        ts, done = resume.load(
            state_file,
            ts,
            run,
            progress_keys=tuple(done),
            finite=lambda ts: (ts.params, ts.normalizer),
        )
    holder = {"ts": ts}
    guard = _guard(holder)
    chunk = max(1, config.iterations // config.num_evals)
    first = done["chunks"]
    step_config = compiled_config(config)
    for i in tqdm(
        range(first, config.num_evals),
        desc=label,
        initial=first,
        total=config.num_evals,
        disable=not progress,
    ):
        t0 = time.perf_counter()
        ts, metrics = train_iterations(ts, step_config, chunk)
        holder["ts"] = ts
        _check_divergence(guard, metrics, ts.params, i * chunk, config)
        if i > first or config.num_evals - first == 1:
            done["timed_s"] += time.perf_counter() - t0
            done["timed_steps"] += chunk * config.steps_per_iteration
        done["eval_steps"].append((i + 1) * chunk * config.steps_per_iteration)
        done["eval_returns"].append(evaluate(config, ts.params, ts.normalizer, seed + 10_000 + i))
        done["chunks"] = i + 1
        if state_file is not None:
            elapsed = done["wall_time_s"] + time.perf_counter() - start
            resume.save(state_file, ts, run, {**done, "wall_time_s": elapsed})
    return TrainResult(
        config=config,
        params=ts.params,
        normalizer=ts.normalizer,
        eval_steps=done["eval_steps"],
        eval_returns=done["eval_returns"],
        train_steps_per_s=done["timed_steps"] / max(done["timed_s"], 1e-9),
        wall_time_s=done["wall_time_s"] + time.perf_counter() - start,
    )
