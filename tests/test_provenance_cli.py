"""Results files carry full provenance; the command line writes where it is told."""

import json

import numpy as np
import pytest

from sgb.__main__ import main
from sgb.provenance import provenance, read_results
from sgb.recording import write_results


def test_results_files_carry_full_provenance(tmp_path):
    record = provenance({"lr": 0.1}, "smoke", [0, 1], 1.234)
    path = write_results(tmp_path / "r.json", {"acc": np.array([0.5, 0.6])}, record)
    loaded = read_results(path)
    prov = loaded["provenance"]
    for field in ("config", "profile", "seeds", "git_commit", "versions", "date", "wall_time_s"):
        assert field in prov
    assert prov["versions"]["jax"] and prov["versions"]["sgb"]
    assert loaded["results"]["acc"] == [0.5, 0.6]
    json.dumps(loaded)


def test_cli_reports_a_bad_profile_without_a_traceback(capsys):
    with pytest.raises(SystemExit):
        main(["reproduce", "bbb", "--profile", "huge"])
    assert "invalid choice" in capsys.readouterr().err


def test_cli_rejects_an_option_the_experiment_does_not_take(capsys):
    assert main(["reproduce", "bbb", "--dataset", "mnist"]) == 2
    assert "bbb does not take --dataset" in capsys.readouterr().err
