"""Experiments behind the book's figures, run by ``python -m sgb reproduce``.

Each experiment is registered once, in ``EXPERIMENTS``, by the module that holds
it, its run function ``run(profile: str, out_dir: Path, **options) -> Path`` (which
writes a results file with provenance and returns its path) and its profiles
(a dict profile name -> the config that ``run`` uses at that profile).
"""

import importlib
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

PROFILE_NAMES = ("smoke", "cpu", "paper")


@dataclass(frozen=True)
class Experiment:
    """Where an experiment lives: a module under sgb.experiments and two of its names."""

    module: str
    run_name: str = "run"
    profiles_name: str = "PROFILES"

    def _module(self):
        return importlib.import_module(f"sgb.experiments.{self.module}")

    @property
    def run(self) -> Callable[..., Path]:
        """``run(profile, out_dir, **options) -> Path`` of the results file."""
        return getattr(self._module(), self.run_name)

    @property
    def profiles(self) -> dict[str, Any]:
        """Profile name -> the config ``run`` uses at that profile."""
        return getattr(self._module(), self.profiles_name)


EXPERIMENTS: dict[str, Experiment] = {
    "bbb": Experiment("bayes_by_backprop"),
    "theory": Experiment("theory"),
    "fig2": Experiment("fig2"),
    "dgb_budget": Experiment("dgb_budget"),
    "fig3": Experiment("rl", "run_fig3", "FIG3_PROFILES"),
    "fig4": Experiment("rl", "run_fig4", "FIG4_PROFILES"),
    "fig5": Experiment("rl", "run_fig5", "FIG5_PROFILES"),
    "spread": Experiment("rl_spread"),
}


def get_experiment(name: str) -> Experiment:
    """The registered experiment ``name``."""
    if name not in EXPERIMENTS:
        raise ValueError(f"unknown experiment {name!r}; available: {sorted(EXPERIMENTS)}")
    return EXPERIMENTS[name]


def check_profile(profile: str) -> str:
    """Validate a profile name."""
    if profile not in PROFILE_NAMES:
        raise ValueError(f"unknown profile {profile!r}; choose one of {PROFILE_NAMES}")
    return profile


def profile_from_env() -> str:
    """The profile named by the environment variable ``SGB_PROFILE`` (default "smoke")."""
    return check_profile(os.environ.get("SGB_PROFILE", "smoke"))
