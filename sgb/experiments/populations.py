"""Beyond Figures 4E and 5 (registered as ``populations``): individuals of several genomes,
with enough episodes to tell them apart.

Figures 4E and 5 rest on one genome whose 100 individuals played 3 episodes each; there
a one-way ANOVA gives F(99, 200) = 1.13, p = 0.24, and the reliability of a 3-episode
mean is about 0.1, so the r and the t of those figures measure episode noise. Here each
genome of Figure 3 with 64 cell types (ours and the authors' settings, seeds 0, 1, 2 at
``cpu``) gets 100 individuals that play E episodes each on the normal and the
long-legged Ant, and its mean network plays the same initial states on the normal Ant.
Actions are deterministic (tanh of the Gaussian mean).

Initial states: individual i's episode e starts from state (i, e), the same in both
bodies and for the mean network (``sgb.rl.population.population_returns`` with one seed
per genome). A cheaper design would give the mean network one episode per episode index,
all individuals sharing those E states (6 x (2 x 100 x 64 + 64) episodes); then the mean
network's own episode noise would set the error of Figure 5's difference. On the
committed ``fig5_ant_cpu.json`` the mean network's episode SD is
about 990 and its return on a shared state correlates with an individual's at only
r = 0.03, so with 64 shared states the difference's SE would be about 990 / sqrt(64) =
124 a genome (and a paired t over individuals would leave that noise out). With the
mean network on every state (i, e) the SE is about sqrt(sd_b^2 / 100 + 1367^2 / (100 E))
= 32 at E = 32 (sd_b about 196, 1367 the SD of one episode's difference on the same
committed file).

Cost (measured on 2 CPU cores that 5 other CPU-bound processes shared, so per
CPU-second): ``population_returns`` on the Ant (``spring``) steps 17,200 to 18,400
envs per CPU-second at batches of 800 to 3,200 envs once compiled, for our genome, the
authors' and the mean network alike (6,900 to 11,300 a wall-second at the 0.4 to 0.7 of
a core the process got); compiling one program takes about 25 CPU-seconds, and there
are 6 (3 parts x 2 network settings). The shared-state design, 6 x (2 x 100 x 64 + 64) x
1000 = 77.2M env-steps, is 74 min of one core; this design at E = 64, 6 x 3 x 100 x 64 x
1000 = 115.2M, 111 min. The ``cpu`` profile plays E = 32: 57.6M env-steps, about 58 min of
one core plus 3 of compiling (E = 48 would take 86). At the committed Figure 4 ICC
(normal 0.041, 95 % interval -0.068 to 0.167; long legs -0.048, -0.145 to 0.070), a
32-episode mean has reliability 0.58 on the normal body (interval 0 to 0.87) and at
most 0.71 on the long legs.

Per genome the results file keeps every return, (N, E) per part (rounded to 0.001), the
variance split and split-half reliability of each body, Figure 4E's r and Figure 5's
paired difference; per genome settings, both pooled over its genomes. A finished part
(a body's individuals, the mean network) is kept in the file, written after every part,
and not evaluated again on a rerun.

Pooled over a setting's genomes, the fixed-effect (inverse-variance) difference and the
Fisher-z r speak for these genomes only. Whether the genomes of a setting differ is the
random-effects check: Cochran's Q, the between-genome variance tau^2, and the Student-t
interval over the genomes' estimates. With 3 genomes it has 2 degrees of freedom: it can
show a spread far larger than the per-genome errors, not rule out one of their size, and
its interval (t = 4.30) is what a claim about the setting's genomes in general must use.
"""

import hashlib
import json
import math
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from scipy import stats as scipy_stats

from sgb import claims, runlock, stats, validation
from sgb.claims import (
    Row,
    genomes_at,
    judge,
    legs_row,
    sd_below,
    stored_test,
    trained_steps,
    variability_row,
)
from sgb.profiles import PROFILE_NAMES, check_profile
from sgb.prose import GENOMES, NOT_RUN, REGIME_STEPS, Card, regime_setting, row_of, row_texts
from sgb.provenance import git_commit, read_results, results_file
from sgb.queued import Queue, QueuedRun, known_sum, run_lock
from sgb.recording import Recording, start
from sgb.reliability import between_sd_at, between_sd_bound, episodes_for, variance_split
from sgb.results import Records
from sgb.rl import regime_runs
from sgb.rl.population import population_returns
from sgb.rl.ppo import PPOConfig, state_agent
from sgb.rl.protocols import load_agent
from sgb.rl.regimes import SETTINGS
from sgb.rl.runs import checkpoint_name, checkpoint_root, finished_run, kept_state
from sgb.schemas import (
    Correlation,
    Count,
    Each,
    Finite,
    List,
    NonNegative,
    Positive,
    Probability,
    Record,
    Reliability,
    ResultsFile,
    Return,
    Returns,
    Seed,
    StoredTest,
)
from sgb.timing import timed

BODIES = ("normal", "long_legs")
PARTS = (*BODIES, "mean_network")  # the mean network plays the normal body
# the authors' protocol, with sampled actions: other individuals on both bodies, and the
# mean network on the normal body on episodes of its own
SAMPLED_BODIES = ("sampled", "long_legs_sampled")
AUTHORS_PARTS = (*SAMPLED_BODIES, "mean_network_sampled")
PROTOCOLS = {"ours": PARTS, "authors": AUTHORS_PARTS}  # protocol -> the parts it plays
TARGET_RELIABILITY = 0.8
DECIMALS = 3  # returns are kept to 0.001


@dataclass(frozen=True)
class Genome:
    """One trained genome: its settings, cell types and training seed; of Figure 3, or
    (``regime=True``) of a run under the authors' training regime at the paper's budget
    (``sgb.experiments.regime``, the authors' genome settings)."""

    settings: str
    seed: int
    cell_types: int = 64
    regime: bool = False
    protocols: tuple[str, ...] = ("ours",)  # of PROTOCOLS, the ones it is evaluated under
    chunk: int | None = None  # a regime genome part-way: the state its run kept after it

    def __post_init__(self) -> None:
        validation.choice("settings", self.settings, SETTINGS)
        validation.integer("seed", self.seed, minimum=0)
        if self.regime and self.settings != "authors":
            raise ValueError("a regime genome has the authors' settings")
        if not self.protocols:
            raise ValueError("a genome is evaluated under at least one protocol")
        for protocol in self.protocols:
            validation.choice("protocol", protocol, tuple(PROTOCOLS))
        if self.chunk is not None and not self.regime:
            raise ValueError("only a regime genome is kept part-way through its training")

    @property
    def parts(self) -> tuple[str, ...]:
        """The parts its protocols play, in the order they are evaluated."""
        return tuple(part for protocol in self.protocols for part in PROTOCOLS[protocol])

    def checkpoint(self, profile: str, env: str = "ant") -> str:
        """The file name of its checkpoint, trained at ``profile`` (of the state its run
        kept, part-way: ``sgb.rl.runs.kept_state``)."""
        name = checkpoint_name(
            env, self.cell_types, self.seed, profile, self.settings, regime=self.regime
        )
        return name if self.chunk is None else kept_state(Path(name), self.chunk).name


