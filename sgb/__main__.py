"""Command line: ``python -m sgb reproduce EXPERIMENT --profile smoke|cpu|paper [options]``."""

import argparse
import inspect
import sys
from collections.abc import Callable
from pathlib import Path

from sgb.divergence import TrainingDiverged
from sgb.experiments import EXPERIMENTS, PROFILE_NAMES, get_experiment


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m sgb",
        epilog="fig2 takes --dataset (digits, mnist1d offline; mnist, cifar10 downloaded); "
        "fig3 takes --env (ant, halfcheetah); fig4, fig5 and spread take --env ant.",
    )
    commands = parser.add_subparsers(dest="command", required=True)
    reproduce = commands.add_parser("reproduce", help="run an experiment and write its results")
    reproduce.add_argument("experiment", choices=sorted(EXPERIMENTS))
    reproduce.add_argument("--profile", choices=PROFILE_NAMES, default="smoke")
    reproduce.add_argument("--out-dir", type=Path, default=Path("results"))
    reproduce.add_argument("--dataset", help="dataset, for experiments that take one")
    reproduce.add_argument("--env", help="environment, for experiments that take one")
    args = parser.parse_args(argv)
    options = {k: v for k, v in (("dataset", args.dataset), ("env", args.env)) if v is not None}
    try:
        run = get_experiment(args.experiment).run
        _check_options(args.experiment, run, options)
        path = run(args.profile, args.out_dir, **options)
    except (ValueError, TypeError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    except (OSError, TrainingDiverged) as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    print(f"wrote {path}")
    return 0


def _check_options(experiment: str, run: Callable[..., Path], options: dict[str, str]) -> None:
    """Reject --dataset/--env for an experiment whose ``run`` does not take them."""
    parameters = inspect.signature(run).parameters
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters.values()):
        return
    unknown = sorted(set(options) - set(parameters))
    if unknown:
        flags = ", ".join(f"--{name}" for name in unknown)
        raise ValueError(f"{experiment} does not take {flags}")


if __name__ == "__main__":
    sys.exit(main())
