"""The blocks of an out-of-core ``lodkit simplify`` as Ray tasks.

``lodkit simplify BIG.ply -o OUT.ply --ratio 0.01 --ray ADDRESS`` cuts the
input into blocks in a staging folder beside the output and, for each
round of blocks, writes ``tasks.json`` there and runs::

    python -m pylodkit.blocks TASKS.json --address ADDRESS [--workers N]

which runs one Ray task per block (``_lodkit.run_block_task``: the same
Rust code as the single-process run, so the same bytes come out), prints
``done I FACES_IN FACES_OUT`` as each finishes, and exits 0 once all are
written, or 1 with a one-line message on stderr. ``ADDRESS``: ``local``
starts a local cluster of ``--workers`` CPUs (default: all) for this run;
``auto`` or ``HOST:PORT`` joins a running cluster, whose nodes must all see
the staging folder at the same path (a shared folder). Each task uses one
core (``RAYON_NUM_THREADS=1``). A block whose output exists is skipped, so
a rerun after an interruption resumes.
"""
from __future__ import annotations

import argparse
import os
import sys
from typing import List, Optional


def _run(path: str, index: int):
    from pylodkit import _lodkit

    return _lodkit.run_block_task(path, index)


def run_blocks(tasks: str, address: str = "local", workers: Optional[int] = None,
               out=sys.stdout) -> int:
    """Runs every task of the task file ``tasks`` on Ray; returns the
    number of tasks. Raises ``pylodkit.errors.InputError`` for a bad task
    file and the task's error for a failed block."""
    import ray

    from . import _lodkit

    path = os.path.abspath(tasks)
    n = _lodkit.block_task_count(path)
    env = {"RAYON_NUM_THREADS": "1"}
    if address == "local":
        # The local cluster's workers inherit the driver's environment.
        os.environ.update(env)
        ray.init(address="local", num_cpus=workers or os.cpu_count() or 1, include_dashboard=False,
                 log_to_driver=False, configure_logging=False)
    else:
        ray.init(address=address, runtime_env={"env_vars": env}, log_to_driver=False)
    try:
        task = ray.remote(num_cpus=1, max_retries=1)(_run)
        pending = {task.remote(path, i): i for i in range(n)}
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            for ref in ready:
                i = pending.pop(ref)
                faces_in, faces_out = ray.get(ref)
                print("done %d %d %d" % (i, faces_in, faces_out), file=out, flush=True)
    finally:
        ray.shutdown()
    return n


def _last_line(e: BaseException) -> str:
    text = str(e).strip()
    return text.splitlines()[-1] if text else type(e).__name__


def main(argv: Optional[List[str]] = None) -> int:
    p = argparse.ArgumentParser(prog="python -m pylodkit.blocks",
                                description="Run the block tasks of an out-of-core lodkit simplify on Ray.")
    p.add_argument("tasks", help="the round's tasks.json, written by lodkit simplify --ray")
    p.add_argument("--address", default="local",
                   help="local (a local cluster for this run), auto, or HOST:PORT")
    p.add_argument("--workers", type=int, default=None,
                   help="CPUs of a local cluster (default: all)")
    a = p.parse_args(argv)
    if a.workers is not None and not 1 <= a.workers <= 4096:
        p.error("--workers: expected 1..=4096, got %d" % a.workers)
    try:
        import ray  # noqa: F401
    except ImportError:
        print("pylodkit.blocks: Ray is not installed here: pip install 'pylodkit[batch]'",
              file=sys.stderr)
        return 1
    try:
        run_blocks(a.tasks, a.address, a.workers)
    except Exception as e:  # one line, as lodkit's CLI prints its errors
        print("pylodkit.blocks: %s" % _last_line(e), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