@dataclass(frozen=True)
class PopulationsConfig:
    """Which genomes (checkpoints of Figure 3's ``source`` profile), and how many
    individuals, episodes and steps; genome j draws its individuals and initial states
    with seed ``seed + j``."""

    genomes: tuple[Genome, ...]
    n_individuals: int = 100
    episodes: int = 32
    episode_length: int = 1000
    seed: int = 0
    source: str = "cpu"

    def __post_init__(self) -> None:
        validation.instance("genomes", self.genomes, tuple)
        validation.integer("n_individuals", self.n_individuals, minimum=4)  # r needs 4
        validation.integer("episodes", self.episodes, minimum=2)  # the split needs 2
        validation.integer("episode_length", self.episode_length)
        validation.integer("seed", self.seed, minimum=0)
        validation.choice("source", self.source, PROFILE_NAMES)


def genome_label(genome: Genome, env: str = "ant") -> str:
    """The genome's name in the results and the progress: e.g. ``ant_k64_authors_s1``,
    ``ant_regime_k64_s0``, ``ant_regime_k64_s0_chunk2``."""
    label = replace(genome, chunk=None).checkpoint("cpu", env).removesuffix("_cpu.msgpack")
    return label if genome.chunk is None else f"{label}_chunk{genome.chunk}"


def checkpoint_path(genome: Genome, config: PopulationsConfig, env: str = "ant") -> str:
    """The genome's checkpoint, relative to a results directory."""
    return f"rl/checkpoints/{genome.checkpoint(config.source, env)}"


def populations_config(profile: str) -> PopulationsConfig:
    """The design at ``profile``: at ``smoke`` our seed-0 and seed-1 genomes (one network,
    so one set of compiled programs), 4 individuals, 3 episodes of 50 steps; at ``cpu``
    both settings, seeds 0 to 2, 100 individuals x 32 episodes of 1000 steps; at
    ``paper`` seeds 0 to 4 of Figure 3's paper checkpoints, 64 episodes."""
    check_profile(profile)
    if profile == "smoke":
        genomes = (Genome("ours", 0), Genome("ours", 1))
        return PopulationsConfig(genomes, n_individuals=4, episodes=3, episode_length=50)
    seeds = range(3) if profile == "cpu" else range(5)
    genomes = tuple(Genome(settings, seed) for settings in SETTINGS for seed in seeds)
    if profile == "cpu":
        return PopulationsConfig(genomes)
    return PopulationsConfig(genomes, episodes=64, source="paper")


PROFILES = {p: populations_config(p) for p in PROFILE_NAMES}


def regime_populations_config(profile: str) -> PopulationsConfig:
    """Figures 4E and 5 on every SGB genome of the authors' regime at the paper's budget
    (``sgb.rl.regime_runs.grid``: 128 and 16 types at seeds 0-2, in the order they train,
    then 64 types at seeds 0-2) under the authors' protocol, and under ours too for the 64
    types; and the 64-type seed-0 genome after 10^7 steps (the state its run keeps after
    chunk 2) under the authors' protocol: 100 individuals x 64 episodes of 1000 steps at
    ``cpu`` and ``paper``; at
    ``smoke`` the regime's 16-type smoke genome (``reproduce regime --profile smoke`` makes
    it), 4 individuals x 3 episodes of 50."""
    check_profile(profile)
    both = tuple(PROTOCOLS)
    if profile == "smoke":  # the smoke profile trains 16 types
        genomes = (Genome("authors", 0, 16, regime=True, protocols=both),)
        return PopulationsConfig(genomes, 4, 3, 50, source="smoke")
    grid = [r for r in regime_runs.grid() if r.cell_types and r.genome == "authors"]
    genomes = []
    for r in grid:
        protocols = both if r.cell_types == 64 else ("authors",)
        genomes.append(Genome("authors", r.seed, r.cell_types, True, protocols))
        if (r.cell_types, r.seed) == (64, 0):  # the same genome part-way, as its run kept it
            kept = regime_runs.KEPT_CHUNKS[64][0]
            genomes.append(Genome("authors", 0, 64, True, ("authors",), chunk=kept))
    return PopulationsConfig(tuple(genomes), 100, 64, 1000, source=profile)


REGIME_PROFILES = {p: regime_populations_config(p) for p in PROFILE_NAMES}


# Per genome -----------------------------------------------------------------------------


def split_half(returns: np.ndarray) -> dict:
    """Test-retest reliability measured directly: r across individuals between the means
    of the even and the odd episodes (2 h of them, h = E // 2; returns (N, E), N >= 4), its
    Fisher-z interval, and the Spearman-Brown reliability of a 2h-episode mean,
    2r / (1 + r), with the interval's ends transformed alike."""
    x = np.asarray(returns, dtype=np.float64)
    half = x.shape[1] // 2
    test = stats.fisher_r(x[:, 0 : 2 * half : 2].mean(1), x[:, 1 : 2 * half : 2].mean(1))

    def brown(r: float) -> float:
        return 2 * r / (1 + r)

    return {
        "episodes": 2 * half,
        "r": test.estimate,
        "r_ci": (test.low, test.high),
        "reliability": brown(test.estimate),
        "reliability_ci": (brown(test.low), brown(test.high)),
    }


