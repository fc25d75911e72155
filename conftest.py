"""Settings of every test run (unit tests and notebooks alike), made before JAX is imported.

The tests compile hundreds of small XLA programs and run most of them briefly, so
compiling is most of their time, and LLVM's optimisation most of compiling. They
compile at optimisation level 0 (the same programs, unoptimised machine code): that
halves the time of a run. The notebooks' kernels inherit the setting from this
process's environment. A level already given in ``XLA_FLAGS`` is kept.
"""

import os

LEVEL_FLAG = "--xla_backend_optimization_level"


def _with_level_zero(flags: str) -> str:
    """``flags`` with the backend optimisation level 0 added, unless they set a level."""
    return flags if LEVEL_FLAG in flags else f"{flags} {LEVEL_FLAG}=0".strip()


os.environ["XLA_FLAGS"] = _with_level_zero(os.environ.get("XLA_FLAGS", ""))
