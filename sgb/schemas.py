"""Schemas of the results files: the evidence each experiment's file holds, checked before a
reader uses it (``check``), so that a damaged or edited file is refused with an error naming
it and the field, not read into a ``KeyError``, a numpy ``TypeError`` or another verdict.

A schema is a value of this small language:

- a ``dict``: an object with these keys (others may be present), each under its schema; a
  key whose schema is ``Optional(...)`` may be absent;
- ``Array(item, ndim)``: a rectangular list ``ndim`` deep, non-empty unless ``allow_empty``,
  each entry under ``item``; ``Each(item)``: an object whose every value is under ``item``;
- ``Number(low, high)``: a finite number in [low, high]; ``Integer(low)``; ``Null(schema)``:
  null or ``schema``;
- ``str``, ``bool``, ``dict``: a string, a boolean, any object.

A results file writes a non-finite number as null (``sgb.provenance.NULL_MEANS``); null is
accepted only under ``Null``, where a reader expects it (an SEM of one seed, vanilla's cell
types). Each schema names the fields the book's readers use (``sgb.claims``, ``sgb.prose``,
``sgb.results``, and the returns and accuracies the figures draw), not every field.
"""

import json
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NoReturn

from sgb.validation import CorruptFile

REWRITE = "restore it from git, or run its experiment again to write it anew"


class _Mismatch(Exception):
    """A payload does not hold what its schema says; the message is what it holds instead."""