def body_summary(returns: np.ndarray, target: float = TARGET_RELIABILITY) -> dict:
    """One body's returns (N, E): the mean return; the one-way variance split (between and
    within variance, return^2; ICC and the E-episode reliability, 95 % F intervals); the
    episodes a mean needs to reach ``target``; the split-half reliability; and, if the
    reliability is below ``target``, the upper bound on the SD between individuals
    (return units and percent of the mean return)."""
    x = np.asarray(returns, dtype=np.float64)
    split = variance_split(x)
    mean = float(x.mean())
    out = {
        "mean_return": mean,
        "variance_split": split._asdict(),
        "between_sd": math.sqrt(split.between_var),
        "within_sd": math.sqrt(split.within_var),
        "episodes_for_target": episodes_for(split.icc, target),
        "split_half": split_half(x),
    }
    if split.reliability < target:
        bound = between_sd_bound(split)
        out["between_sd_bound"] = bound
        out["between_sd_bound_percent"] = 100 * bound / abs(mean)
    return out


def legs_correlation(normal: np.ndarray, long_legs: np.ndarray) -> dict:
    """Figure 4E: Pearson r of the individuals' E-episode means on the two bodies (N, E)
    each, Fisher-z 95 % interval; and, secondary, r divided by sqrt(rel_normal x
    rel_long) (the ANOVA reliabilities; None when either is <= 0), with the interval's
    ends divided alike (the reliabilities' own uncertainty left out)."""
    normal, long_legs = np.asarray(normal), np.asarray(long_legs)
    test = stats.fisher_r(normal.mean(1), long_legs.mean(1))
    rel = [variance_split(x).reliability for x in (normal, long_legs)]
    factor = math.sqrt(rel[0] * rel[1]) if min(rel) > 0 else math.nan
    return {
        "test": test._asdict(),
        "reliabilities": rel,
        "disattenuated": test.estimate / factor,
        "disattenuated_ci": (test.low / factor, test.high / factor),
    }


def mean_network_difference(individuals: np.ndarray, mean_network: np.ndarray) -> dict:
    """Figure 5: per individual, the mean over its episodes of its return minus the mean
    network's on the same initial state (both (N, E)); their mean with a paired-t 95 %
    interval and standard error (return units), and as percent of the mean network's
    mean return."""
    ind, net = np.asarray(individuals), np.asarray(mean_network)
    if ind.shape != net.shape:
        raise ValueError(f"individuals {ind.shape} and mean network {net.shape} must match")
    test = stats.paired(ind.mean(1), net.mean(1))
    base = float(net.mean())
    se = float(np.std(ind.mean(1) - net.mean(1), ddof=1) / math.sqrt(ind.shape[0]))
    return {
        "test": test._asdict(),
        "se": se,
        "mean_network_return": base,
        "percent": 100 * test.estimate / base,
        "percent_ci": (100 * test.low / base, 100 * test.high / base),
        "percent_se": 100 * se / abs(base),
    }


def authors_comparison(individuals: np.ndarray, mean_network: np.ndarray) -> dict:
    """Figure 5 under the authors' protocol (sampled actions): the individuals' mean
    returns (N, from (N, E)) against the mean network's episodes (any shape, M in all).
    Their test, a one-sample t against the mean network's mean taken as exact, beside
    Welch's t, which counts the mean network's own standard error; the t of each."""
    means = np.asarray(individuals, dtype=np.float64).mean(1)
    episodes = np.ravel(np.asarray(mean_network, dtype=np.float64))
    base = float(episodes.mean())
    one = stats.one_sample(means - base, 0.0)  # the difference, the base taken as exact
    welch = stats.welch(means, episodes)
    se_ind = float(means.std(ddof=1) / math.sqrt(means.size))
    se_net = float(episodes.std(ddof=1) / math.sqrt(episodes.size))
    difference = float(means.mean()) - base
    return {
        "individual_episodes": int(np.shape(individuals)[1]),
        "mean_network_episodes": int(episodes.size),
        "individuals_mean": float(means.mean()),
        "individuals_se": se_ind,
        "mean_network_mean": base,
        "mean_network_se": se_net,
        "one_sample": {**one._asdict(), "t": difference / se_ind},
        "welch": {**welch._asdict(), "t": difference / math.hypot(se_ind, se_net)},
    }


def genome_summary(returns: dict) -> dict:
    """Everything above for one genome's returns ``{part: (N, E)}``: under our protocol
    where ``returns`` holds its parts (``PARTS``), and under the authors' where it holds
    theirs (``authors_protocol``: their Figure 5 comparison, each sampled body's variance
    split and the r between the bodies)."""
    arrays = {part: np.asarray(v, dtype=np.float64) for part, v in returns.items()}
    out = {}
    if set(PARTS) <= set(arrays):
        out |= {
            **{body: body_summary(arrays[body]) for body in BODIES},
            "legs": legs_correlation(arrays["normal"], arrays["long_legs"]),
            "mean_network": mean_network_difference(arrays["normal"], arrays["mean_network"]),
        }
    if set(AUTHORS_PARTS) <= set(arrays):
        normal, long_legs, mean_network = (arrays[p] for p in AUTHORS_PARTS)
        out["authors_protocol"] = {
            **authors_comparison(normal, mean_network),
            "normal": body_summary(normal),
            "long_legs": body_summary(long_legs),
            "legs": legs_correlation(normal, long_legs),
        }
    return out


# Pooled over the genomes of one setting --------------------------------------------------


def pool_setting(summaries: list[dict]) -> dict:
    """Figure 5's difference (return units and percent of the mean network) and Figure
    4E's r pooled over the genome ``summaries`` of one setting, each with the spread over
    genomes beside the pooled value."""
    diffs = [s["mean_network"] for s in summaries]
    legs = [s["legs"]["test"] for s in summaries]
    measures = {
        "mean_network_difference": ([d["test"]["estimate"] for d in diffs], "se"),
        "mean_network_percent": ([d["percent"] for d in diffs], "percent_se"),
    }
    out: dict = {"n_genomes": len(summaries)}
    for key, (values, se) in measures.items():
        out[key] = {
            "fixed_effect": stats.inverse_variance(values, [d[se] for d in diffs]),
            "between_genomes": stats.between_genomes(values),
        }
    rs = [t["estimate"] for t in legs]
    out["legs_r"] = {
        "fixed_effect": stats.pooled_r(rs, [t["n"] for t in legs]),
        "between_genomes": stats.between_genomes_r(rs),
    }
    return out


# Evaluation and the results file ---------------------------------------------------------


def eta_s(elapsed_s: float, done_steps: int, remaining_steps: int) -> float:
    """Seconds left at the rate so far (``nan`` before any step is done)."""
    return remaining_steps * elapsed_s / done_steps if done_steps else math.nan


