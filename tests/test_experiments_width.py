"""``sgb.experiments.width``: a smoke sweep pairs each SGB with a DGB of its compression
and lists its cells in the queue; the row finds a known growth of the SGB's lead."""

import numpy as np

from sgb import verdicts
from sgb.compression import compression
from sgb.experiments import width
from sgb.provenance import read_results
from sgb.supervised_sweep import sweep_cells


def test_at_each_cpu_width_the_dgb_is_compressed_as_the_sgb_is():
    """On Fashion-MNIST's shapes, at 200, 800 and 3,200 hidden units, the DGB's g-net
    width gives a compression (our count) within 2 % of the SGB's with 10 hidden types,
    which rises with the width."""
    config = width.PROFILES["cpu"]
    ratios = []
    for w in config.widths:
        sizes = (784, w, 10)
        cells = {m: s for m, s, _ in sweep_cells(config.sweep(w, (28, 28), 10), sizes)}
        sgb = compression("sgb", sizes, cells["sgb"], 30, 10)
        dgb = compression("dgb", sizes, cells["dgb"], 30, 10, layout="authors")
        assert cells["sgb"] == 10 and abs(dgb / sgb - 1) < 0.02
        ratios.append(sgb)
    assert ratios == sorted(ratios)


def test_a_smoke_sweep_trains_each_cell_once_and_the_queue_lists_them_done(tmp_path):
    """Each width's two models at one seed; a rerun trains nothing; the queue lists every
    cell done, with its wall time."""
    path = width.run("smoke", tmp_path, progress=False)
    cells = read_results(path)["results"]["cells"]
    config = width.PROFILES["smoke"]
    assert sorted((c["width"], c["model"]) for c in cells) == sorted(
        (w, m) for w in config.widths for m in ("sgb", "dgb")
    )
    before = path.read_bytes()
    width.run("smoke", tmp_path, progress=False)
    assert path.read_bytes() == before
    queue = width.queued("smoke", tmp_path)
    assert queue.results == path and len(queue.runs) == len(cells)
    assert all(r.finished and r.wall_time_s > 0 for r in queue.runs)


def _results(leads: dict[int, list[float]]) -> width.WidthResults:
    """Width results whose SGB leads its DGB by ``leads[w][seed]`` points at width w."""
    cells = []
    for w, by_seed in leads.items():
        for seed, lead in enumerate(by_seed):
            for model, accuracy in (("sgb", 0.6 + lead / 100), ("dgb", 0.6)):
                cells.append(
                    {
                        "width": w,
                        "model": model,
                        "setting": 10,
                        "seed": seed,
                        "accuracy": accuracy,
                        "compression": w / 2,
                        "compression_authors": w,
                    }
                )
    return width.WidthResults.model_validate({"cells": cells})


def test_the_row_finds_a_lead_that_grows_by_a_point_per_doubling_and_a_flat_one():
    rng = np.random.default_rng(4)
    widths = (200, 800, 3200)

    def leads(per_doubling: float) -> dict[int, list[float]]:
        return {w: list(per_doubling * np.log2(w / 200) + 0.2 * rng.normal(size=4)) for w in widths}

    (growing,) = width.width_rows(_results(leads(1.0)), "toy")
    assert growing.verdict == verdicts.REPRODUCED
    assert growing.test.low < 1.0 < growing.test.high
    (flat,) = width.width_rows(_results(leads(0.0)), "toy")
    assert flat.verdict == verdicts.CONTRADICTED
    assert width.width_rows(_results({200: [1.0, 2.0]}), "toy") == []
