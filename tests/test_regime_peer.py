"""``sgb.experiments.regime_peer``: the prediction interval of one more run covers it at
the stated rate, and the authors' values are set beside ours only at the steps they
evaluated."""

import numpy as np

from sgb.experiments import regime_peer


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