def _clock(seconds: float) -> str:
    if not math.isfinite(seconds):
        return "unknown until the first part ends"
    return f"{seconds / 60:.0f} min" if seconds >= 90 else f"{seconds:.0f} s"


SAMPLED_SEED_OFFSET = 1000  # the authors' protocol draws its individuals and states apart


def evaluate_part(agent: tuple, part: str, config: PopulationsConfig, seed: int) -> np.ndarray:
    """Returns (N, E) of one part: the individuals on a body, or the mean network on the
    normal body (on the individuals' initial states, row by row); the ``AUTHORS_PARTS``,
    the same with sampled actions, from evaluation seed ``seed + SAMPLED_SEED_OFFSET``
    (other individuals, other states; the same individuals on both bodies). ``agent``:
    (PPO settings, actor parameters, normalizer)."""
    ppo, actor, normalizer = agent
    sampled = part in AUTHORS_PARTS
    body = "long_legs" if part.startswith("long_legs") else "normal"
    returns = population_returns(
        replace(ppo.env, variant=body),
        ppo.network,
        actor,
        normalizer,
        config.n_individuals,
        config.episodes,
        config.episode_length,
        seed=seed + SAMPLED_SEED_OFFSET * sampled,
        mean_network=part.startswith("mean_network"),
        stochastic=sampled,
    )
    return np.round(np.asarray(returns, dtype=np.float64), DECIMALS)


def summarise(results: dict, config: PopulationsConfig) -> dict:
    """``results`` with every finished genome's summary, each regime genome's steps
    trained, the pooled summaries of every setting (our protocol), and whether the design
    is complete."""
    genomes = results["genomes"]
    done = {
        genome_label(g): g
        for g in config.genomes
        if set(g.parts) <= set(genomes.get(genome_label(g), {}).get("parts", {}))
    }
    for genome in config.genomes:
        if genome.regime and genome_label(genome) in genomes:
            genomes[genome_label(genome)]["trained_steps"] = genome_steps(genome, config)
    for label, genome in done.items():
        parts = genomes[label]["parts"]
        genomes[label]["summary"] = genome_summary({p: parts[p]["returns"] for p in genome.parts})
    ours = [genomes[label] for label, g in done.items() if "ours" in g.protocols]
    results["pooled"] = {
        settings: pool_setting([g["summary"] for g in ours if g["settings"] == settings])
        for settings in SETTINGS
        if any(g["settings"] == settings for g in ours)
    }
    results["complete"] = len(done) == len(config.genomes)
    return results


def run(profile: str, out_dir: Path, env: str = "ant") -> Path:
    """Evaluate every genome's parts that the results file does not hold yet, writing
    ``rl/populations_<env>_<profile>.json`` after each; returns its path."""
    if env != "ant":
        raise ValueError(f"env must be 'ant' for populations (the Ant's bodies), got {env!r}")
    return evaluate(start(PROFILES, profile, Path(out_dir) / "rl", "populations_ant"), out_dir)


def run_regime(profile: str, out_dir: Path) -> Path:
    """``run`` for the genome of the authors' regime (``REGIME_PROFILES``), writing
    ``rl/regime_populations_ant_<profile>.json``."""
    rl_dir = Path(out_dir) / "rl"
    return evaluate(start(REGIME_PROFILES, profile, rl_dir, "regime_populations_ant"), out_dir)


def _checkpoint_file(genome: Genome, config: PopulationsConfig, out_dir: Path, env: str) -> Path:
    """``genome``'s checkpoint under ``out_dir``, else the committed one."""
    checkpoint = checkpoint_path(genome, config, env)
    return checkpoint_root(out_dir, checkpoint) / checkpoint


def _regime_ppo(genome: Genome, config: PopulationsConfig) -> PPOConfig:
    """The settings of the regime run that trained ``genome``."""
    run = regime_runs.RegimeRun(genome.cell_types, genome.seed)
    return regime_runs.run_config(regime_runs.RUNS[config.source], run)


def landed(genome: Genome, config: PopulationsConfig, out_dir: Path, env: str = "ant") -> bool:
    """Whether ``genome``'s checkpoint (under ``out_dir``, else the committed one) holds its
    finished training: for a regime genome, a run of the regime as it now trains
    (``sgb.rl.regime_runs.run_config``), not an earlier one under its name."""
    path = _checkpoint_file(genome, config, out_dir, env)
    if not genome.regime or genome.chunk is not None:
        return path.exists()  # a kept state says which run it is of when it is read
    return finished_run(path, _regime_ppo(genome, config)) is not None


def genome_agent(genome: Genome, config: PopulationsConfig, out_dir: Path) -> tuple:
    """(PPO settings, actor parameters, normalizer) of ``genome``: from its checkpoint, or
    for a genome part-way (``Genome.chunk``) from the state its regime run kept."""
    path = _checkpoint_file(genome, config, out_dir, "ant")
    if genome.chunk is None:
        return load_agent(path)
    ppo = _regime_ppo(genome, config)
    return (ppo, *state_agent(path, ppo, genome.seed))


def genome_steps(genome: Genome, config: PopulationsConfig) -> int | None:
    """The environment steps a regime genome trained, nominal for a finished run as its
    settings give them (``None`` for another genome)."""
    if not genome.regime:
        return None
    runs = regime_runs.RUNS[config.source]
    return (
        runs.ppo.total_steps if genome.chunk is None else regime_runs.steps_at(runs, genome.chunk)
    )


def evaluate(recording: Recording, out_dir: Path) -> Path:
    """Evaluate every part of ``recording.config`` that its results file does not hold yet
    (checkpoints under ``out_dir``, else the committed ones), writing the file after each
    part; a genome whose training has not landed (``landed``) waits for a later run. One
    process at a time evaluates into a file (another one returns at once); returns its
    path."""
    path = recording.path
    with runlock.claim(path.with_suffix("")) as mine:
        if not mine:
            print(f"another process is evaluating into {path}; it is left to it", flush=True)
            return path
        return _evaluate(recording, out_dir)


