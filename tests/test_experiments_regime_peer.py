"""``sgb.experiments.regime_peer``: the prediction interval of one more run covers it at
the stated rate, and the authors' values are set beside ours only at the steps they
evaluated."""

import json

import numpy as np

from sgb import (
    prose,
)
from sgb.experiments import (
    regime_peer,
)


def test_the_prediction_interval_of_one_more_run_covers_it_95_times_in_100():
    rng = np.random.default_rng(0)
    draws = rng.normal(5.0, 2.0, size=(4000, 4))  # three runs of ours, one more
    covered = [
        low <= d[3] <= high for d in draws for low, high in [regime_peer.prediction_interval(d[:3])]
    ]
    assert abs(np.mean(covered) - 0.95) < 0.01


def test_the_comparison_sets_the_authors_value_beside_ours_at_their_steps_only():
    steps = list(regime_peer.THEIR_STEPS)
    runs = [
        {
            "label": "k64_aliased",
            "eval_steps": steps,
            "eval_returns": [-560.0 + d, -500.0 + d / 100, x],
        }
        for d, x in ((0.0, -300.0), (10.0, -360.0), (-10.0, -330.0))
    ]
    runs.append({"label": "vanilla", "eval_steps": [0, 160, 320], "eval_returns": [1, 2, 3]})
    rows = {(r["label"], r["step"]): r for r in regime_peer.compare(runs)}
    last = rows[("k64_aliased", steps[2])]
    assert last["theirs"] == -351.2 and last["mean"] == -330.0
    low, high = last["interval"]
    assert low < -351.2 < high and last["inside"] is True
    assert rows[("k64_aliased", steps[1])]["inside"] is False  # -500 +- 0.5 leaves -496.4 out
    # vanilla evaluated at other steps (a smoke run): nothing of theirs beside it
    assert {r["theirs"] for k, r in rows.items() if k[0] == "vanilla"} == {None}


def test_the_peer_texts_set_the_authors_run_against_the_interval_of_ours():
    """Three seeds of ours, the authors' one run inside their interval for vanilla and
    outside it for the aliased layer; nothing from a point they did not evaluate."""

    def run(label: str, last: list[float]) -> list[dict]:
        steps = list(regime_peer.THEIR_STEPS)
        return [{"label": label, "eval_steps": steps, "eval_returns": [0.0, 0.0, x]} for x in last]

    runs = run("vanilla", [250.0, 300.0, 350.0]) + run("k64_aliased", [-100.0, -90.0, -110.0])
    results = {"env": "ant", "runs": [], "comparison": regime_peer.compare(runs)}
    stored = json.loads(json.dumps(results))  # as the file holds it: the interval a list
    texts = regime_peer.regime_peer(regime_peer.RegimePeerResults.model_validate(stored))
    assert texts["peer_vanilla_ours"].startswith("250, 300, 350 at 1,638,400 steps (mean 300")
    assert (texts["peer_vanilla_theirs"], texts["peer_vanilla_inside"]) == ("279.8", "inside")
    assert (texts["peer_aliased_theirs"], texts["peer_aliased_inside"]) == ("-351.2", "outside")
    assert set(regime_peer.regime_peer(None).values()) == {prose.NOT_RUN}
