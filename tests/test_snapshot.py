"""The scorecard and the chapters' texts are those of the snapshot: a change of code that
moves a row or a glued text fails here unless the committed results moved too."""

import json

import pytest
from snapshot import SNAPSHOT, current


def test_the_scorecard_and_the_chapters_texts_are_the_snapshots():
    saved = json.loads(SNAPSHOT.read_text())
    now = current()
    if now["results"] != saved["results"]:
        changed = sorted(
            name
            for name in set(now["results"]) | set(saved["results"])
            if now["results"].get(name) != saved["results"].get(name)
        )
        pytest.fail(
            f"results changed since the snapshot ({', '.join(changed)}): check the rows and "
            "texts they move, then rewrite it with python tests/snapshot.py"
        )
    assert now["rows"] == saved["rows"]
    assert now["texts"] == saved["texts"]
    assert now["scorecard_html_sha256"] == saved["scorecard_html_sha256"]
