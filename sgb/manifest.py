"""The manifest of the committed results: ``results/MANIFEST.json`` holds the sha256 of the
bytes of every results file under ``results/``, by its path there (``"rl/fig5_ant_cpu.json"``),
as the run that wrote it left them.

``sgb.recording.write_results`` enters every file it writes into the committed results
(``record``); the readers (``sgb.results.load``, through which the chapters and the
scorecard read) refuse a file whose bytes differ from its entry, or that has none
(``verify``), so that a file edited by hand is refused, by name. A results file that a run
wrote elsewhere (a worktree at another commit, a GPU machine) is entered by a maintainer
once it is copied in:

    python -m sgb manifest --maintainer-write-committed results/rl/fig5_ant_cpu.json

which checks it first (``add``, under the model its experiment declares). Checkpoints
(``results/*/checkpoints/``) and smoke runs, which git ignores, are not entered.
"""

import argparse
import hashlib
import json
import subprocess
import sys
from collections.abc import Callable, Iterable
from pathlib import Path, PurePosixPath

from sgb import runlock, schemas
from sgb.paths import committed_results
from sgb.provenance import atomic_write, read_results, verify_checksum
from sgb.validation import CorruptFile

NAME = "MANIFEST.json"
# the flag without which neither this module nor ``python -m sgb reproduce`` writes the
# committed results
MAINTAINER_FLAG = "--maintainer-write-committed"
REPOSITORY = Path(__file__).resolve().parent.parent  # the git checkout of this package
ABOUT = (
    "sha256 of the bytes of each results file, entered by the run that wrote it or by "
    "python -m sgb manifest (sgb.manifest); not to be edited by hand"
)


def covers(name: str) -> bool:
    """Whether the manifest keeps results file ``name`` (a path under the results
    directory): a JSON file, not the manifest, a checkpoint's sidecar or a smoke run's."""
    parts = PurePosixPath(name).parts
    return (
        name.endswith(".json")
        and name != NAME
        and "checkpoints" not in parts
        and "_smoke." not in parts[-1]
    )


def digest(path: str | Path) -> str:
    """The sha256 of the bytes of ``path``, in hex."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def _committed() -> Path | None:
    try:
        return committed_results().resolve()
    except FileNotFoundError:
        return None


def _name(path: str | Path, root: Path | None) -> str | None:
    """``path`` as a name under ``root`` if it lies there and the manifest covers it."""
    if root is None:
        return None
    try:
        name = Path(path).resolve().relative_to(root).as_posix()
    except ValueError:
        return None
    return name if covers(name) else None


def entries(root: str | Path) -> dict[str, str]:
    """The manifest of the results directory ``root``: name -> sha256 (``{}`` if it has
    none); a CorruptFile if the manifest is not one."""
    manifest = Path(root) / NAME
    if not manifest.exists():
        return {}
    try:
        written = json.loads(manifest.read_bytes())["sha256"]
    except (UnicodeDecodeError, json.JSONDecodeError, TypeError, KeyError) as error:
        raise CorruptFile(
            manifest, f"is not a manifest ({error!r})", _restore(root, NAME), "manifest"
        ) from error
    if not isinstance(written, dict):
        raise CorruptFile(manifest, "holds no sha256 object", _restore(root, NAME), "manifest")
    return written


def _restore(root: str | Path, name: str) -> str:
    return f"restore it from git (git checkout -- {Path(root).name}/{name})"


def _enter(root: Path, files: list[Path]) -> None:
    """Set the entries of ``files`` (under ``root``) to their digests now, holding the
    manifest's lock, so that processes entering different files at once keep every entry."""
    with runlock.exclusive(root / NAME):
        written = entries(root) | {_name(f, root): digest(f) for f in files}
        manifest = {"about": ABOUT, "sha256": dict(sorted(written.items()))}
        atomic_write(root / NAME, (json.dumps(manifest, indent=1) + "\n").encode())


def record(path: str | Path) -> None:
    """Enter results file ``path`` into the manifest of the committed results if it lies in
    them and the manifest covers it; else nothing."""
    root = _committed()
    if _name(path, root) is not None:
        _enter(root, [Path(path)])


