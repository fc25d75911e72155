"""Command line: ``python -m sgb reproduce EXPERIMENT --profile smoke|cpu|paper [options]``,
and ``python -m sgb grid ...``, the background queue of long runs (``sgb.grid``).

The arguments are checked before anything runs; the paper profile is refused where JAX
finds no GPU on this machine (without ``--ray``: a cluster's machines run it), unless
``--force-cpu``.

Results go to ``--out-dir``, else ``$SGB_RESULTS``, else ``./sgb-results``. The committed
results (``sgb.paths.committed_results()``) are written only with
``--maintainer-write-committed``; an ``--out-dir`` inside them is refused without it.
A sweep that shares its runs out may run as several workers on Ray (``sgb.cluster``):
``--workers N`` on a local cluster, ``--ray ADDRESS`` on an existing one; its runs take
one XLA thread however many workers share them, so their numbers do not depend on it.
"""

import argparse
import functools
import inspect
import os
import subprocess
import sys
import textwrap
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from sgb import cluster, validation
from sgb.divergence import TrainingDiverged
from sgb.experiments import CHAPTERS, EXPERIMENTS, get_experiment
from sgb.manifest import MAINTAINER_FLAG
from sgb.paths import committed_results
from sgb.profiles import DEFAULT_PROFILE, PROFILE_NAMES
from sgb.recording import pick

RESULTS_ENV = "SGB_RESULTS"
DEFAULT_OUT_DIR = Path("sgb-results")
_WIDTH = 88


def default_out_dir() -> Path:
    """Where results go without ``--out-dir``: ``$SGB_RESULTS``, else ``./sgb-results``."""
    return Path(os.environ.get(RESULTS_ENV) or DEFAULT_OUT_DIR)


def _committed() -> Path | None:
    try:
        return committed_results().resolve()
    except FileNotFoundError:
        return None


def resolve_out_dir(out_dir: Path | None, maintainer: bool) -> Path:
    """The directory a run writes to; a ValueError for the committed results (or a directory
    inside them) unless ``maintainer``, which writes there and nowhere else, and for a
    directory that a file stands in the place of (it, or one above it)."""
    committed = _committed()
    if maintainer:
        if committed is None:
            raise ValueError(f"{MAINTAINER_FLAG}: no committed results next to the sgb package")
        if out_dir is not None and out_dir.resolve() != committed:
            raise ValueError(
                f"{MAINTAINER_FLAG} writes into the committed results, {committed}; "
                f"it takes no other --out-dir (got {out_dir})"
            )
        return committed
    out_dir = default_out_dir() if out_dir is None else out_dir
    target = out_dir.resolve()
    if committed is not None and (target == committed or committed in target.parents):
        raise ValueError(
            f"{out_dir} is {'' if target == committed else 'inside '}the committed results "
            f"({committed}), which reproduce writes only with {MAINTAINER_FLAG} "
            f"(for maintainers refreshing them). Leave out --out-dir to write to "
            f"${RESULTS_ENV} or ./{DEFAULT_OUT_DIR}, or name another directory."
        )
    blocker = next(p for p in (out_dir, *out_dir.parents) if p.exists())
    if not blocker.is_dir():
        raise ValueError(
            f"cannot write results under {out_dir}: {blocker} is a file, not a directory"
        )
    return out_dir


def _block(label: str, text: str, indent: int, hanging: int = 2) -> list[str]:
    return textwrap.wrap(
        f"{label}{text}",
        _WIDTH,
        initial_indent=" " * indent,
        subsequent_indent=" " * (indent + hanging),
    )


