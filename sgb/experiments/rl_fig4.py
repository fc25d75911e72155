"""Figure 4 (registered as ``fig4``): see ``sgb.experiments.rl``."""

from pathlib import Path

from sgb.experiments import rl

PROFILES = {p: rl.population_config(p) for p in ("smoke", "cpu", "paper")}


def run(profile: str, out_dir: Path, env: str = "ant") -> Path:
    """Run Figure 4's experiment at ``profile``; returns the results file."""
    return rl.run_fig4(profile, out_dir, env=env)
