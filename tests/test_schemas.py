"""The models of the results files (``sgb.schemas``, pydantic) refuse a committed file
damaged in one field, naming the file and the field, and accept the nulls a reader expects."""

import json

import pytest

from sgb import gather, schemas
from sgb.paths import committed_results
from sgb.validation import CorruptFile


def _payload(name: str) -> dict:
    return json.loads((committed_results() / name).read_text())


def _set(path: tuple, value):
    """A change of the payload: the entry at ``path`` (keys and indices) set to ``value``."""

    def change(payload: dict) -> None:
        *inner, last = path
        for key in inner:
            payload = payload[key]
        payload[last] = value

    return change


def _delete(path: tuple):
    def change(payload: dict) -> None:
        *inner, last = path
        for key in inner:
            payload = payload[key]
        del payload[last]

    return change


FIG5 = "rl/fig5_ant_cpu.json"
RETURNS = ("results", "returns", "normal", "individuals")
SUPERVISED = "innate_start_supervised_fashion-mnist_cpu.json"


@pytest.mark.parametrize(
    ("name", "change", "problem"),
    [
        (FIG5, _set((*RETURNS, 3, 1), None), r"individuals\[3\]\[1\] = null: Input should"),
        (FIG5, _set((*RETURNS, 0, 0), 1e308), r"individuals\[0\]\[0\] = 1e\+308: .* less than or"),
        (FIG5, _set((*RETURNS, 0, 1), float("nan")), r"\[0\]\[1\] = NaN: Input should be a finite"),
        (FIG5, _set((*RETURNS, 0, 0), True), r"individuals\[0\]\[0\] = true: Input should be a"),
        (FIG5, _set((*RETURNS, 2), [1.0, 2.0]), r"individuals: row 2 has 2 entries, the first 3"),
        (FIG5, _set((*RETURNS,), []), r"individuals = \[\]: List should have at least 1 item"),
        (
            FIG5,
            _delete(("results", "authors_protocol", "t")),
            r"has no results\.authors_protocol\.t",
        ),
        (
            FIG5,
            _set(("provenance", "wall_time_s"), -1.0),
            r"provenance\.wall_time_s = -1.0: Input should be greater than or equal to 0",
        ),
        (SUPERVISED, _set(("results", "records", 0, "runs", 2, "accuracy", 1), None), "= null"),
        (
            SUPERVISED,
            _set(("results", "summary", 0, "accuracy", 0), 1.5),
            r"summary\[0\]\.accuracy\[0\] = 1\.5: Input should be less than or equal to 1",
        ),
        ("rl/fig3_ant_cpu.json", _set(("results", "runs", 0, "cell_types"), "64"), "cell_types"),
    ],
)
def test_a_file_damaged_in_one_field_is_refused_naming_the_file_and_the_field(
    name, change, problem
):
    payload = _payload(name)
    schemas.check(gather.model_of(name), payload, "unchanged")
    change(payload)
    with pytest.raises(CorruptFile, match=problem) as error:
        schemas.check(gather.model_of(name), payload, committed_results() / name)
    assert error.value.path == committed_results() / name
    assert str(error.value).startswith(f"results file {committed_results() / name} has ")


@pytest.mark.parametrize(
    ("name", "change"),
    [
        (
            "fig2_fashion-mnist_cpu.json",
            _set(("results", "ours", "summary", "sgb", "sem", 0), None),
        ),
        (SUPERVISED, _set(("results", "summary", 0, "accuracy_sem", 0), None)),
        (FIG5, _set((*RETURNS, 0, 0), schemas.MAX_RETURN)),
        ("rl/fig3_ant_cpu.json", _set(("results", "runs", 0, "cell_types"), None)),
        ("rl/populations_ant_cpu.json", _delete(("results", "genomes", "ant_k64_s0", "summary"))),
    ],
)
def test_the_nulls_and_absences_a_reader_expects_are_accepted(name, change):
    payload = _payload(name)
    change(payload)
    schemas.check(gather.model_of(name), payload, committed_results() / name)


def test_a_return_is_bounded_by_the_longest_episode_at_a_speed_no_body_reaches():
    assert schemas.MAX_RETURN == schemas.EPISODE_STEPS * schemas.MAX_SPEED == 50_000
    returns = [
        value
        for name in ("rl/fig3_ant_cpu.json", "rl/innate_start_ant_cpu.json")
        for run in _payload(name)["results"]["runs"]
        for value in run["eval_returns"]
    ]
    assert max(returns) < schemas.MAX_RETURN / 3  # the fastest run is far inside the bound
