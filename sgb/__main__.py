"""Command line: ``python -m sgb reproduce EXPERIMENT --profile smoke|cpu|paper [options]``."""

import argparse
import sys
from pathlib import Path

from sgb.experiments import EXPERIMENTS, PROFILE_NAMES, get_experiment


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m sgb")
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
        path = get_experiment(args.experiment).run(args.profile, args.out_dir, **options)
    except ValueError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
