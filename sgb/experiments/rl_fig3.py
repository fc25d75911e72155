"""Figure 3 (registered as ``fig3``): see ``sgb.experiments.rl``."""

from pathlib import Path

from sgb.experiments import rl

PROFILES = {p: rl.sweep_config("ant", p) for p in ("smoke", "cpu", "paper")}


def run(profile: str, out_dir: Path, env: str = "ant") -> Path:
    """Run Figure 3's experiment at ``profile``; returns the results file."""
    return rl.run_fig3(profile, out_dir, env=env)
