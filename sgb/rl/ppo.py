"""PPO for vanilla and SGB actor-critics on Brax environments: settings, runs, evaluation.

``PPOConfig`` holds a run's settings; ``train`` runs it in chunks of iterations of the
compiled step (``sgb.rl.trainer``: births, unroll, update), evaluating after each chunk,
saving a resumable state and stopping if the loss diverges. The vanilla network is the
special case with no sampling and no KL. A run starts from fresh parameters, or from a
given actor and observation normalizer (``Start``; the critic and the optimizer still
start fresh).
"""

import time
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from tqdm.auto import tqdm

from sgb import resume, validation
from sgb.divergence import Guard, likely_cause
from sgb.genome import layer_sigmas
from sgb.rl.agent import Individual, NetworkConfig, Params
from sgb.rl.envs import EnvSpec
from sgb.rl.losses import LossSettings
from sgb.rl.normalizer import Normalizer, init_normalizer
from sgb.rl.population import check_actor_params, check_normalizer, population_returns
from sgb.rl.trainer import StepSettings, TrainState, make_trainer, strong

REGIMES = ("ours", "authors")
ENTROPY_DRAWS = ("reparameterised", "detached")


@dataclass(frozen=True)
class PPOConfig:
    """Hyperparameters of one PPO run; steps are environment steps summed over environments.

    ``regime`` is ``"ours"`` or ``"authors"`` (``sgb.rl.trainer``, ``sgb.rl.losses``):
    under the authors' an iteration collects ``unrolls_per_iteration`` unrolls of every
    environment (1 under ours), and an evaluation is their window return
    (``Trainer.window_return``) over ``eval_individuals`` environments, each step a new draw.
    ``entropy_draw`` is how the loss draws the entropy's action (``sgb.rl.losses``);
    ``eval_at_start`` evaluates the initial parameters too, at step 0, as the authors do.
    ``interim_eval_individuals`` (``None``: ``eval_individuals``) is how many the evaluations
    before the last use: what a run trains does not depend on it (``trains_as``), only what
    its intermediate evaluations cost and how precise they are.
    """

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
    regime: str = "ours"
    unrolls_per_iteration: int = 1
    entropy_draw: str = "reparameterised"
    eval_at_start: bool = False
    interim_eval_individuals: int | None = None

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
            "unrolls_per_iteration",
        ):
            validation.integer(name, getattr(self, name))
        validation.positive("learning_rate", self.learning_rate)
        validation.positive("clip", self.clip)
        validation.in_range("discount", self.discount, 0.0, 1.0, low_open=True)
        validation.in_range("gae_lambda", self.gae_lambda, 0.0, 1.0)
        validation.positive("reward_scaling", self.reward_scaling)
        for name in ("value_coef", "entropy_coef", "kl_coef"):
            validation.non_negative(name, getattr(self, name))
        validation.choice("regime", self.regime, REGIMES)
        validation.choice("entropy_draw", self.entropy_draw, ENTROPY_DRAWS)
        validation.instance("eval_at_start", self.eval_at_start, bool)
        if self.interim_eval_individuals is not None:
            validation.integer("interim_eval_individuals", self.interim_eval_individuals)
        if self.regime == "ours" and self.unrolls_per_iteration != 1:
            raise ValueError("our regime collects one unroll per iteration")
        sequences = self.num_envs * self.unrolls_per_iteration
        if sequences % self.num_minibatches:
            raise ValueError(
                f"num_envs x unrolls_per_iteration = {sequences} must be a multiple of "
                f"num_minibatches={self.num_minibatches}"
            )
        if self.total_steps // self.steps_per_iteration < self.num_evals:
            raise ValueError(
                f"total_steps={self.total_steps} must hold at least one iteration of "
                f"{self.steps_per_iteration} steps per evaluation (num_evals={self.num_evals})"
            )

    def eval_size(self, last: bool) -> int:
        """Individuals (environments, under the authors' regime) of the last evaluation
        (``last``) or of one before it."""
        if last or self.interim_eval_individuals is None:
            return self.eval_individuals
        return self.interim_eval_individuals

    def trains_as(self, other: "PPOConfig") -> bool:
        """Whether ``other`` trains what this config trains and scores it with the same last
        evaluation: the two differ at most in their intermediate evaluations' size."""
        validation.instance("other", other, PPOConfig)
        return replace(self, interim_eval_individuals=other.interim_eval_individuals) == other

    @property
    def steps_per_iteration(self) -> int:
        return self.num_envs * self.unroll_length * self.unrolls_per_iteration

    @property
    def iterations(self) -> int:
        return max(1, self.total_steps // self.steps_per_iteration)

    def step_settings(self) -> StepSettings:
        """The settings one training iteration reads, and nothing else."""
        loss = LossSettings(**{name: getattr(self, name) for name in LossSettings._fields})
        copied = {f.name for f in fields(StepSettings)} - {"architecture", "loss"}
        return StepSettings(
            **{name: getattr(self, name) for name in copied},
            architecture=self.network.architecture,
            loss=loss,
        )


class Start(NamedTuple):
    """Where a run starts instead of at fresh parameters: the actor's ``{"params": ...}``,
    of the shapes of the config's network, and the observation normalizer it expects."""

    actor: dict
    normalizer: Normalizer


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
    # per evaluation, the actor's mean sigma per SGB layer (``genome.layer_sigmas``); None
    # for an evaluation made before runs recorded it
    eval_sigmas: list[dict[str, float] | None] = field(default_factory=list)
    # the CPU time of the processes that trained it (s, all their threads; a pause does not
    # count); None for a run resumed from a state saved before runs recorded it
    cpu_time_s: float | None = None


def _keys(seed: int) -> list[jax.Array]:
    """A run's five keys from ``seed``: state, actor, critic, resets, first births."""
    return list(jax.random.split(jax.random.PRNGKey(validation.seed("seed", seed)), 5))


def initial_params(config: PPOConfig, seed: int) -> Params:
    """Initial actor and critic parameters for ``seed``, as ``init_state`` makes them."""
    validation.instance("config", config, PPOConfig)
    _, ka, kc, _, _ = _keys(seed)
    return make_trainer(config.step_settings()).agent.init(ka, kc, config.network)


def _started(params: Params, initial: Start, obs_size: int) -> tuple[Params, Normalizer]:
    """``params`` with ``initial``'s actor, and ``initial``'s normalizer, both checked: the
    actor finite and of the shapes of ``params.actor``, the normalizer of ``obs_size``."""
    validation.instance("initial", initial, Start)
    actor = check_actor_params(initial.actor)
    shapes = [jax.tree_util.tree_map(jnp.shape, p) for p in (actor, params.actor)]
    if shapes[0] != shapes[1]:
        raise ValueError(f"initial.actor must have the shapes {shapes[1]}, got {shapes[0]}")
    normalizer = check_normalizer(initial.normalizer, obs_size)
    # strong types, as the training step returns them (weak types would force a recompile)
    actor, normalizer = jax.tree_util.tree_map(
        lambda x: strong(jnp.asarray(x)), (actor, normalizer)
    )
    return params._replace(actor=actor), normalizer


def init_state(config: PPOConfig, seed: int, initial: Start | None = None) -> TrainState:
    """Initial parameters, optimizer, environments and individuals for ``seed``; with
    ``initial``, its actor and normalizer in place of the fresh ones."""
    validation.instance("config", config, PPOConfig)
    trainer = make_trainer(config.step_settings())
    env = trainer.env
    key, ka, kc, kr, ki = _keys(seed)
    params = trainer.agent.init(ka, kc, config.network)
    normalizer = init_normalizer(env.observation_size)
    if initial is not None:
        params, normalizer = _started(params, initial, env.observation_size)
    env_state = jax.jit(jax.vmap(env.reset))(jax.random.split(kr, config.num_envs))
    # strong types, as the training step returns them (weak types would force a recompile)
    env_state = jax.tree_util.tree_map(strong, env_state)
    e = config.num_envs
    kept = config.network.sgb and config.regime == "ours"
    individual = trainer.first_births(ki) if kept else Individual(None, None)
    return TrainState(
        params=params,
        opt_state=trainer.optimizer.init(params),
        normalizer=normalizer,
        env_state=env_state,
        steps=jnp.zeros(e),
        finished=jnp.zeros(e),
        individual=individual,
        key=key,
        start_state=env_state if config.regime == "authors" else None,
    )


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


def evaluate(
    config: PPOConfig, params: Params, normalizer: Normalizer, seed: int, last: bool = True
) -> float:
    """Mean innate return of ``config.eval_size(last)`` individuals, one full episode each;
    under the authors' regime, their window return over as many environments."""
    validation.instance("config", config, PPOConfig)
    validation.instance("params", params, Params)
    size = config.eval_size(last)
    if config.regime == "authors":
        trainer = make_trainer(config.step_settings())
        key = jax.random.PRNGKey(validation.seed("seed", seed))
        return float(trainer.window_return(params, normalizer, key, size))
    returns = population_returns(
        config.env,
        config.network,
        params.actor,
        normalizer,
        size,
        1,
        config.episode_length,
        seed=seed,
    )
    return float(np.mean(returns))


def _kept(ts: TrainState, config: PPOConfig) -> TrainState:
    """What a state file keeps of ``ts`` between chunks: all of it, or under the authors'
    regime all but the environments' states, which every chunk resets (``restart_all``)
    from the kept key; so the file is some kilobytes, not megabytes, and travels."""
    if config.regime == "authors":
        return ts._replace(env_state=None, start_state=None)
    return ts


def state_agent(path: str | Path, config: PPOConfig, seed: int) -> tuple[dict, Normalizer]:
    """The actor parameters and observation normalizer of the training state at ``path``
    (a state file or one ``train`` kept) of ``config`` trained with ``seed``; a
    ValueError if the file belongs to another run."""
    template = _kept(init_state(config, seed), config)
    run = {"config": repr(config), "seed": seed}
    ts, _ = resume.load(path, template, run, finite=lambda ts: (ts.params, ts.normalizer))
    return ts.params.actor, ts.normalizer


def train(
    config: PPOConfig,
    seed: int = 0,
    progress: bool = True,
    state_file: str | Path | None = None,
    label: str = "PPO",
    initial: Start | None = None,
    keep: dict[int, Path] | None = None,
) -> TrainResult:
    """Train with PPO; evaluates ``num_evals`` times, the last one after the final update
    (and first at step 0 with ``eval_at_start``). With ``initial`` the run starts from its
    actor and normalizer (``init_state``).

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
    not finite, is a ``sgb.validation.CorruptFile`` naming it. Under the authors' regime it
    does not hold the environments' states (``_kept``). ``label`` names the run on
    its progress bar. Training stops (``sgb.divergence.TrainingDiverged``) when the loss
    is not finite or its magnitude exceeds ``sgb.divergence.BLOWUP_FACTOR`` times that of
    the first one of this call. A state file is known by the run's config and seed only:
    runs from different ``initial`` starts need files of their own. ``keep`` (chunk ->
    path): the state after that chunk is also written there and kept, the agent as it was
    at that point of training (``state_agent``); what is trained is the same.
    """
    start, cpu_start = time.perf_counter(), time.process_time()
    ts = init_state(config, seed, initial)
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
        kept, done = resume.load(
            state_file,
            _kept(ts, config),
            run,
            progress_keys=tuple(done),
            finite=lambda ts: (ts.params, ts.normalizer),
        )
        # a state saved before runs recorded their spreads has none for its chunks, and
        # one saved before they recorded their CPU time leaves the run's unknown
        done.setdefault("eval_sigmas", [None] * len(done["eval_steps"]))
        done.setdefault("cpu_time_s", None)
        ts = (
            kept._replace(env_state=ts.env_state, start_state=ts.start_state)
            if (config.regime == "authors")
            else kept
        )
    done.setdefault("eval_sigmas", [])
    done.setdefault("cpu_time_s", 0.0)

    def spent() -> dict:  # the wall and CPU time of the run so far, this call's added
        cpu = done["cpu_time_s"]
        return {
            "wall_time_s": done["wall_time_s"] + time.perf_counter() - start,
            "cpu_time_s": None if cpu is None else cpu + time.process_time() - cpu_start,
        }

    holder = {"ts": ts}
    guard = _guard(holder)
    chunk = max(1, config.iterations // config.num_evals)
    first = done["chunks"]
    trainer = make_trainer(config.step_settings())
    if config.eval_at_start and not done["eval_steps"]:
        done["eval_steps"].append(0)
        first_return = evaluate(config, ts.params, ts.normalizer, seed + 9_999, last=False)
        done["eval_returns"].append(first_return)
        done["eval_sigmas"].append(layer_sigmas(ts.params.actor))
    for i in tqdm(
        range(first, config.num_evals),
        desc=label,
        initial=first,
        total=config.num_evals,
        disable=not progress,
    ):
        t0 = time.perf_counter()
        ts, metrics = trainer.iterations(ts, chunk)
        holder["ts"] = ts
        _check_divergence(guard, metrics, ts.params, i * chunk, config)
        if i > first or config.num_evals - first == 1:
            done["timed_s"] += time.perf_counter() - t0
            done["timed_steps"] += chunk * config.steps_per_iteration
        done["eval_steps"].append((i + 1) * chunk * config.steps_per_iteration)
        last = i + 1 == config.num_evals
        ret = evaluate(config, ts.params, ts.normalizer, seed + 10_000 + i, last=last)
        done["eval_returns"].append(ret)
        done["eval_sigmas"].append(layer_sigmas(ts.params.actor))
        done["chunks"] = i + 1
        so_far = spent()
        for path in [state_file, (keep or {}).get(i + 1)]:
            if path is not None:
                resume.save(path, _kept(ts, config), run, {**done, **so_far})
    return TrainResult(
        config=config,
        params=ts.params,
        normalizer=ts.normalizer,
        eval_steps=done["eval_steps"],
        eval_returns=done["eval_returns"],
        train_steps_per_s=done["timed_steps"] / max(done["timed_s"], 1e-9),
        eval_sigmas=done["eval_sigmas"],
        **spent(),
    )
