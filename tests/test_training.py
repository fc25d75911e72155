"""The one minibatch loop: steps, epochs, hooks."""

import numpy as np
import pytest

from sgb.training import train_loop


def test_loop_visits_every_example_once_per_epoch_and_calls_the_hook_on_schedule():
    x = np.arange(10, dtype=np.float32)[:, None]
    y = np.zeros(10, np.int32)
    seen, hooks = [], []

    def step(state, xb, yb, key):
        seen.extend(xb[:, 0].tolist())
        return state + 1, {"loss": float(xb.mean())}

    def hook(state):
        hooks.append(state)
        return state

    state, history = train_loop(
        0,
        step,
        x,
        y,
        batch_size=3,
        num_steps=7,
        seed=0,
        hook=hook,
        hook_every=2,
        params_of=lambda state: state,
        progress=False,
    )
    assert state == 7 and hooks == [2, 4, 6]
    # 3 batches of 3 per epoch (the 10th example dropped), then a partial epoch of one step
    assert [round(h["epoch"], 3) for h in history] == [1.0, 2.0, round(7 / 3, 3)]
    assert len(set(seen[:9])) == 9 and len(set(seen[9:18])) == 9
    assert history[0]["loss"] == pytest.approx(np.mean(seen[:9]))
    with pytest.raises(ValueError, match="hook_every"):
        train_loop(0, step, x, y, batch_size=3, num_steps=1, seed=0, hook=hook)


def test_loop_stops_at_the_first_non_finite_loss():
    from sgb.divergence import TrainingDiverged

    x, y = np.zeros((8, 1), np.float32), np.zeros(8, np.int32)

    def step(state, xb, yb, key):
        return state + 1, {"loss": float("nan") if state == 2 else 0.0}

    with pytest.raises(TrainingDiverged, match="step 3"):
        train_loop(0, step, x, y, batch_size=2, num_steps=5, seed=0, progress=False)
