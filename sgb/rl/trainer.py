"""The PPO training step, built once per ``StepSettings`` (``make_trainer``).

One training iteration:

1. *Births.* Every parallel environment whose episode ended during the last
   unroll is reset, and a new individual is born for it from a fresh PRNG key
   (``sgb.rl.agent.Agent.birth``): the weight noise of its actor and critic,
   kept for its whole life. So an individual lives exactly one episode, and each
   of the ``num_envs`` environments runs its own individual.
2. *Unroll.* Each environment runs ``unroll_length`` steps. Actions are
   tanh(u), u ~ N(loc, scale) from the individual's policy. An environment
   whose episode ends waits, masked out, until the unroll is over (no
   auto-reset), so one unroll of one environment is always played by one
   individual. Episodes are cut at ``episode_length`` steps (truncation:
   the value of the last state is bootstrapped).
3. *Update.* ``num_epochs`` passes over the unrolls in ``num_minibatches``
   minibatches of environments, each a step of Adam on ``sgb.rl.losses.ppo_loss``.

That is our regime (``regime="ours"``). The authors' regime (``regime="authors"``;
their ``RL/training_torch.py`` and ``RL/models.py``) differs in three ways:

- *Redraws.* Every environment step draws one actor from the genome
  (``Network.draw``), shared by all environments; no individual is kept.
- *Resets on the spot.* An environment whose episode ends starts again at once from
  the state its episode began in (Brax's ``AutoResetWrapper``), and every chunk of
  iterations begins with all environments reset (their ``env.reset()`` per block).
- *Batches of unrolls.* An iteration collects ``unrolls_per_iteration`` unrolls of
  every environment before the update, whose minibatches are drawn from all of them.

The loss follows the regime too (``sgb.rl.losses``).

``StepSettings`` is the part of a run's settings that an iteration reads: runs that
differ only in the rest (their length, their evaluations, how their genome starts)
share one ``Trainer`` and its compiled step, and the step cannot read what it is not
given.
"""

from dataclasses import dataclass
from functools import cache, cached_property
from typing import NamedTuple

import jax
import jax.numpy as jnp
import optax

from sgb import genome, validation
from sgb.noise import standard_normal
from sgb.rl.agent import (
    Agent,
    Architecture,
    Individual,
    Layers,
    Params,
    make_agent,
    tanh_gaussian_log_prob,
)
from sgb.rl.envs import EnvSpec, make_env
from sgb.rl.losses import LossSettings, Unroll, ppo_loss
from sgb.rl.normalizer import Normalizer, update


@dataclass(frozen=True)
class StepSettings:
    """What a training iteration reads: ``PPOConfig`` less the run's length, its
    evaluations and the genome's initial values (``NetworkConfig.rho_init``, ``mean_init``)."""

    env: EnvSpec
    architecture: Architecture
    num_envs: int
    unroll_length: int
    unrolls_per_iteration: int
    regime: str
    num_minibatches: int
    num_epochs: int
    learning_rate: float
    episode_length: int
    loss: LossSettings


class TrainState(NamedTuple):
    params: Params
    opt_state: optax.OptState
    normalizer: Normalizer
    env_state: object
    steps: jnp.ndarray  # (E,) steps into the current episode
    finished: jnp.ndarray  # (E,) 1.0 where the episode ended
    individual: Individual  # each environment's player, leading axis E; None for vanilla
    key: jax.Array
    start_state: object = None  # authors' regime: where each environment's episode began


