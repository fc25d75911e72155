"""The scorecard's rows and every chapter's glued texts, computed from the committed
results and kept in ``tests/data/snapshot.json`` with the digests of the files they came
from: ``test_snapshot`` fails on any change to them that no changed results file explains.

    python tests/snapshot.py   # rewrite it, in the commit that lands new results
"""

import hashlib
import json
import math
from pathlib import Path

from sgb import chapters, claims, gather, manifest, scorecard
from sgb.paths import committed_results

SNAPSHOT = Path(__file__).resolve().parent / "data" / "snapshot.json"


def current() -> dict:
    """The results' digests, each scorecard row (its key, its table's columns and its p
    after Holm's correction), the scorecard page's sha256 and every chapter's texts."""
    results_dir = committed_results()
    rows = gather.scorecard(results_dir)
    card = claims.by_key(rows)
    table = claims.table(rows).to_dict("records")
    holm = ["-" if math.isnan(q) else f"{q:.6g}" for q in scorecard.holm_p(rows)]
    page = scorecard.html(rows).encode()
    return {
        "results": manifest.entries(results_dir),
        "rows": [
            {"key": r.key, **cells, "holm p": q}
            for r, cells, q in zip(rows, table, holm, strict=True)
        ],
        "scorecard_html_sha256": hashlib.sha256(page).hexdigest(),
        "texts": {name: chapters.texts(name, results_dir, card) for name in chapters.CHAPTERS},
    }


def write() -> None:
    SNAPSHOT.write_text(json.dumps(current(), indent=1, ensure_ascii=False) + "\n")


if __name__ == "__main__":
    write()
    print(f"wrote {SNAPSHOT}")