def _shown(value: Any) -> str:
    text = json.dumps(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _fail(where: str, value: Any, expected: str) -> NoReturn:
    raise _Mismatch(f"{where} = {_shown(value)}, where {expected} is read")


@dataclass(frozen=True)
class Number:
    """A finite number (not a boolean) in [low, high], or (low, high] when ``low_open``."""

    low: float = -math.inf
    high: float = math.inf
    low_open: bool = False

    def expected(self) -> str:
        if self.low == -math.inf and self.high == math.inf:
            return "a finite number"
        low = "-inf" if self.low == -math.inf else f"{self.low:g}"
        high = "inf" if self.high == math.inf else f"{self.high:g}"
        return f"a finite number in {'(' if self.low_open else '['}{low}, {high}]"

    def check(self, value: Any, where: str) -> None:
        if (
            isinstance(value, bool)
            or not isinstance(value, int | float)
            or (isinstance(value, float) and not math.isfinite(value))
            or not self.low <= value <= self.high
            or (self.low_open and value == self.low)
        ):
            _fail(where, value, self.expected())


@dataclass(frozen=True)
class Integer:
    """An integer (not a boolean) >= ``low``."""

    low: int = 0

    def check(self, value: Any, where: str) -> None:
        if isinstance(value, bool) or not isinstance(value, int) or value < self.low:
            _fail(where, value, f"an integer >= {self.low}")


@dataclass(frozen=True)
class Null:
    """Null, or a value under ``schema``."""

    schema: Any

    def check(self, value: Any, where: str) -> None:
        if value is not None:
            _check(self.schema, value, where)


@dataclass(frozen=True)
class Optional:
    """A key of an object that may be absent; present, its value is under ``schema``."""

    schema: Any

    def check(self, value: Any, where: str) -> None:
        _check(self.schema, value, where)


@dataclass(frozen=True)
class Each:
    """An object (keys: names of cells, genomes, conditions) whose every value is under
    ``item``, holding at least the keys ``keys``."""

    item: Any
    keys: tuple[str, ...] = ()

    def check(self, value: Any, where: str) -> None:
        if not isinstance(value, dict):
            _fail(where, value, "an object")
        for key in self.keys:
            if key not in value:
                raise _Mismatch(f'no {where}["{key}"]')
        for key, entry in value.items():
            _check(self.item, entry, f'{where}["{key}"]')


@dataclass(frozen=True)
class Array:
    """A rectangular list ``ndim`` deep (every list at one depth as long as the first),
    each entry under ``item``; non-empty unless ``allow_empty``."""

    item: Any
    ndim: int = 1
    allow_empty: bool = False

    def check(self, value: Any, where: str) -> None:
        shape, first = [], value
        for _ in range(self.ndim):
            if not isinstance(first, list):
                _fail(where, value, f"a list {self.ndim} deep")
            if not first:
                if self.allow_empty and not shape:
                    return
                _fail(where, value, f"a non-empty list {self.ndim} deep")
            shape.append(len(first))
            first = first[0]
        self._walk(value, where, shape)

    def _walk(self, value: Any, where: str, shape: list[int]) -> None:
        if not shape:
            _check(self.item, value, where)
            return
        if not isinstance(value, list) or len(value) != shape[0]:
            _fail(where, value, f"a list of {shape[0]} entries, as the first at this depth")
        for i, entry in enumerate(value):
            self._walk(entry, f"{where}[{i}]", shape[1:])


def _check(schema: Any, value: Any, where: str) -> None:
    """Raise ``_Mismatch`` unless ``value`` (found at ``where``) is under ``schema``."""
    if isinstance(schema, dict):
        if not isinstance(value, dict):
            _fail(where, value, "an object")
        for key, item in schema.items():
            inner = f"{where}.{key}" if where else key
            if key in value:
                _check(item, value[key], inner)
            elif not isinstance(item, Optional):
                raise _Mismatch(f"no {inner}")
    elif isinstance(schema, type):
        if not isinstance(value, schema) or (schema is not bool and isinstance(value, bool)):
            _fail(where, value, {str: "a string", bool: "a boolean", dict: "an object"}[schema])
    else:
        schema.check(value, where)


# Units and bounds --------------------------------------------------------------------------

EPISODE_STEPS = 1000  # the longest episode of any profile (Brax's episode length)
MAX_SPEED = 50.0  # m/s, far beyond any body here: the fastest committed run earns 13.5 a step
MAX_RETURN = EPISODE_STEPS * MAX_SPEED
"""The largest |return| of an episode: a step earns the body's forward speed (m/s, negative
backwards), plus the Ant's healthy reward of 1, less control and contact costs."""

FINITE = Number()
NON_NEGATIVE = Number(0)
POSITIVE = Number(0, low_open=True)
RETURN = Number(-MAX_RETURN, MAX_RETURN)
RETURNS = Array(RETURN, ndim=2)  # individuals x episodes
ACCURACY = Number(0, 1)  # a fraction of examples, as is evolution's fitness
PROBABILITY = Number(0, 1)
CORRELATION = Number(-1, 1)
RELIABILITY = Number(high=1)  # an intraclass estimate: negative where individuals do not differ
COMPRESSION = Number(1)  # the dense network's parameters over the compressed one's
SEED = Integer(0)
COUNT = Integer(1)
STEPS = Integer(0)
SECONDS = NON_NEGATIVE

PROVENANCE = {
    "config": dict,
    "profile": str,
    "seeds": Array(SEED, allow_empty=True),
    "git_commit": str,
    "git_commits": Optional(Array(str)),
    "date": str,
    "wall_time_s": SECONDS,
    "backend": str,
}
TEST = {  # a sgb.stats.Test as a file stores it; a null dof is a normal test
    "name": str,
    "estimate": FINITE,
    "low": FINITE,
    "high": FINITE,
    "dof": Null(POSITIVE),
    "p": PROBABILITY,
    "detectable": NON_NEGATIVE,
    "n": COUNT,
}


def _file(results: dict, config: Any = dict) -> dict:
    """A results file: its ``results`` and its provenance, whose config holds ``config``."""
    return {"provenance": PROVENANCE | {"config": config}, "results": results}


# Chapter 4: Figure 2 -----------------------------------------------------------------------

_CURVE = {  # one model's accuracy per setting, over seeds
    "setting": Array(FINITE),
    "compression": Array(COMPRESSION),
    "mean": Array(ACCURACY),
    "sem": Array(Null(NON_NEGATIVE)),
    "n": Array(COUNT),
}
_CONVENTION = {
    "summary": {"dense": _CURVE, "sgb": _CURVE, "dgb": _CURVE},
    "summary_mean_network": {"sgb": _CURVE},
    "crossovers": Array(COMPRESSION, allow_empty=True),
}
FIG2 = _file(
    {
        "records": Array(
            {
                "model": str,
                "setting": FINITE,
                "seed": SEED,
                "accuracy": ACCURACY,
                "compression": COMPRESSION,
            }
        ),
        "ours": _CONVENTION,
        "authors": _CONVENTION,
    }
)
SGB_FULL = _file(
    {
        "cells": Each(
            {
                "variant": str,
                "model": str,
                "setting": FINITE,
                "seed": SEED,
                "accuracy": ACCURACY,
                "mean_network": ACCURACY,
                "compression": COMPRESSION,
                "compression_authors": COMPRESSION,
                "layers": Array({"mean_sigma": NON_NEGATIVE}),
            }
        ),
        "variants": dict,
    },
    {"variants": Array(str), "sweep": {"ratios": Array(COMPRESSION), "seeds": Array(SEED)}},
)
DGB_RECORD = {
    "rounds": COUNT,
    "best_validation_accuracy": ACCURACY,
    "test_accuracy": ACCURACY,
    "generated_test_accuracy": ACCURACY,
}
DGB_FULL = _file(
    {
        "cells": Each(
            {
                "ratio": COMPRESSION,
                "seed": SEED,
                "gnet_width": COUNT,
                "compression_ours": COMPRESSION,
                "compression_authors": COMPRESSION,
                "nominal_ratio": NON_NEGATIVE,
                "records": Array(DGB_RECORD, allow_empty=True),
            }
        )
    },
    {"ratios": Array(COMPRESSION), "seeds": Array(SEED), "dgb": {"rounds": COUNT}},
)
DGB_BUDGET = _file(
    {
        "records": Array(DGB_RECORD),
        "uncompressed_same_budget": {"epochs": COUNT, "accuracy": ACCURACY},
    }
)
_NETWORKS = ("accuracy", "mean_network", "moment_network")  # the individuals' and two networks'
MEAN_GAP = _file(
    {
        "records": Array(
            {
                "setting": COUNT,
                "seed": SEED,
                "rho_init": FINITE,
                "steps": COUNT,
                "layers": Array({"rho_travel_fraction": FINITE, "end": {"mean_rho": FINITE}}),
            }
        ),
        "summary": Array(
            {
                "setting": COUNT,
                "rho_init": FINITE,
                "moment_recovery": FINITE,
                "sigma_end": NON_NEGATIVE,
                **{k: ACCURACY for k in _NETWORKS},
                **{f"{k}_sem": NON_NEGATIVE for k in _NETWORKS},
            }
        ),
    }
)

# Chapter 3: the Jensen gap -----------------------------------------------------------------

_TRAJECTORY = {
    "gap": Array(FINITE),
    "gap_stderr": Array(NON_NEGATIVE),
    "prediction": Array(FINITE),
}
_GAP = {"gap": FINITE, "stderr": NON_NEGATIVE}
_FIT = {
    "median_ratio": FINITE,
    "ratio_q10": FINITE,
    "ratio_q90": FINITE,
    "log_correlation": CORRELATION,
}
THEORY = _file(
    {
        "trajectories": {"convex": _TRAJECTORY, "concave": _TRAJECTORY},
        "elbo_toy": Optional(
            {
                "kl_weights": Array(NON_NEGATIVE),
                "predicted_sigma": Array(NON_NEGATIVE),
                "steps": Array(STEPS),
                "runs": {
                    "softplus": {
                        "settled_mean": Array(NON_NEGATIVE),
                        "settled_sd": Array(NON_NEGATIVE),
                    }
                },
            }
        ),
        "network": Array(
            {
                "cell_types": Array(Null(COUNT)),
                "sigma_mean": NON_NEGATIVE,
                "accuracy": {"mean_network": ACCURACY},
                "hutchinson_probes": COUNT,
                "hutchinson": {"value": FINITE, "stderr": NON_NEGATIVE},
                "scales": Array(
                    {
                        "scale": NON_NEGATIVE,
                        "predicted": FINITE,
                        "train_cross_entropy": _GAP,
                        "train_error_rate": _GAP,
                        "test_error_rate": _GAP,
                    }
                ),
                "layers": Array({"layer": str, "predicted": FINITE, **_GAP}),
            }
        ),
        "fixed_point": Optional(
            Array(
                {
                    "cell_types": Array(Null(COUNT)),
                    "runs": Array(
                        {
                            "epochs": COUNT,
                            "kl_weight": NON_NEGATIVE,
                            "prior_sigma": POSITIVE,
                            "population_hessians": COUNT,
                            "accuracy": {
                                "mean_network": ACCURACY,
                                "population_average": ACCURACY,
                            },
                            "layers": Each({"sigma2": Array(NON_NEGATIVE)}),
                            "summary": {"at_mean": _FIT, "population": _FIT},
                        }
                    ),
                }
            )
        ),
    }
)

# Chapter 5: Brax -------------------------------------------------------------------------

_FIG3_SUMMARY = Array(
    {
        "settings": str,
        "cell_types": Null(COUNT),
        "mean_return": RETURN,
        "sem_return": Null(NON_NEGATIVE),
        "fraction": Null(FINITE),
        "sem_fraction": Null(NON_NEGATIVE),
        "n_seeds": COUNT,
    }
)
_TRAINING = {  # one PPO run: its evaluations and its score
    "cell_types": Null(COUNT),
    "seed": SEED,
    "final_return": RETURN,
    "last_two_return": RETURN,
    "eval_steps": Array(STEPS),
    "eval_returns": Array(RETURN),
}
FIG3 = _file(
    {
        "env": str,
        "runs": Array(_TRAINING | {"settings": str}),
        "summary": _FIG3_SUMMARY,
        "summary_last_two": Optional(_FIG3_SUMMARY),
    },
    {"ppo": {"total_steps": COUNT}},
)
REGIME = _file(
    {
        "env": str,
        "runs": Array(
            _TRAINING
            | {"authors_scale": FINITE, "train_steps_per_s": POSITIVE, "wall_time_s": SECONDS}
        ),
    }
)
SPEED = Number(-MAX_SPEED, MAX_SPEED)  # m/s, forward
REGIME_GAIT = _file(
    {
        "walking_speed": POSITIVE,
        "runs": Array(
            {
                "cell_types": Null(COUNT),
                "seed": SEED,
                "genome": str,
                "window_return": RETURN,
                "forward_velocity": SPEED,
                "forward_velocity_sem": Number(0, MAX_SPEED),
                "walks": bool,
            },
            allow_empty=True,
        ),
    }
)
_CORRELATION = {"r": CORRELATION, "p": PROBABILITY}
FIG4 = _file(
    {
        "returns": {
            body: {"individuals": RETURNS}
            for body in ("normal", "long_legs", "slippery", "low_gravity")
        },
        "legs": _CORRELATION,
        "niches": _CORRELATION,
    },
    {"checkpoint": str},
)
_FIG5_TEST = {  # a test of the individuals against the mean network; ci99: mean, low, high
    "t": FINITE,
    "p": PROBABILITY,
    "individuals_ci99": Array(RETURN),
    "mean_network_ci99": Array(RETURN),
}
FIG5 = _file(
    {
        "returns": {"normal": {"individuals": RETURNS, "mean_network": RETURNS}},
        "mean_network": _FIG5_TEST,
        "authors_protocol": _FIG5_TEST | {"individuals": RETURNS, "mean_network": Array(RETURN)},
    }
)
_SPLIT = {"variance_split": {"reliability": RELIABILITY, "icc": RELIABILITY}}
_POOLED = {
    "random_effects": FINITE,
    "random_effects_ci": Array(FINITE),
    "random_effects_se": POSITIVE,
}
_POOLED_R = {  # pooled on Fisher's z
    "random_effects": CORRELATION,
    "random_effects_ci": Array(CORRELATION),
    "random_effects_z_se": POSITIVE,
}
_NORMAL = _SPLIT | {"between_sd_bound_percent": Optional(NON_NEGATIVE)}
POPULATIONS = _file(
    {
        "genomes": Each(
            {
                "settings": str,
                "parts": {"normal": {"returns": RETURNS}},
                "summary": Optional(
                    {
                        "normal": _NORMAL | {"mean_return": RETURN},
                        "long_legs": _SPLIT,
                        "mean_network": {"percent": FINITE, "percent_ci": Array(FINITE)},
                    }
                ),
            }
        ),
        "pooled": Each(
            {
                "mean_network_percent": {"fixed_effect": _POOLED},
                "legs_r": {"fixed_effect": _POOLED_R},
            }
        ),
    }
)
REGIME_POPULATIONS = _file(
    {
        "genomes": Each(
            {
                "training_seed": SEED,
                "parts": {"normal": {"returns": RETURNS}},
                "summary": Optional(
                    {
                        "mean_network": {"mean_network_return": RETURN, "test": TEST},
                        "authors_protocol": Optional(
                            {
                                "individual_episodes": COUNT,
                                "mean_network_episodes": COUNT,
                                "mean_network_mean": RETURN,
                                "one_sample": TEST,
                                "welch": TEST,
                            }
                        ),
                        "normal": _NORMAL
                        | {
                            "split_half": {
                                "episodes": COUNT,
                                "r": CORRELATION,
                                "r_ci": Array(CORRELATION),
                            }
                        },
                        "long_legs": _SPLIT,
                        "legs": {"test": TEST},
                    }
                ),
            }
        )
    }
)
SPREAD = _file(
    {
        "runs": Array(
            {
                "rho_init": FINITE,
                "sigma_init": POSITIVE,
                "seed": SEED,
                "checkpoint": str,
                "sigma_trained": NON_NEGATIVE,
                "individuals_mean": RETURN,
                "individuals_sd": NON_NEGATIVE,
                "mean_network_mean": RETURN,
                "paired_test": {"t": FINITE, "p": PROBABILITY},
            }
        )
    }
)
_SPEED = {"train_steps_per_s": POSITIVE, "wall_time_s": SECONDS}
BENCH_BACKENDS = _file(
    {
        "throughput": Each(_SPEED, keys=("spring", "mjx")),
        "reach": _SPEED | {"eval_steps": Array(STEPS), "eval_returns": Array(RETURN)},
    }
)
_BENCH_RUN = _SPEED | {"seed": SEED, "final_return": RETURN, "eval_returns": Array(RETURN)}
BENCH_RL = _file(
    {
        "throughput": {
            "population_steps_per_s": POSITIVE,
            "bare_env_steps_per_s": POSITIVE,
            "ratio": POSITIVE,
        },
        "training_throughput": {"steps_per_s": Each(POSITIVE)},
        "ours": Array(_BENCH_RUN),
        "brax": Array(_BENCH_RUN),
        "sgb_64_types": Array(_BENCH_RUN),
    }
)
BENCH_REGIME = _file(  # per configuration (vanilla: null cell types), each phase's speed
    {
        "rows": Array(
            {
                "cell_types": Null(COUNT),
                "env_steps_per_s": Each(POSITIVE),
                "ratio_to_simulator": Each(POSITIVE),
                "seconds": Each(Array(POSITIVE)),
                "bound_env_steps_per_s": POSITIVE,
                "iteration_over_bound": POSITIVE,
                "bound_over_simulator": POSITIVE,
                "sgd_flops_per_env_step": POSITIVE,
                "update_gflops": POSITIVE,
                "matmul_gflops": POSITIVE,
                "run_hours": Each(POSITIVE),
            }
        ),
        "table": Array(str),
    }
)
BENCH_PARALLEL = _file(  # per workload: its speed alone and two at once
    Each(
        {
            "alone": Array(POSITIVE),
            "two_at_once": Array(POSITIVE),
            "ratios": Array(POSITIVE),
            "median_ratio": POSITIVE,
        }
    )
)

# Chapter 6: beyond the paper ---------------------------------------------------------------

EVOLUTION = _file(
    {
        "dataset": str,
        "records": Array(
            {
                "hidden_types": COUNT,
                "stochastic": bool,
                "seed": SEED,
                "compression": COMPRESSION,
                "mean_fitness": Array(ACCURACY),
                "individuals": Array(ACCURACY),
                "mean_network": ACCURACY,
                "sigma_mean": NON_NEGATIVE,
                "wall_time_s": SECONDS,
            }
        ),
    },
    {"base": {"candidates": COUNT}},
)
_HEDGING_SCORE = {  # the survival the scorecard reads: threshold 0.5, at least 10 members
    "geometric_fitness": FINITE,
    "mean_fitness": FINITE,
    "p_at_least": Each(Each(PROBABILITY, keys=("10",)), keys=("0.5",)),
}
BET_HEDGING = _file(
    {
        "genomes": Array(
            {
                "rho_init": FINITE,
                "training_seed": SEED,
                "sigma_trained": NON_NEGATIVE,
                "scale": RETURN,
                "returns": {
                    "individuals": Each(RETURNS, keys=("normal",)),
                    "clones": Each(RETURNS, keys=("normal",)),
                },
                "scores": {"individuals": _HEDGING_SCORE, "clones": _HEDGING_SCORE},
            }
        )
    }
)
INNATE_START = _file(
    {
        "complete": bool,
        "selections": Array({"individual_means": Array(RETURN)}),
        "runs": Array(
            {
                "genome": Null(str),
                "start": str,
                "seed": SEED,
                "auc": RETURN,
                "eval_steps": Array(STEPS),
                "eval_returns": Array(RETURN),
            }
        ),
        "summary": Array(dict),
    }
)
_CURVE_OVER_STEPS = {"start": str, "steps": Array(STEPS), "accuracy": Array(ACCURACY)}
INNATE_START_SUPERVISED = _file(
    {
        "dataset": str,
        "records": Array({"runs": Array(_CURVE_OVER_STEPS)}, allow_empty=True),
        "summary": Array(
            _CURVE_OVER_STEPS | {"accuracy_sem": Array(Null(NON_NEGATIVE)), "n_seeds": COUNT}
        ),
    }
)

# Which schema a file is under, by its path under the results directory: ``*`` stands for
# a dataset, an environment or a profile (lower case, digits and hyphens).
SCHEMAS = {
    "fig2_*_*.json": FIG2,
    "sgb_full_*_*.json": SGB_FULL,
    "dgb_full_*_*.json": DGB_FULL,
    "dgb_budget_*_*.json": DGB_BUDGET,
    "mean_gap_*_*.json": MEAN_GAP,
    "theory_*.json": THEORY,
    "evolution_*_*.json": EVOLUTION,
    "innate_start_supervised_*_*.json": INNATE_START_SUPERVISED,
    "bench_parallel.json": BENCH_PARALLEL,
    "rl/fig3_*_*.json": FIG3,
    "rl/fig4_*_*.json": FIG4,
    "rl/fig5_*_*.json": FIG5,
    "rl/regime_*_*.json": REGIME,
    "rl/populations_*_*.json": POPULATIONS,
    "rl/regime_populations_*_*.json": REGIME_POPULATIONS,
    "rl/regime_gait_*_*.json": REGIME_GAIT,
    "rl/spread_*_*.json": SPREAD,
    "rl/bet_hedging_*_*.json": BET_HEDGING,
    "rl/innate_start_*_*.json": INNATE_START,
    "rl/bench_backends.json": BENCH_BACKENDS,
    "rl/bench_rl.json": BENCH_RL,
    "rl/bench_regime.json": BENCH_REGIME,
}


def schema_of(name: str) -> dict:
    """The schema of results file ``name`` (its path under the results directory, e.g.
    ``"rl/fig5_ant_cpu.json"``); a ValueError for a name that no pattern of ``SCHEMAS``, or
    more than one, covers."""
    found = [
        schema
        for pattern, schema in SCHEMAS.items()
        if re.fullmatch(re.escape(pattern).replace(r"\*", "[a-z0-9-]+"), name)
    ]
    if len(found) != 1:
        raise ValueError(f"{len(found) or 'no'} schemas in sgb.schemas cover results file {name}")
    return found[0]


def check(name: str, payload: Any, path: str | Path) -> None:
    """Refuse ``payload``, the contents of results file ``name`` read from ``path``, unless
    it holds what its schema says: a ``CorruptFile`` naming the file and the first field
    that is missing, null where a number is read, or outside its bounds."""
    try:
        _check(schema_of(name), payload, "")
    except _Mismatch as mismatch:
        raise CorruptFile(path, f"has {mismatch}", REWRITE, "results file") from None
