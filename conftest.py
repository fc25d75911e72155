"""Settings of every test run (unit tests and notebooks alike), made before JAX is imported.

The tests compile hundreds of small XLA programs and run most of them briefly, so
compiling is most of their time. They compile the same programs faster: at LLVM
optimisation level 0, and with XLA's classic CPU emitters instead of its newer fusion
emitters (which take about twice as long to compile here). Together that more than
halves the time of a run. The notebooks' kernels inherit the settings from this
process's environment. A flag already given in ``XLA_FLAGS`` keeps its value.
"""

import os

FAST_COMPILE_FLAGS = {
    "--xla_backend_optimization_level": "0",
    "--xla_cpu_use_fusion_emitters": "false",
}


def with_fast_compile(flags: str) -> str:
    """``flags`` (an ``XLA_FLAGS`` value) with every fast-compile flag it does not set."""
    added = [f"{name}={value}" for name, value in FAST_COMPILE_FLAGS.items() if name not in flags]
    return " ".join([flags, *added]).strip()


os.environ["XLA_FLAGS"] = with_fast_compile(os.environ.get("XLA_FLAGS", ""))
# MuJoCo picks its GL backend when first imported: a test module that imports brax before
# sgb.rl.envs (which sets the same default) would leave the renders without a context.
os.environ.setdefault("MUJOCO_GL", "egl")
