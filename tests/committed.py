"""The committed results as the tests read them: as records (``RECORDS``, through the
package) and as plain JSON (``raw``, without it), so that a test can set one against the
other."""

import json

from sgb import gather
from sgb.paths import committed_results

RECORDS = gather.records()  # the committed results, read by experiment


def raw(name: str) -> dict:
    """A committed results file as plain JSON, read without the package."""
    return json.loads((committed_results() / name).read_text())