def experiments_help() -> str:
    """What ``reproduce --help`` says of every experiment, by chapter of the book, and of
    where results go."""
    lines = _block(
        "",
        "experiments by chapter of the book, with the cost of each profile "
        f"({DEFAULT_PROFILE}, the default, is what the tests run):",
        0,
    )
    for chapter in sorted({experiment.chapter for experiment in EXPERIMENTS.values()}):
        lines.append(f"chapter {chapter}, {CHAPTERS[chapter]}:")
        for name, experiment in EXPERIMENTS.items():
            if experiment.chapter == chapter:
                lines += _block(f"{name}: ", experiment.figure, 2, 4)
                lines += _block("inputs: ", experiment.inputs, 6)
                for profile in PROFILE_NAMES:
                    lines += _block(f"{profile}: ", experiment.costs.get(profile, "not stated"), 6)
    lines.append("")
    lines.append("where results go:")
    lines += _block(
        "",
        f"--out-dir, else ${RESULTS_ENV}, else ./{DEFAULT_OUT_DIR} (a file named after the "
        "experiment, its dataset or environment and the profile; the RL experiments write "
        "under rl/, their checkpoints under rl/checkpoints/). A rerun into the same "
        "directory continues what an earlier run of the same config left there: finished "
        "runs and cells are reused, a killed run resumes, and a results file whose results "
        "come out the same is kept as it was, with its provenance. The committed results "
        f"of the book are written only with {MAINTAINER_FLAG}.",
        2,
    )
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    """The parser of ``python -m sgb``."""
    parser = argparse.ArgumentParser(
        prog="python -m sgb",
        epilog="python -m sgb reproduce --help describes every experiment.",
    )
    commands = parser.add_subparsers(dest="command", required=True)
    reproduce = commands.add_parser(
        "reproduce",
        help="run an experiment and write its results",
        description="Run one experiment of the book at a profile and write its results "
        "file, with provenance.",
        epilog=experiments_help(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    commands.add_parser(
        "manifest",
        help="enter results files written elsewhere into results/MANIFEST.json, once checked "
        "(python -m sgb manifest --help)",
        add_help=False,
    )
    commands.add_parser(
        "grid",
        help="the background queue of long runs: start, status, land, stop "
        "(python -m sgb grid --help)",
        add_help=False,
    )
    reproduce.add_argument("experiment", choices=list(EXPERIMENTS))
    reproduce.add_argument(
        "--profile",
        choices=PROFILE_NAMES,
        default=DEFAULT_PROFILE,
        help=f"the budget to run at (default: {DEFAULT_PROFILE}, what the tests run); cpu "
        "made the book's committed results; paper is the paper's, meant for a GPU",
    )
    reproduce.add_argument(
        "--force-cpu",
        action="store_true",
        help="run the paper profile even where JAX finds no GPU",
    )
    reproduce.add_argument(
        "--out-dir",
        type=Path,
        default=None,
        help=f"where results go (default: ${RESULTS_ENV}, else ./{DEFAULT_OUT_DIR}); "
        f"never the committed results without {MAINTAINER_FLAG}",
    )
    reproduce.add_argument(
        MAINTAINER_FLAG,
        action="store_true",
        help="write into the book's committed results/ (maintainers refreshing them)",
    )
    reproduce.add_argument("--dataset", help="dataset, for experiments that take one")
    reproduce.add_argument("--env", help="environment, for experiments that take one")
    reproduce.add_argument(
        "--workers",
        type=int,
        default=None,
        help="workers sharing the runs of a sweep that shares them "
        f"({', '.join(n for n, e in EXPERIMENTS.items() if e.shares_runs)}) on Ray "
        "(default: one per core on a local cluster where Ray is installed, at the "
        "cpu and paper profiles; else 1, in this process)",
    )
    reproduce.add_argument(
        "--ray",
        metavar="ADDRESS",
        default=None,
        help="run the workers on the Ray cluster at ADDRESS ('auto': this machine's)",
    )
    return parser


def worker_count(experiment: str, profile: str, workers: int | None, address: str | None) -> int:
    """How many workers share ``experiment``'s runs: ``workers`` if given; else one per
    core where Ray is installed and the experiment shares its runs at ``cpu`` or
    ``paper`` (or on a cluster, ``address``), else 1."""
    shares = get_experiment(experiment).shares_runs
    if workers is not None:
        if workers > 1 and not shares:
            raise ValueError(f"{experiment} does not share its runs out; run it with --workers 1")
        return validation.integer("workers", workers)
    if address is not None and not shares:
        raise ValueError(f"{experiment} does not share its runs out; run it without --ray")
    if shares and cluster.available() and (profile != "smoke" or address is not None):
        return cluster.local_workers()
    return 1


def _files(directory: Path) -> dict[Path, tuple[int, int]]:
    """Every file under ``directory`` with its modification time and size."""
    if not directory.is_dir():
        return {}
    return {
        p.resolve(): (s.st_mtime_ns, s.st_size)
        for p in directory.rglob("*")
        if p.is_file() and not p.name.endswith((".lock", ".tmp"))
        for s in [p.stat()]
    }


def jax_backend() -> str:
    """``jax.default_backend()`` of a child process: this one starts no backend, so holds
    no GPU memory that workers would need, and its runs still get their XLA flags."""
    done = subprocess.run(
        [sys.executable, "-c", "import jax; print(jax.default_backend())"],
        capture_output=True,
        text=True,
    )
    if done.returncode != 0:
        raise RuntimeError(f"JAX could not start to tell its backend: {done.stderr[-500:]}")
    return done.stdout.split()[-1]


def check_backend(profile: str, force_cpu: bool) -> None:
    """Refuse the paper profile where JAX finds no GPU, unless ``force_cpu``."""
    if profile == "paper" and not force_cpu and jax_backend() == "cpu":
        raise ValueError(
            "the paper profile is meant for a GPU, and JAX finds none here (its backend is "
            "cpu); run --profile cpu, or add --force-cpu to run the paper profile on the CPU"
        )


def main(argv: list[str] | None = None) -> int:
    """``python -m sgb`` with ``argv``; its exit status (2 for bad arguments, 1 for a failed
    run)."""
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["grid"]:
        from sgb import grid

        return grid.main(argv[1:], main)
    if argv[:1] == ["manifest"]:
        from sgb import gather, manifest

        return manifest.main(argv[1:], gather.model_of)
    args = build_parser().parse_args(argv)
    options = {k: v for k, v in (("dataset", args.dataset), ("env", args.env)) if v is not None}
    experiment = get_experiment(args.experiment)
    try:
        out_dir = resolve_out_dir(args.out_dir, args.maintainer_write_committed)
        run = experiment.run
        _check_options(args.experiment, run, options)
        _check_choices(experiment.profiles, args.profile, options)
        workers = worker_count(args.experiment, args.profile, args.workers, args.ray)
        if args.ray is None:  # on a cluster, its machines run the profile, not this one
            check_backend(args.profile, args.force_cpu)
        print(f"{args.experiment} ({args.profile}): results go to {out_dir}", flush=True)
        before = _files(out_dir)
        if experiment.shares_runs:
            # its runs take one XLA thread here as in a worker, so come out the same (sgb.cluster)
            os.environ["XLA_FLAGS"] = cluster.one_thread(os.environ.get("XLA_FLAGS", ""))
        if workers > 1 or args.ray is not None:
            where = args.ray or "a local Ray cluster"
            print(f"  {workers} workers share the runs, on {where}", flush=True)
            task = functools.partial(run, args.profile, out_dir, **options)
            path = cluster.run_workers(task, workers, args.ray)[-1]
        else:
            path = run(args.profile, out_dir, **options)
    except (ValueError, TypeError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    except (OSError, RuntimeError, TrainingDiverged) as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    after = _files(out_dir)
    changed = sorted(p for p in after if before.get(p) != after[p])
    if Path(path).resolve() in changed:
        print(f"wrote {path}")
    else:
        print(
            f"kept {path}: the results came out as the file already had them, so it keeps "
            "its provenance (the run that made them)"
        )
    others = [p for p in changed if p != Path(path).resolve()]
    if others:
        print(f"also wrote {len(others)} other files under {out_dir} (checkpoints, states)")
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


def _check_choices(profiles: Mapping[str, Any], profile: str, options: dict[str, str]) -> None:
    """Reject a --dataset or --env that names no config of ``profile``, for an experiment
    whose profiles hold one per dataset or environment (``sgb.recording.pick``)."""
    if not isinstance(profiles[profile], Mapping):
        return
    known = sorted({name for configs in profiles.values() for name in configs})
    for option, value in options.items():
        if value not in known:
            raise ValueError(f"unknown {option} {value!r}; choose one of {known}")
        pick(profiles, profile, value)


if __name__ == "__main__":
    sys.exit(main())