def _evaluate(recording: Recording, out_dir: Path) -> Path:
    env, config, path = "ant", recording.config, recording.path
    name = path.stem.removesuffix(f"_{env}_{recording.profile}")  # the experiment
    results = recording.earlier() or {"env": env, "genomes": {}}
    ready = [g for g in config.genomes if landed(g, config, out_dir, env)]
    for genome in config.genomes:
        if genome not in ready:
            print(f"{name} {genome_label(genome, env)}: its training has not landed; it waits")
    digests = {}
    for genome in ready:
        label, checkpoint = genome_label(genome, env), checkpoint_path(genome, config, env)
        digests[label] = checkpoint_digest(checkpoint_root(out_dir, checkpoint) / checkpoint)
        kept = results["genomes"].get(label, {}).get("checkpoint_sha256")
        if kept is not None and kept != digests[label]:
            print(f"{label}: its checkpoint changed since it was evaluated; evaluated again")
            del results["genomes"][label]
    plan = [(j, g, part) for j, g in enumerate(config.genomes) for part in g.parts]
    steps = config.n_individuals * config.episodes * config.episode_length
    todo = [item for item in plan if item[1] in ready and not _has(results, *item[1:], env)]
    agents: dict[str, tuple] = {}
    for k, (j, genome, part) in enumerate(todo):
        label = genome_label(genome, env)
        eta = eta_s(time.perf_counter() - recording.began, k * steps, (len(todo) - k) * steps)
        count = plan.index((j, genome, part)) + 1
        print(f"{name} {label} {part} ({count}/{len(plan)}): ETA {_clock(eta)}", flush=True)
        if label not in agents:
            agents = {label: genome_agent(genome, config, out_dir)}
        with runlock.exclusive(run_lock(path, label)), timed() as spent:  # held meanwhile
            returns = evaluate_part(agents[label], part, config, config.seed + j)
        record = results["genomes"].setdefault(label, _new_record(genome, j, config, env))
        record["checkpoint_sha256"] = digests[label]
        record["parts"][part] = {
            "returns": returns,
            **spent,
            "env_steps_per_s": round(steps / spent["wall_time_s"], 1),
            "git_commit": git_commit(),
        }
        _write(recording, summarise(results, config))
    if not todo:
        print(f"{name}: every landed genome's parts are in {path}; nothing evaluated", flush=True)
    return _write(recording, summarise(results, config))


def queued(profile: str, results_dir: Path) -> Queue:
    """The regime's genomes at ``profile`` under ``results_dir`` (``REGIME_PROFILES``), in
    the order they are evaluated, each one chunk a part, for the background queue
    (``sgb.grid``); a genome whose training has not landed is labelled so."""
    config = REGIME_PROFILES[check_profile(profile)]
    path = results_file(Path(results_dir) / "rl", "regime_populations_ant", profile)
    genomes = read_results(path)["results"]["genomes"] if path.exists() else {}
    runs = []
    for genome in config.genomes:
        label, steps = genome_label(genome), genome_steps(genome, config)
        parts = genomes.get(label, {}).get("parts", {})
        done = [parts[p] for p in genome.parts if p in parts]
        waits = (
            "" if landed(genome, config, Path(results_dir)) else " (its training has not landed)"
        )
        lock = run_lock(path, label)
        spent_cpu = known_sum([p.get("cpu_time_s") for p in done])
        runs.append(
            QueuedRun(
                label=f"{_genome_name(genome.cell_types, genome.seed, steps)}{waits}",
                checkpoint=lock,
                state=lock.with_suffix(".state.npz"),  # none: its parts are in the file
                chunks=len(genome.parts),
                finished=len(done) == len(genome.parts),
                wall_time_s=sum(p["wall_time_s"] for p in done) if done else None,
                chunks_done=len(done),
                spent_s=sum(p["wall_time_s"] for p in done),
                cpu_time_s=spent_cpu if done else None,
                spent_cpu_s=spent_cpu,
            )
        )
    return Queue(path, tuple(runs))


def _new_record(genome: Genome, j: int, config: PopulationsConfig, env: str) -> dict:
    return {
        "settings": genome.settings,
        "cell_types": genome.cell_types,
        "training_seed": genome.seed,
        "evaluation_seed": config.seed + j,
        "checkpoint": checkpoint_path(genome, config, env),
        "parts": {},
    }


def checkpoint_digest(checkpoint: Path) -> str:
    """The SHA-256 of ``checkpoint``'s parameters, as its sidecar records it (of a kept
    state's bytes): a genome's parts are reused only while the checkpoint they were
    evaluated on is the same."""
    sidecar = checkpoint.with_suffix(".json")
    if sidecar.exists():
        return json.loads(sidecar.read_text())["sha256"]
    return hashlib.sha256(checkpoint.read_bytes()).hexdigest()


def _has(results: dict, genome: Genome, part: str, env: str) -> bool:
    return part in results["genomes"].get(genome_label(genome, env), {}).get("parts", {})


def _write(recording: Recording, results: dict) -> Path:
    parts = [p for g in results["genomes"].values() for p in g["parts"].values()]
    seeds = sorted(g["evaluation_seed"] for g in results["genomes"].values())
    return recording.write(results, seeds, parts=parts)


def _pooled_test(name: str, pooled: "Pooled | PooledR", n: int, transform=None) -> stats.Test:
    """A random-effects pooled estimate (DerSimonian-Laird, normal interval) as a ``Test``;
    ``transform`` maps Fisher's z back to r where the pooling was on z (``PooledR``)."""
    estimate, (low, high) = pooled.random_effects, pooled.random_effects_ci
    se = pooled.random_effects_z_se if isinstance(pooled, PooledR) else pooled.random_effects_se
    z = (math.atanh(estimate) if transform else estimate) / se
    detectable = 2.8 * se if transform is None else transform(2.8 * se)
    p = float(2 * scipy_stats.norm.sf(abs(z)))
    return stats.Test(name, estimate, low, high, math.inf, p, detectable, n)


def _bound(normal: "NormalSplit") -> float:
    """The upper bound on the SD between individuals, % of the return (0 where none)."""
    bound = normal.between_sd_bound_percent
    return 0.0 if bound is None else bound