def verify(path: str | Path, root: str | Path | None = None) -> None:
    """Refuse results file ``path`` under the results directory ``root`` (default: the
    committed results) unless its bytes match its entry in ``root``'s manifest: a
    CorruptFile naming it and the remedy. Not checked: a file outside ``root`` or that the
    manifest does not cover, and a directory other than the committed results that has no
    manifest (a run's own ``--out-dir``)."""
    committed = _committed()
    root = committed if root is None else Path(root).resolve()
    name = _name(path, root)
    if name is None:
        return
    manifest = root / NAME
    if not manifest.exists():
        if root != committed:
            return
        raise CorruptFile(manifest, "is missing", _restore(root, NAME), "manifest")
    entry = entries(root).get(name)
    if entry == digest(path):
        return
    problem = (
        f"has no entry in {manifest}"
        if entry is None
        else f"differs from its entry in {manifest}: its bytes are not those its run wrote"
    )
    remedy = (
        f"{_restore(root, name)} or run its experiment again with --maintainer-write-committed; "
        f"a file a run wrote elsewhere is entered with python -m sgb manifest "
        f"--maintainer-write-committed {path}"
    )
    raise CorruptFile(path, problem, remedy, "results file")


def _check_commit(path: Path, commit: object, repository: Path) -> None:
    """Refuse results file ``path`` unless ``commit`` (its provenance's, ``+dirty`` allowed)
    is a commit of the git repository at ``repository``."""
    known = isinstance(commit, str) and bool(commit)
    if known:
        try:
            done = subprocess.run(
                ["git", "cat-file", "-e", f"{commit.removesuffix('+dirty')}^{{commit}}"],
                cwd=repository,
                capture_output=True,
            )
        except OSError as error:
            raise ValueError(f"cannot ask git of {repository} for commits: {error}") from error
        known = done.returncode == 0
    if not known:
        raise CorruptFile(
            path,
            f"names commit {commit!r}, which is not a commit of the repository at {repository}",
            "fetch the commit its run ran at, or run it again at a commit of this repository",
            "results file",
        )


def add(
    paths: Iterable[str | Path], model_of: Callable[[str], type[schemas.ResultsFile]]
) -> list[str]:
    """Enter results files a run wrote elsewhere into the committed results' manifest, once
    each passes the checks: it lies in the committed results and the manifest covers it,
    the commit of its provenance is one of this repository, its payload matches the
    checksum its run wrote (where it wrote one) and it parses under its model
    (``model_of(name)``, e.g. ``sgb.gather.model_of``). Returns their names; if one fails
    (a ValueError or CorruptFile naming it), none is entered."""
    root = _committed()
    if root is None:
        raise ValueError("no committed results next to the sgb package to enter files into")
    files = [Path(p) for p in paths]
    for file in files:
        name = _name(file, root)
        if name is None:
            raise ValueError(
                f"{file} is not a results file of the committed results ({root}): a .json "
                "file under it, not a checkpoint's sidecar or a smoke run's"
            )
        payload = read_results(file, schemas.REWRITE)
        verify_checksum(file, payload, schemas.REWRITE)
        schemas.check(model_of(name), payload, file)
        _check_commit(file, payload["provenance"]["git_commit"], REPOSITORY)
    _enter(root, files)
    return [_name(file, root) for file in files]


def main(argv: list[str], model_of: Callable[[str], type[schemas.ResultsFile]]) -> int:
    """``python -m sgb manifest --maintainer-write-committed PATH...``: ``add``."""
    parser = argparse.ArgumentParser(
        prog="python -m sgb manifest",
        description="Enter results files that a run wrote on another machine, and that are "
        "now copied into the committed results/, into results/MANIFEST.json, once each is "
        "checked: its commit is one of this repository, its checksum and its schema hold.",
    )
    parser.add_argument("paths", nargs="+", type=Path, help="results files under results/")
    parser.add_argument(MAINTAINER_FLAG, action="store_true", help="write results/MANIFEST.json")
    args = parser.parse_args(argv)
    if not args.maintainer_write_committed:
        print(f"error: the manifest is written only with {MAINTAINER_FLAG}", file=sys.stderr)
        return 2
    try:
        names = add(args.paths, model_of)
    except (ValueError, OSError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    print(f"entered in {committed_results() / NAME}: {', '.join(names)}")
    return 0
