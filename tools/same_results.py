"""Do two results directories hold the same results? A check for changes that must not
change what an experiment computes (a refactor of how runs are recorded, say): run the same
experiments at the same profile from the code before and after into two directories, then

    python tools/same_results.py BEFORE_DIR AFTER_DIR

compares every results file (``*.json`` with results, under ``rl/`` too) that both hold:
the results exactly but for the bookkeeping of each run (``RUN_FIELDS``: when, how fast
and from which commit it ran), and the provenance fields that make two runs the same
(config, profile, seeds); and every checkpoint (``*.msgpack``) byte for byte. Prints one
line per file and exits 1 if any differs or either directory lacks a file of the other.
"""

import argparse
import sys
from pathlib import Path

from sgb.provenance import SAME_RUN_FIELDS, read_results

RUN_FIELDS = (
    "wall_time_s",
    "cpu_time_s",
    "training_wall_time_s",
    "training_cpu_time_s",
    "git_commit",
    "date",
    "train_steps_per_s",
    "env_steps_per_s",
)


def without_run_fields(value):
    """``value`` with every ``RUN_FIELDS`` entry of its dicts, at any depth, left out."""
    if isinstance(value, dict):
        return {k: without_run_fields(v) for k, v in value.items() if k not in RUN_FIELDS}
    if isinstance(value, list):
        return [without_run_fields(v) for v in value]
    return value


def differences(before: Path, after: Path) -> list[str] | None:
    """What differs between two results files (the results, SAME_RUN_FIELDS) or two
    checkpoints (their bytes); ``None`` for a JSON file without results (a checkpoint's
    sidecar, whose checkpoint is compared)."""
    if before.suffix == ".msgpack":
        return [] if before.read_bytes() == after.read_bytes() else ["bytes"]
    old, new = read_results(before), read_results(after)
    if "results" not in old:
        return None
    same = without_run_fields(old["results"]) == without_run_fields(new["results"])
    names = [] if same else ["results"]
    old, new = old["provenance"], new["provenance"]
    return names + [f"provenance.{k}" for k in SAME_RUN_FIELDS if old.get(k) != new.get(k)]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before", type=Path)
    parser.add_argument("after", type=Path)
    args = parser.parse_args()
    files = {
        side: {p.relative_to(root) for p in (*root.rglob("*.json"), *root.rglob("*.msgpack"))}
        for side, root in (("before", args.before), ("after", args.after))
    }
    status = 0
    for name in sorted(files["before"] ^ files["after"]):
        print(f"{name}: only in {'before' if name in files['before'] else 'after'}")
        status = 1
    for name in sorted(files["before"] & files["after"]):
        differ = differences(args.before / name, args.after / name)
        if differ is None:
            continue
        print(f"{name}: {'differs in ' + ', '.join(differ) if differ else 'the same'}")
        status |= bool(differ)
    return status


if __name__ == "__main__":
    sys.exit(main())
