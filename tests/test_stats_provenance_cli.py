import json

import numpy as np
import pytest
from scipy import stats as scipy_stats

from sgb import stats
from sgb.__main__ import main
from sgb.provenance import provenance, read_results
from sgb.recording import write_results


def test_sem_and_confidence_interval_cover_the_true_mean_at_the_stated_rate():
    rng = np.random.default_rng(0)
    samples = rng.normal(3.0, 2.0, size=(2000, 10))
    covered = [lo <= 3.0 <= hi for _, lo, hi in map(stats.mean_ci, samples)]
    assert abs(np.mean(covered) - 0.95) < 0.02
    np.testing.assert_allclose(stats.sem(samples[0]), samples[0].std(ddof=1) / np.sqrt(10))


def test_r_and_the_t_tests_agree_with_scipy():
    """Each test's estimate, statistic and p against scipy's own: Pearson's r, the paired
    and the one-sample t (the statistic the Figure 5 protocols write)."""
    rng = np.random.default_rng(1)
    x = rng.normal(size=50)
    y = 0.6 * x + rng.normal(size=50)
    r, theirs = stats.fisher_r(x, y), scipy_stats.pearsonr(x, y)
    assert (r.estimate, r.p, r.dof) == pytest.approx((theirs.statistic, theirs.pvalue, 48))
    t, theirs = stats.paired(y, x), scipy_stats.ttest_rel(y, x)
    assert (t.statistic, t.p, t.dof) == pytest.approx((theirs.statistic, theirs.pvalue, 49))
    assert t.estimate == pytest.approx(np.mean(y - x))
    one, theirs = stats.one_sample(y, 0.25), scipy_stats.ttest_1samp(y, 0.25)
    assert (one.statistic, one.p, one.dof) == pytest.approx((theirs.statistic, theirs.pvalue, 49))


def test_stats_reject_bad_input():
    with pytest.raises(ValueError, match="same length"):
        stats.fisher_r([1, 2, 3, 4, 5], [1, 2, 3, 4])
    with pytest.raises(ValueError, match="at least 2"):
        stats.paired([1.0], [2.0])
    with pytest.raises(ValueError, match="level"):
        stats.mean_ci([1, 2, 3], level=1.5)


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
