"""Figures 4 and 5: the individuals of one trained genome (a checkpoint of Figure 3).

- ``fig4``: sample N individuals from a trained SGB and evaluate each for several
  episodes on the Ant with normal and long legs (4E) and on two physical niches (4F);
  Pearson r between conditions.
- ``fig5``: the same individuals against the mean network on the normal Ant, on the same
  initial states; paired t-test.
"""

from dataclasses import replace
from pathlib import Path

from sgb.profiles import PROFILE_NAMES
from sgb.recording import start
from sgb.rl.protocols import (
    PopulationConfig,
    authors_protocol,
    compare,
    individuals_vs_mean,
    load_agent,
    population_config,
    population_on,
)
from sgb.rl.runs import checkpoint_root


def evaluate_conditions(config: PopulationConfig, results_dir: Path) -> dict:
    """Returns (N, episodes) of the individuals on every condition, and of the mean network
    (on the same initial states) on ``mean_network_conditions``."""
    return population_on(*load_agent(Path(results_dir) / config.checkpoint), config)


def fig4_config(profile: str) -> PopulationConfig:
    """Figure 4: the individuals on every condition; no mean network."""
    return replace(population_config(profile), mean_network_conditions=())


def fig5_config(profile: str) -> PopulationConfig:
    """Figure 5: the individuals and the mean network on the normal Ant."""
    return replace(population_config(profile), conditions=("normal",))


FIG4_PROFILES = {p: fig4_config(p) for p in PROFILE_NAMES}
FIG5_PROFILES = {p: fig5_config(p) for p in PROFILE_NAMES}


def _run_population(profile: str, out_dir: Path, env: str, figure: str) -> Path:
    if env != "ant":
        raise ValueError(
            f"env must be 'ant' for {figure} (the variants are Ant bodies), got {env!r}"
        )
    profiles = FIG4_PROFILES if figure == "fig4" else FIG5_PROFILES
    recording = start(profiles, profile, Path(out_dir) / "rl", f"{figure}_{env}")
    config = recording.config
    agent = load_agent(checkpoint_root(out_dir, config.checkpoint) / config.checkpoint)
    returns = population_on(*agent, config)
    results = {"returns": returns}
    if figure == "fig4":
        results["legs"] = compare(returns, "normal", "long_legs")
        results["niches"] = compare(returns, "slippery", "low_gravity")
    else:
        results["mean_network"] = individuals_vs_mean(returns)
        results["authors_protocol"] = authors_protocol(*agent, config)
    return recording.write(results, [config.seed])


def run_fig4(profile: str, out_dir: Path, env: str = "ant") -> Path:
    """Figure 4E/F: individuals on normal vs long legs and on two niches."""
    return _run_population(profile, out_dir, env, "fig4")


def run_fig5(profile: str, out_dir: Path, env: str = "ant") -> Path:
    """Figure 5: individuals against the mean network."""
    return _run_population(profile, out_dir, env, "fig5")
