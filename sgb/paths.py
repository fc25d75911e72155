"""Where the committed results (JSON files and checkpoints) are read from."""

from pathlib import Path

PACKAGE = Path(__file__).resolve().parent


def committed_results() -> Path:
    """The committed ``results/`` directory.

    An installed wheel carries it as package data (``sgb/results``); a checkout of the
    repository has it next to the package.
    """
    for candidate in (PACKAGE / "results", PACKAGE.parent / "results"):
        if candidate.is_dir():
            return candidate
    raise FileNotFoundError(f"no committed results next to the sgb package at {PACKAGE}")
