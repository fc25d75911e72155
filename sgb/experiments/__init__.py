"""Experiments behind the book's figures, one module each, run by ``python -m sgb reproduce``.

Each module defines ``PROFILES`` (a dict profile name -> config) and
``run(profile: str, out_dir: Path, **options) -> Path`` that writes a results
file with provenance and returns its path.
"""

import importlib
import os
from types import ModuleType

PROFILE_NAMES = ("smoke", "cpu", "paper")

# experiment name -> module under sgb.experiments
EXPERIMENTS: dict[str, str] = {
    "bbb": "bayes_by_backprop",
    "theory": "theory",
    "fig2": "fig2",
    "fig3": "rl_fig3",
    "fig4": "rl_fig4",
    "fig5": "rl_fig5",
    "spread": "rl_spread",
}


def get_experiment(name: str) -> ModuleType:
    """The module of experiment ``name``."""
    if name not in EXPERIMENTS:
        raise ValueError(f"unknown experiment {name!r}; available: {sorted(EXPERIMENTS)}")
    return importlib.import_module(f"sgb.experiments.{EXPERIMENTS[name]}")


def check_profile(profile: str) -> str:
    """Validate a profile name."""
    if profile not in PROFILE_NAMES:
        raise ValueError(f"unknown profile {profile!r}; choose one of {PROFILE_NAMES}")
    return profile


def profile_from_env() -> str:
    """The profile named by the environment variable ``SGB_PROFILE`` (default "smoke")."""
    return check_profile(os.environ.get("SGB_PROFILE", "smoke"))