def populations_rows(results: "PopulationsResults") -> list[Row]:
    """Figures 4E and 5 on several genomes per genome settings (``sgb.experiments.
    populations``), pooled over the genomes by random effects. Figure 4E's r is compared
    with the paper's as this measurement sees it, attenuated by the bodies' mean
    reliabilities."""
    rows = []
    for settings, pooled in results.pooled.items():
        done = [
            g.summary
            for g in results.genomes.values()
            if g.settings == settings and g.summary is not None
        ]
        n_genomes = len(done)
        episodes = len(next(iter(results.genomes.values())).parts.normal.returns[0])
        who = "our" if settings == "ours" else "the authors'"
        budget = f"{n_genomes} genomes x 100 individuals x {episodes} episodes"
        label = f"ant, {who} genome, 64 types, {n_genomes} genomes pooled (random effects)"
        diff = _pooled_test("pooled z", pooled.mean_network_percent.fixed_effect, n_genomes)
        rows.append(
            judge(
                "fig5.population_beats_mean",
                label + ", % of the mean network's return",
                diff,
                budget,
                unit="genomes",
            )
        )
        rels = [
            max(g.normal.variance_split.reliability, 0.0)
            * max(g.long_legs.variance_split.reliability, 0.0)
            for g in done
        ]
        r = _pooled_test("pooled Fisher z", pooled.legs_r.fixed_effect, 100 * n_genomes, math.tanh)
        bound = max(_bound(g.normal) for g in done)
        attenuation = float(np.mean(np.sqrt(rels)))
        rows.append(legs_row(label, r, attenuation, budget, sd_below(bound)))
    groups = {}
    for genome in results.genomes.values():
        if genome.summary is not None:
            who = "our" if genome.settings == "ours" else "the authors'"
            setting = f"ant, {who} genome, 64 types"
            row = variability_row(genome.summary.normal, f"{setting}, seed {genome.training_seed}")
            if row is not None:
                rows.append(row)
                n, episodes = np.shape(genome.parts.normal.returns)
                groups.setdefault((setting, n, episodes, None), []).append(row.test.estimate)
    return rows + pooled_variability_rows("title.variability", groups)


def regime_population_rows(results: "RegimePopulationsResults") -> list[Row]:
    """Figures 4E and 5 and the title's claim on each genome of the authors' training regime
    at the paper's budget (``reproduce regime_populations``), under each protocol it was
    evaluated with: ours (deterministic actions; Figure 5 paired with the mean network on
    the same initial states) and theirs (sampled actions; Figure 5 by their one-sample t
    and by Welch's t), Figure 5 in % of the mean network's return (left out where that
    return is not positive), Figure 4E's r against the paper's as these reliabilities see
    it; then ``pooled_variability_rows``."""
    rows, variability = [], {}
    for genome in results.genomes.values():
        summary = genome.summary
        if summary is None:
            continue
        n, episodes = np.shape(genome.parts.sampled.returns)
        steps = regime_steps(genome.trained_steps)
        label = (
            f"ant, the authors' regime, {steps}, {genome.cell_types} types, "
            f"seed {genome.training_seed}"
        )
        budget = f"1 genome x {n} individuals x {episodes} episodes"
        protocols = []
        if summary.mean_network is not None:
            ours = summary.mean_network
            tests = [("our protocol (paired, same states)", ours.test)]
            protocols.append(
                ("deterministic actions", summary, _percent_of(ours.mean_network_return, tests))
            )
        theirs = summary.authors_protocol
        sampled = (
            f"their protocol ({theirs.individual_episodes} sampled episodes each, "
            f"mean network {theirs.mean_network_episodes})"
        )
        tests = [
            (f"{sampled}, their one-sample t", theirs.one_sample),
            (f"{sampled}, Welch t", theirs.welch),
        ]
        protocols.append(("sampled actions", theirs, _percent_of(theirs.mean_network_mean, tests)))
        for actions, bodies, tests in protocols:
            found = _protocol_rows(label, actions, bodies, tests, budget)
            rows += [replace(r, amount=genome.trained_steps) for r in found]
            if found[-1].key == "title.variability.regime":
                steps = genome.trained_steps
                setting = (
                    f"ant, the authors' regime, {regime_steps(steps)}, "
                    f"{genome.cell_types} types, {actions}"
                )
                group = (setting, n, episodes, steps)
                variability.setdefault(group, []).append(found[-1].test.estimate)
    return rows + pooled_variability_rows("title.variability.regime", variability)


def _percent_of(
    mean_network_return: float, tests: list[tuple[str, StoredTest]]
) -> list[tuple[str, stats.Test]]:
    """Figure 5's ``tests`` in % of the mean network's return; none where that return is
    not positive (a genome that does not yet walk: a % of it says nothing)."""
    if mean_network_return <= 0:
        return []
    return [(name, stored_test(test, 100 / mean_network_return)) for name, test in tests]


def regime_steps(steps: int) -> str:
    """A regime genome's training in a row's setting: ``REGIME_STEPS`` for a finished run,
    else e.g. ``9.83 x 10^6 steps``."""
    finished = regime_runs.RUNS["cpu"].ppo.total_steps
    return REGIME_STEPS if steps == finished else f"{steps / 1e6:.3g} x 10^6 steps"


def _protocol_rows(
    label: str, actions: str, bodies: Record, tests: list[tuple[str, stats.Test]], budget: str
) -> list[Row]:
    """One genome's rows under one protocol: Figure 5 by each of ``tests``, Figure 4E, and
    last the title's claim (left out where the mean return is not positive). ``bodies``:
    the protocol's summary with its ``normal``, ``long_legs`` and ``legs``."""
    rows = [
        judge(
            "fig5.population_beats_mean",
            f"{label}, {protocol}, % of the mean network's return",
            test,
            budget,
        )
        for protocol, test in tests
    ]
    setting = f"{label}, {actions}"
    normal, long_legs = bodies.normal, bodies.long_legs
    reliabilities = [max(b.variance_split.reliability, 0.0) for b in (normal, long_legs)]
    legs = stored_test(bodies.legs.test)
    if normal.mean_return > 0:
        bound = sd_below(_bound(normal))
    else:  # a % of a return that is not positive says nothing: in return units
        split = normal.variance_split
        most = between_sd_at(split.icc_ci[1], split.within_var)
        bound = (
            f"individuals that differ: their SD is at most {most:.2g} (return units; the mean "
            f"return, {normal.mean_return:.0f}, is not positive)"
        )
    rows.append(legs_row(setting, legs, math.sqrt(math.prod(reliabilities)), budget, bound))
    variability = variability_row(normal, setting, "title.variability.regime")
    return rows + ([variability] if variability else [])


