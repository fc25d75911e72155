"""The profiles every experiment runs at (smoke, cpu, paper), and the one check of a
profile's name."""

import os

PROFILE_NAMES = ("smoke", "cpu", "paper")
DEFAULT_PROFILE = "smoke"


def check_profile(profile: str) -> str:
    """Validate a profile name."""
    if profile not in PROFILE_NAMES:
        raise ValueError(f"unknown profile {profile!r}; choose one of {PROFILE_NAMES}")
    return profile


def profile_from_env() -> str:
    """The profile named by the environment variable ``SGB_PROFILE`` (default smoke)."""
    return check_profile(os.environ.get("SGB_PROFILE", DEFAULT_PROFILE))
