"""Figure 2's SGB trained the authors' way (``sgb.experiments.sgb_full``): every variant's
cells trained once, with the variant's KL counting and rho start, and a rerun that trains
only what is missing."""

import json

import numpy as np

from sgb import supervised_sweep
from sgb.experiments import sgb_full
from sgb.provenance import read_results


def test_a_smoke_run_trains_each_variant_once_and_a_rerun_only_what_is_missing(
    tmp_path, monkeypatch
):
    trained = []
    real = supervised_sweep.run_one

    def counted(kind, setting, seed, data, sweep):
        trained.append((sweep.sgb.kl_counting, sweep.sgb.rho_init))
        return real(kind, setting, seed, data, sweep)

    monkeypatch.setattr(sgb_full, "run_one", counted)
    path = sgb_full.run("smoke", tmp_path, progress=False)
    assert sorted(trained) == [("synapse", -7.0), ("synapse", -5.0), ("table", -7.0)]
    payload = read_results(path)
    results = payload["results"]
    assert results["complete"] and set(results["variants"]) == set(sgb_full.VARIANTS)
    for name, cell in results["cells"].items():
        assert name.startswith(cell["variant"]) and cell["model"] == "sgb"
        (layer_0, layer_1) = cell["layers"]
        # one epoch from rho = -7 or -5 leaves sigma near its start: softplus(-7) = 9e-4
        start = np.log1p(np.exp(sgb_full.VARIANTS[cell["variant"]]["rho_init"]))
        assert 0.2 * start < layer_0["mean_sigma"] < 20 * start
    assert payload["provenance"]["git_commits"]

    trained.clear()
    assert sgb_full.run("smoke", tmp_path, progress=False) == path and trained == []
    names = set(results["cells"])
    del results["cells"][min(names)]  # a cell lost: the only one trained again
    path.write_text(json.dumps(payload))
    sgb_full.run("smoke", tmp_path, progress=False)
    assert len(trained) == 1 and set(read_results(path)["results"]["cells"]) == names