@dataclass(frozen=True, eq=False)
class Trainer:
    """The environment, agent and optimizer of one ``StepSettings``, built once
    (``make_trainer``), and its jitted steps."""

    settings: StepSettings

    @cached_property
    def env(self):
        return make_env(self.settings.env)

    @cached_property
    def agent(self) -> Agent:
        env = self.env
        return make_agent(self.settings.architecture, env.observation_size, env.action_size)

    @cached_property
    def optimizer(self) -> optax.GradientTransformation:
        return optax.adam(self.settings.learning_rate)

    def births(self, individual: Individual, fresh: jnp.ndarray, key: jax.Array) -> Individual:
        """``individual`` with a newborn in every ``fresh`` environment, born from
        ``split(key, num_envs)[i]`` for environment i. Only newborns draw, one after
        another; the others keep their noise."""
        e = self.settings.num_envs
        if not self.settings.architecture.sgb:
            return individual
        keys = jax.random.split(key, e)
        born = jnp.nonzero(fresh, size=e, fill_value=0)[0]

        def renew(j, noise):
            i = born[j]
            new = self.agent.birth(keys[i])
            return jax.tree_util.tree_map(lambda n, d: n.at[i].set(d), noise, new)

        # in place, over the newborns only: the others cost nothing
        return jax.lax.fori_loop(0, jnp.sum(fresh), renew, individual)

    @cached_property
    def first_births(self):
        """Jitted: every environment's first individual from a key, environment i's born
        from ``split(key, num_envs)[i]`` as ``births`` would give it."""
        e = self.settings.num_envs
        return jax.jit(lambda key: jax.vmap(self.agent.birth)(jax.random.split(key, e)))

    def acting_actor(
        self, actor_params: dict, individual: genome.Noise | None, key: jax.Array
    ) -> Layers:
        """The actor phenotypes that act at one step: under our regime the environments'
        own individuals (``individual``, leading axis E); under the authors' one actor
        drawn from ``key``, shared by every environment."""
        if self.settings.regime == "authors":
            return self.agent.actor.layers(actor_params, self.agent.actor.draw(key))
        return self.agent.actor.layers(actor_params, individual)

    def act(self, actor: Layers, normalizer, state, steps: jnp.ndarray, key: jax.Array):
        """One step of every environment under the phenotypes ``actor``: sampled pre-tanh
        actions u and their log-densities, the next states, the steps into each episode,
        and the done and truncation flags (an episode cut at ``episode_length``)."""
        loc, scale = self.agent.policy(actor, normalizer, state.obs)
        u = loc + scale * standard_normal(key, loc.shape)
        log_prob = tanh_gaussian_log_prob(u, loc, scale)
        nstate = jax.vmap(self.env.step)(state, jnp.tanh(u))
        steps = steps + 1.0
        truncation = jnp.where(steps >= self.settings.episode_length, 1.0 - nstate.done, 0.0)
        return u, log_prob, nstate, steps, jnp.maximum(nstate.done, truncation), truncation

    def unroll(self, ts: TrainState) -> tuple[TrainState, Unroll]:
        """Our regime's unroll: every environment played by its own individual."""
        env, s = self.env, self.settings
        key, k_reset, k_birth, k_act = jax.random.split(ts.key, 4)
        e = s.num_envs
        fresh = ts.finished > 0

        def reset(env_state):
            resets = jax.vmap(env.reset)(jax.random.split(k_reset, e))

            def pick(new, old):
                return jnp.where(fresh.reshape((e,) + (1,) * (old.ndim - 1)), new, old)

            return jax.tree_util.tree_map(pick, resets, env_state)

        env_state = jax.lax.cond(jnp.any(fresh), reset, lambda state: state, ts.env_state)
        individual = self.births(ts.individual, fresh, k_birth)
        steps = jnp.where(fresh, 0.0, ts.steps)
        actor = self.acting_actor(ts.params.actor, individual.actor, k_birth)

        def step(carry, k):
            state, steps, finished = carry
            u, log_prob, nstate, steps, done, truncation = self.act(
                actor, ts.normalizer, state, steps, k
            )
            valid = 1.0 - finished
            out = (state.obs, u, log_prob, nstate.reward, done, truncation, valid)
            return (nstate, steps, jnp.maximum(finished, done)), out

        carry = (env_state, steps, jnp.zeros(e))
        keys = jax.random.split(k_act, s.unroll_length)
        (env_state, steps, finished), out = jax.lax.scan(step, carry, keys)
        out = [jnp.swapaxes(x, 0, 1) for x in out]
        data = Unroll(*out, last_obs=env_state.obs, individual=individual)
        ts = ts._replace(
            env_state=env_state, steps=steps, finished=finished, individual=individual, key=key
        )
        return ts, data

    def shared_step(self, params: Params, normalizer, start_state):
        """The authors' regime's environment step ``(state, steps), key -> (state, steps),
        (obs, u, log_prob, reward, done, truncation, metrics)``, for states (E,): one actor
        drawn for all E, actions sampled, ended episodes restarted from ``start_state``;
        ``metrics`` are the environment's of the step (Brax's ``State.metrics``)."""

        def step(carry, k):
            state, steps = carry
            k_draw, k_u = jax.random.split(k)
            actor = self.acting_actor(params.actor, None, k_draw)
            u, log_prob, nstate, steps, done, truncation = self.act(
                actor, normalizer, state, steps, k_u
            )
            out = (state.obs, u, log_prob, nstate.reward, done, truncation, nstate.metrics)

            def restart(first, now):
                return jnp.where(done.reshape(done.shape + (1,) * (now.ndim - 1)) > 0, first, now)

            nstate = jax.tree_util.tree_map(restart, start_state, nstate)
            return (nstate, jnp.where(done > 0, 0.0, steps)), out

        return step

    def shared_unroll(self, ts: TrainState) -> tuple[TrainState, Unroll]:
        """The authors' regime's unroll: ``unroll_length`` steps of ``shared_step``."""
        key, k_act = jax.random.split(ts.key)
        step = self.shared_step(ts.params, ts.normalizer, ts.start_state)
        keys = jax.random.split(k_act, self.settings.unroll_length)
        (env_state, steps), (*out, _) = jax.lax.scan(step, (ts.env_state, ts.steps), keys)
        out = [jnp.swapaxes(x, 0, 1) for x in out]
        data = Unroll(
            *out,
            valid=jnp.ones_like(out[2]),
            last_obs=env_state.obs,
            individual=Individual(None, None),
        )
        return ts._replace(env_state=env_state, steps=steps, key=key), data

    def collect(self, ts: TrainState) -> tuple[TrainState, Unroll]:
        """One iteration's data: our regime's unroll, or the authors' regime's
        ``unrolls_per_iteration`` unrolls of every environment, as (U * E, T, ...)."""
        if self.settings.regime == "ours":
            return self.unroll(ts)
        ts, data = jax.lax.scan(
            lambda ts, _: self.shared_unroll(ts), ts, None, self.settings.unrolls_per_iteration
        )
        return ts, jax.tree_util.tree_map(lambda x: x.reshape(-1, *x.shape[2:]), data)

    def restart_all(self, ts: TrainState) -> TrainState:
        """The authors' regime's start of a chunk: every environment reset, each to a new
        initial state that its episodes restart from."""
        key, k_reset = jax.random.split(ts.key)
        env_state = jax.vmap(self.env.reset)(jax.random.split(k_reset, self.settings.num_envs))
        steps = jnp.zeros(self.settings.num_envs)
        return ts._replace(env_state=env_state, start_state=env_state, steps=steps, key=key)

    def _window(self, params: Params, normalizer, key: jax.Array, n_envs: int):
        """The authors' evaluation window (``eval_unroll`` in ``RL/training_torch.py``):
        ``n_envs`` environments play ``episode_length`` steps under the authors' regime (a
        new draw every step, sampled actions, ended episodes restarted); the reward and
        done of every step, (T, E) each, and the environment's metrics, (T, E) each."""
        k_reset, k_act = jax.random.split(key)
        state = jax.vmap(self.env.reset)(jax.random.split(k_reset, n_envs))
        step = self.shared_step(params, normalizer, state)
        keys = jax.random.split(k_act, self.settings.episode_length)
        _, (_, _, _, reward, done, _, metrics) = jax.lax.scan(
            step, (state, jnp.zeros(n_envs)), keys
        )
        return reward, done, metrics

    @cached_property
    def window_return(self):
        """Jitted ``(params, normalizer, key, n_envs) -> return``: the summed reward over
        the episodes ended in the authors' evaluation window (``_window``), per episode."""

        def run(params: Params, normalizer, key: jax.Array, n_envs: int) -> jnp.ndarray:
            reward, done, _ = self._window(params, normalizer, key, n_envs)
            return jnp.sum(reward) / jnp.maximum(jnp.sum(done), 1.0)

        return jax.jit(run, static_argnames="n_envs")

    @cached_property
    def window_gait(self):
        """Jitted ``(params, normalizer, key, n_envs) -> (return, per_env)``: on the window
        of ``window_return`` (the same key plays the same steps), its return and, for each
        environment, shape (E,) each: ``velocity``, the mean forward velocity (m/s, Brax's
        ``x_velocity``); ``episodes``, the episodes that ended in the window; ``reward``
        and ``control_cost`` (Brax's ``-reward_ctrl``), means per step. The return is
        ``episode_length * sum(reward) / sum(episodes)``. An environment whose agent falls
        k >= 1 times ends k episodes in the window (the one it restarts does not end there),
        one that never falls ends one: every fall after the first divides the return."""

        def run(params: Params, normalizer, key: jax.Array, n_envs: int):
            reward, done, metrics = self._window(params, normalizer, key, n_envs)
            ret = jnp.sum(reward) / jnp.maximum(jnp.sum(done), 1.0)
            per_env = {
                "velocity": jnp.mean(metrics["x_velocity"], axis=0),
                "episodes": jnp.sum(done, axis=0),
                "reward": jnp.mean(reward, axis=0),
                "control_cost": -jnp.mean(metrics["reward_ctrl"], axis=0),
            }
            return ret, per_env

        return jax.jit(run, static_argnames="n_envs")

    def sgd(self, ts: TrainState, data: Unroll) -> tuple[TrainState, dict]:
        s = self.settings
        key, k_perm = jax.random.split(ts.key)
        grad_fn = jax.value_and_grad(ppo_loss, has_aux=True)

        def minibatch(carry, xs):
            params, opt_state = carry
            idx, k = xs
            batch = jax.tree_util.tree_map(lambda x: x[idx], data)
            (_, metrics), grads = grad_fn(params, batch, ts.normalizer, k, self.agent, s.loss)
            updates, opt_state = self.optimizer.update(grads, opt_state, params)
            return (optax.apply_updates(params, updates), opt_state), metrics

        def epoch(carry, k):
            k_perm, k_entropy = jax.random.split(k)
            perm = jax.random.permutation(k_perm, s.num_envs * s.unrolls_per_iteration)
            keys = jax.random.split(k_entropy, s.num_minibatches)
            return jax.lax.scan(minibatch, carry, (perm.reshape(s.num_minibatches, -1), keys))

        carry = (ts.params, ts.opt_state)
        (params, opt_state), metrics = jax.lax.scan(
            epoch, carry, jax.random.split(k_perm, s.num_epochs)
        )
        metrics = jax.tree_util.tree_map(jnp.mean, metrics)
        return ts._replace(params=params, opt_state=opt_state, key=key), metrics

    def seen(self, data: Unroll) -> tuple[jnp.ndarray, jnp.ndarray]:
        """The observations (S, T', obs) the normaliser counts from an iteration's data, and
        their 0/1 weights (S, T'): the valid steps', or under the authors' convention every
        unroll's T + 1, the bootstrap observation too, as their ``update_normalization``
        counts ``td.observation`` (so each unroll's last is counted again as the next's first)."""
        if self.settings.architecture.normalizer == "authors":
            obs = jnp.concatenate([data.obs, data.last_obs[:, None]], axis=1)
            return obs, jnp.ones(obs.shape[:-1])
        return data.obs, data.valid

    @cached_property
    def iterations(self):
        """Jitted ``(ts, n) -> (ts, metrics)``: ``n`` PPO iterations (unroll, normaliser
        update, SGD) in one call, after ``restart_all`` under the authors' regime; the
        metrics of every iteration, shape (n,) each."""

        def run(ts: TrainState, n: int):
            if self.settings.regime == "authors":
                ts = self.restart_all(ts)

            def body(ts, _):
                ts, data = self.collect(ts)
                ts = ts._replace(normalizer=update(ts.normalizer, *self.seen(data)))
                return self.sgd(ts, data)

            ts, metrics = jax.lax.scan(body, ts, None, n)
            # Brax's step returns a few weakly typed leaves; strong types keep the next
            # call's signature equal to this one's, so it does not compile again.
            ts = ts._replace(
                env_state=jax.tree_util.tree_map(strong, ts.env_state),
                start_state=jax.tree_util.tree_map(strong, ts.start_state),
            )
            return ts, metrics

        return jax.jit(run, static_argnames="n")


@cache
def make_trainer(settings: StepSettings) -> Trainer:
    """The one ``Trainer`` of ``settings``: every run with these settings shares its
    compiled steps."""
    validation.instance("settings", settings, StepSettings)
    return Trainer(settings)


def strong(x: jnp.ndarray) -> jnp.ndarray:
    """``x`` with the same dtype but no weak type."""
    return jnp.asarray(x, dtype=x.dtype)
