"""The authors' genome settings and training regime, as their public code has them, and
their Figure 3 scale.

Read from ``self-supervisor/genomic_bottleneck_v2`` at commit 7effad6: the PPO settings
from ``RL/configs/ant.yaml`` and ``RL/configs/halfcheetah.yaml``; the regime
(``sgb.rl.trainer``: a new draw of the actor at every environment step, shared by every
environment, and a fresh draw in the loss; resets on the spot; their evaluation) from
``RL/training_torch.py`` and ``RL/models.py``; the Bayesian biases from
``RL/custom_layers.py`` (``BayesianLinear``, ``bias_sampler``). Their ``batch_size`` x
``num_minibatches`` sequences per iteration are ``unrolls_per_iteration`` unrolls of
every environment here. The genome (every layer typed, rho -7, ...) is a separate choice,
``with_settings(..., "authors")``, as is the regime: the book trains either genome under
either.
"""

from dataclasses import replace

from sgb import validation
from sgb.rl.ppo import PPOConfig

SETTINGS = ("ours", "authors")
# the typing ablation of chapter 5: each settings with the other's input typing
ABLATIONS = ("ours_typed_inputs", "authors_untyped_inputs")
_ENVS = 2048
_MINIBATCHES = 32
# per environment: (batch_size, num_update_epochs, unroll_length, entropy_cost,
# complexity_cost, reward_scaling, discounting, eval_frequency) of their yaml files
_YAML = {
    "ant": (1024, 4, 5, 1e-2, 0.0, 0.1, 0.97, 10),
    "halfcheetah": (512, 8, 20, 1e-3, 1e-4, 1.0, 0.95, 20),
}
# Figure 3's y-axis in their code (``proportion_of_max_score``): (R - min) / (SOTA - min)
FIG3_SCALE = {"ant": (-724.0, 8706.0), "halfcheetah": (-724.0, 4838.0)}


def with_settings(ppo: PPOConfig, settings: str) -> PPOConfig:
    """``ppo`` under our genome settings (unchanged) or the authors' (their public code,
    ``RL/custom_layers.py``, ``RL/models.py``, ``RL/configs/*.yaml``): every layer an SGB
    layer, the observation entries and outputs typed too; type means drawn from N(0, 0.1);
    rho_init -7 (sigma about 0.0009); prior N(0, 0.1^2); KL weight 0 on the Ant, 1e-4 on
    the HalfCheetah. Every type pair has its own Gaussian, as the paper describes. The
    training regime is a separate choice (``authors_regime``).

    The ablations swap one difference: ``"ours_typed_inputs"`` is ours with the
    observation entries typed, ``"authors_untyped_inputs"`` the authors' with one type
    per observation entry.
    """
    validation.choice("settings", settings, SETTINGS + ABLATIONS)
    if settings == "ours" or not ppo.network.sgb:
        return ppo
    if settings == "ours_typed_inputs":
        return replace(ppo, network=replace(ppo.network, typed_inputs=True))
    network = replace(
        ppo.network,
        typed_inputs=settings == "authors",
        sgb_output=True,
        mean_init=0.1,
        rho_init=-7.0,
        prior="gaussian",
    )
    return replace(ppo, network=network, kl_coef=0.0 if ppo.env.name == "ant" else 1e-4)


def authors_regime(ppo: PPOConfig) -> PPOConfig:
    """``ppo`` trained as the authors train: their regime, their PPO settings for its
    environment (learning rate 3e-4, clip 0.3, 2048 environments, 32 minibatches, 5 x 10^7
    steps, and the rest of their yaml), an SGB network's biases drawn too, and where their
    ``RL/models.py`` and ``RL/training_torch.py`` depart from ours, theirs:

    - observations scaled by their normaliser (``sgb.rl.normalizer``, ``"authors"``);
    - the entropy's draw passing no gradient (``entropy_draw="detached"``);
    - deterministic layers started as torch's ``nn.Linear`` (``dense_init="torch"``), and
      an SGB layer's every rho drawn from N(rho_init, 0.1^2) (``RL/custom_layers.py``),
      not set to rho_init;
    - evaluated at step 0 and after each of their ``eval_frequency`` chunks
      (``num_evals``), on as many environments as train (their ``eval_unroll`` on the
      training ``env``).

    Its network's shape and genome settings and its episode length are kept."""
    validation.instance("ppo", ppo, PPOConfig)
    validation.choice("env", ppo.env.name, tuple(_YAML))
    batch, epochs, unroll, entropy, kl, scaling, discount, evals = _YAML[ppo.env.name]
    network = replace(ppo.network, normalizer="authors", dense_init="torch", rho_init_std=0.1)
    if network.sgb:
        network = replace(network, bayesian_biases=True)
    return replace(
        ppo,
        network=network,
        regime="authors",
        total_steps=50_000_000,
        num_envs=_ENVS,
        unroll_length=unroll,
        unrolls_per_iteration=batch * _MINIBATCHES // _ENVS,
        num_minibatches=_MINIBATCHES,
        num_epochs=epochs,
        learning_rate=3e-4,
        clip=0.3,
        value_coef=0.5,
        entropy_coef=entropy,
        kl_coef=kl,
        discount=discount,
        gae_lambda=0.95,
        reward_scaling=scaling,
        num_evals=evals,
        eval_individuals=_ENVS,
        eval_at_start=True,
        entropy_draw="detached",
    )


def authors_scale(env: str, value: float) -> float:
    """A return on the authors' Figure 3 scale, (R + 724) / (SOTA + 724) with their
    hard-coded SOTA (8706 on the Ant, 4838 on the HalfCheetah)."""
    low, high = FIG3_SCALE[validation.choice("env", env, tuple(FIG3_SCALE))]
    return (value - low) / (high - low)


def arm_order(cell_types: int | None, genome: str = "authors") -> tuple[bool, int, bool]:
    """Where a regime arm stands in every list and figure of it: vanilla (``cell_types``
    ``None``) first, then more cell types first, the authors' genome before its ablation
    (``genome``, e.g. their aliased pairs)."""
    return cell_types is not None, -(cell_types or 0), genome != "authors"


def by_arm(runs: list) -> dict[tuple[int | None, str], list]:
    """Regime runs by arm, (cell types or ``None`` for vanilla, genome), in ``arm_order``;
    each arm's runs by seed. A run without a ``genome`` is the authors'."""
    arms: dict[tuple[int | None, str], list] = {}
    for run in sorted(runs, key=lambda r: r.seed):
        arms.setdefault((run.cell_types, getattr(run, "genome", "authors")), []).append(run)
    return dict(sorted(arms.items(), key=lambda item: arm_order(*item[0])))


def arm_name(cell_types: int | None, genome: str = "authors") -> str:
    """A regime arm in the book's words: ``vanilla PPO``, ``128 types``, ``16 types,
    pairs aliased``."""
    if cell_types is None:
        return "vanilla PPO"
    return f"{cell_types} types" + ("" if genome == "authors" else ", pairs aliased")