def pooled_variability_rows(
    key: str, groups: dict[tuple[str, int, int, int | None], list[float]]
) -> list[Row]:
    """The title's claim (``key``) per setting over its genomes, the genome the unit: the
    mean of their SDs between individuals (% of the return) with its one-sample t
    interval over genomes, against about 1 %. ``groups``: (setting, individuals,
    episodes, steps the genomes trained or ``None``) -> each genome's SD. A group of one
    genome is left out, and so is one whose genomes' SDs are all equal (all 0 where every
    genome's ICC estimate lies below 0): it has no spread over genomes to test, and its
    genomes' own rows stand."""
    rows = []
    for (setting, n, episodes, steps), sds in groups.items():
        if len(sds) < 2 or np.ptp(sds) == 0:
            continue
        pooled = f"{setting}, {len(sds)} genomes pooled (the genome the unit)"
        budget = f"{len(sds)} genomes x {n} individuals x {episodes} episodes"
        row = judge(key, pooled, stats.one_sample(sds, 0.0), budget, unit="genomes")
        rows.append(row if steps is None else replace(row, amount=steps))
    return rows


def populations(payload: "Populations | None") -> dict[str, str]:
    """The populations experiment (``rl/populations_ant_cpu.json``): ``pop_complete``
    (genomes summarised) and, per genome settings, its Figure 5 and 4E rows
    (``pop_fig5_{ours,authors}_*``, ``pop_fig4e_*``); without the file, "none of the
    genomes" and ``NOT_RUN``."""
    if payload is None:
        return {"pop_complete": "none of the genomes"} | populations_rows_texts([])
    genomes = payload.results.genomes
    done = sum(g.summary is not None for g in genomes.values())
    rows = populations_rows(payload.results)
    return {"pop_complete": f"{done} of {len(genomes)} genomes"} | populations_rows_texts(rows)


def _listed(rows: list[Row], key: str) -> str:
    """Each row of claim ``key``: its setting (``regime_setting``), estimate with interval
    and verdict; ``NOT_RUN`` without one."""
    found = [r for r in rows if r.key == key]
    return "; ".join(f"{regime_setting(r)}: {r.ours}, **{r.verdict}**" for r in found) or NOT_RUN


def _genome_name(cell_types: int, seed: int, steps: int) -> str:
    """A regime genome in the chapter and the queue: e.g. ``128 types seed 0``, ``64 types
    seed 0 after 9.83 x 10^6 steps``."""
    name, trained = f"{cell_types} types seed {seed}", regime_steps(steps)
    return name if trained == REGIME_STEPS else f"{name} after {trained}"


def over_training(genomes: list["RegimePopulationGenome"]) -> str:
    """Whether variability falls as a genome trains: for each genome measured at more than
    one point of its run, the normal body under sampled actions at each point (fewest steps
    first): mean return, ICC with its interval, and the SD between individuals at the
    interval's upper end in % of the SD within one; then at which points individuals can
    be told apart (the ICC's interval above 0). ``NOT_RUN`` without such a genome."""
    runs = {}
    for g in genomes:
        runs.setdefault((g.cell_types, g.training_seed), []).append(g)
    parts = []
    for (cell_types, seed), points in runs.items():
        if len(points) < 2:
            continue
        said, apart = [], []
        for g in sorted(points, key=lambda g: g.trained_steps):
            normal = g.summary.authors_protocol.normal
            split = normal.variance_split
            low, high = split.icc_ci
            most = 100 * between_sd_at(high, split.within_var) / math.sqrt(split.within_var)
            steps = regime_steps(g.trained_steps)
            said.append(
                f"after {steps}, mean return {normal.mean_return:,.0f}: ICC {split.icc:.4f} "
                f"[{low:.4f}, {high:.4f}], the SD between individuals at most {most:.1f} % "
                "of the SD within one"
            )
            if low > 0:
                apart.append(steps)
        told = (
            f"only after {' and '.join(apart)}" if apart else f"at none of its {len(said)} points"
        )
        parts.append(
            f"{cell_types} types seed {seed}: {'; '.join(said)} (individuals told apart {told})"
        )
    return "; ".join(parts) if parts else NOT_RUN


def told_apart(rows: list[Row]) -> str:
    """Whether individuals of one genome differ at the paper's budget, counted from
    ``regime_population_rows`` over the genomes that trained the whole run (pooled rows and
    Figure 5's one-sample t, which takes the mean network's mean as exact, left out): per
    protocol, the genomes whose SD between individuals has an interval above 0 (named, with
    that SD in % of the return); Figure 4E's rows whose r lies above, or below, 0; Figure
    5's rows whose individuals lie above, or below, their mean network. ``NOT_RUN`` without rows."""
    finished = regime_runs.RUNS["cpu"].ppo.total_steps
    mine = [r for r in rows if r.amount == finished and "genomes pooled" not in r.setting]
    said = []
    for actions, protocol in (("sampled", "the authors' protocol"), ("deterministic", "ours")):
        each = [
            r
            for r in mine
            if r.key == "title.variability.regime" and r.setting.endswith(f"{actions} actions")
        ]
        apart = [
            f"{regime_setting(r).removesuffix(f', {actions} actions')}: {r.ours} % of the return"
            for r in each
            if r.test.low > 0
        ]
        if each:
            said.append(
                f"under {actions} actions ({protocol}) in {len(apart)} of {len(each)} genomes"
                + (f" ({'; '.join(apart)})" if apart else "")
            )
    if not said:
        return NOT_RUN
    legs = [r for r in mine if r.key == "fig4e.r_legs"]
    fig5 = [
        r for r in mine if r.key == "fig5.population_beats_mean" and "one-sample" not in r.setting
    ]
    above = sum(r.test.low > 0 for r in fig5)
    below = sum(r.test.high < 0 for r in fig5)
    return (
        f"individuals of one genome can be told apart {' and '.join(said)}. Figure 4E's r "
        f"between the bodies lies above 0 in {sum(r.test.low > 0 for r in legs)} of "
        f"{len(legs)} measurements (genome and protocol) and below 0 in "
        f"{sum(r.test.high < 0 for r in legs)}; Figure 5's individuals lie above their mean "
        f"network in {above} of {len(fig5)} and below it in {below}"
    )


