"""Scale-out: the same sweeps and populations spread over local devices, processes and machines.

Two independent layers, both on engines the user already runs:

- :mod:`camjax.scaleout.sharding` -- one host, several devices (CPU cores as XLA host devices, or
  GPUs): the weighting and (for the GA) population axes of the solvers' batched arrays are laid out
  over a :class:`jax.sharding.Mesh` with ``NamedSharding``; XLA partitions the same jitted
  solvers. Results equal the unsharded ones.
- :mod:`camjax.scaleout.blocks` / :mod:`~camjax.scaleout.backends` / :mod:`~camjax.scaleout.driver`
  -- many processes or machines: a sweep is cut into blocks of (scene, weightings); a pure block
  function is mapped over them by a sequential loop, a spawn process pool or Ray; every finished
  block is stored at once (:mod:`~camjax.scaleout.store`), so a sweep resumes where it stopped and
  a failed block is retried.
"""

from camjax.scaleout.backends import BACKENDS, Outcome, ProcessMap, RayMap, SequentialMap, make_backend
from camjax.scaleout.blocks import (
    BlockTask,
    SweepSpec,
    configure_worker,
    make_blocks,
    pareto_records,
    solve_block,
)
from camjax.scaleout.driver import SweepRun, run_blocks, sweep_blocks
from camjax.scaleout.store import BlockStore, ManifestMismatch

__all__ = [
    "BACKENDS", "BlockStore", "BlockTask", "ManifestMismatch", "Outcome", "ProcessMap", "RayMap",
    "SequentialMap", "SweepRun", "SweepSpec", "configure_worker", "make_backend", "make_blocks",
    "pareto_records", "run_blocks", "solve_block", "sweep_blocks",
]