def regime_populations(payload: "RegimePopulations | None") -> dict[str, str]:
    """Figures 4E and 5 on the genomes of the authors' regime
    (``rl/regime_populations_ant_cpu.json``): the design (``regime_pop_design``: the
    genomes measured of those the grid trains), the normal body's test-retest reliability
    under sampled actions (``regime_pop_retest``: the split-half r of each genome), the
    variability of a genome measured part-way and at the end (``regime_pop_training``), the
    answer counted over the genomes (``regime_pop_answer``, ``told_apart``), and each row of
    ``regime_population_rows``: Figure 4E (``regime_pop_legs``), Figure 5 by
    Welch's t (``regime_pop_welch``) and paired under our protocol (``regime_pop_ours``);
    ``NOT_RUN`` for all without the file or a summary."""
    rows = [] if payload is None else regime_population_rows(payload.results)
    texts = dict.fromkeys(
        ("regime_pop_design", "regime_pop_retest", "regime_pop_training"), NOT_RUN
    )
    if rows:
        genomes = payload.results.genomes
        done = {k: g for k, g in genomes.items() if g.summary is not None}
        names = ", ".join(
            _genome_name(g.cell_types, g.training_seed, g.trained_steps) for g in done.values()
        )
        budget = next(r.budget for r in rows if r.budget.startswith("1 genome"))
        texts["regime_pop_design"] = (
            f"{len(done)} of the {len(REGIME_PROFILES['cpu'].genomes)} genomes ({names}), "
            f"each {budget.removeprefix('1 genome x ')}"
        )
        texts["regime_pop_retest"] = "; ".join(
            f"{_genome_name(g.cell_types, g.training_seed, g.trained_steps)}: "
            f"r = {split.r:.2f} [{split.r_ci[0]:.2f}, {split.r_ci[1]:.2f}]"
            for g in done.values()
            for split in [g.summary.authors_protocol.normal.split_half]
        )
        texts["regime_pop_training"] = over_training(list(done.values()))
    welch = [r for r in rows if "Welch" in r.setting]
    paired = [r for r in rows if "our protocol" in r.setting]
    return texts | {
        "regime_pop_answer": told_apart(rows),
        "regime_pop_legs": _listed(rows, "fig4e.r_legs"),
        "regime_pop_welch": _listed(welch, "fig5.population_beats_mean"),
        "regime_pop_ours": _listed(paired, "fig5.population_beats_mean"),
    }


def populations_rows_texts(rows: list[Row]) -> dict[str, str]:
    """``row_texts`` of the populations experiment's Figure 5 and 4E rows per settings."""
    card = claims.by_key(rows)
    texts = {}
    for who, settings in GENOMES:
        for figure, key in (("fig5", "fig5.population_beats_mean"), ("fig4e", "fig4e.r_legs")):
            texts |= row_texts(f"pop_{figure}_{settings}", row_of(card, key, who))
    return texts


def evidence(records: Records) -> list[Row]:
    """The populations of Figure 3's genomes, pooled (``populations_rows``), their budget
    the steps those genomes trained."""
    payload = records.get("populations")
    if payload is None:
        return []
    steps = trained_steps(records.get("fig3", "ant"))
    return genomes_at(populations_rows(payload.results), steps)


def regime_evidence(records: Records) -> list[Row]:
    """The populations of the regime's genomes (``regime_population_rows``), each row's
    budget the steps its genome trained."""
    payload = records.get("regime_populations")
    return [] if payload is None else regime_population_rows(payload.results)


def texts(records: Records, card: Card) -> dict[str, str]:
    """What chapter 5 glues of both populations."""
    return regime_populations(records.get("regime_populations")) | populations(
        records.get("populations")
    )


class VarianceSplit(Record):
    """The one-way split of a body's returns (individuals x episodes)."""

    n_individuals: Count
    episodes: Count
    within_var: NonNegative
    reliability: Reliability
    icc: Reliability
    icc_ci: List[Reliability]
    p: Probability


class Split(Record):
    variance_split: VarianceSplit


class NormalSplit(Split):
    between_sd_bound_percent: NonNegative = None


class PopulationNormal(NormalSplit):
    mean_return: Return
    between_sd: NonNegative


class MeanNetworkPercent(Record):
    percent: Finite
    percent_ci: List[Finite]


class PopulationSummary(Record):
    normal: PopulationNormal
    long_legs: Split
    mean_network: MeanNetworkPercent


class ReturnsPart(Record):
    returns: Returns


class NormalPart(Record):
    normal: ReturnsPart


class PopulationGenome(Record):
    settings: str
    training_seed: Seed
    parts: NormalPart
    summary: PopulationSummary = None


class Pooled(Record):
    estimate: Finite
    ci: List[Finite]
    random_effects: Finite
    random_effects_ci: List[Finite]
    random_effects_se: Positive


class PooledR(Record):
    """Pooled on Fisher's z."""

    random_effects: Correlation
    random_effects_ci: List[Correlation]
    random_effects_z_se: Positive


class BetweenGenomes(Record):
    """The genomes' estimates: their mean and Student-t interval (null with one genome)."""

    mean: Finite
    ci: List[Finite | None]


class FixedEffect(Record):
    fixed_effect: Pooled
    between_genomes: BetweenGenomes


class FixedEffectR(Record):
    fixed_effect: PooledR


class PooledSetting(Record):
    n_genomes: Count
    mean_network_percent: FixedEffect
    legs_r: FixedEffectR


class PopulationsResults(Record):
    genomes: Each(PopulationGenome)
    pooled: Each(PooledSetting)


class Populations(ResultsFile):
    results: PopulationsResults


class OurProtocol(Record):
    mean_network_return: Return
    test: StoredTest


class SplitHalf(Record):
    episodes: Count
    r: Correlation
    r_ci: List[Correlation]


class RegimeNormal(PopulationNormal):
    split_half: SplitHalf


class LegsTest(Record):
    test: StoredTest


class TheirProtocol(Record):
    """The authors' protocol on one genome: their Figure 5 comparison and the sampled
    bodies' variance splits and r."""

    individual_episodes: Count
    mean_network_episodes: Count
    mean_network_mean: Return
    one_sample: StoredTest
    welch: StoredTest
    normal: RegimeNormal
    long_legs: Split
    legs: LegsTest


class RegimePopulationSummary(Record):
    authors_protocol: TheirProtocol
    mean_network: OurProtocol = None  # our protocol, where the genome was evaluated under it
    normal: RegimeNormal = None
    long_legs: Split = None
    legs: LegsTest = None


class SampledPart(Record):
    # a 64-type genome plays our protocol's parts first: None until its sampled part is in
    sampled: ReturnsPart = None


class RegimePopulationGenome(Record):
    cell_types: Count
    training_seed: Seed
    trained_steps: Count
    parts: SampledPart
    summary: RegimePopulationSummary = None


class RegimePopulationsResults(Record):
    genomes: Each(RegimePopulationGenome)


class RegimePopulations(ResultsFile):
    results: RegimePopulationsResults
