"""Ray, the engine the baselines and the sweeps run on: a local Ray by default, a running cluster with an address.

On one machine nothing needs setting up: ``ray.init()`` starts a local Ray with one worker per CPU and stops it with
the driver. On a cluster, start Ray on each machine (``ray start --head`` on one, ``ray start --address HEAD:6379`` on
the others, each with RAY_AUTH_MODE=token and the head's token: docs/scaling.md) and give the head's address
(``--address HEAD:6379``, or ``auto`` on a cluster machine) from a shell with the same two: the repository's
code is shipped to the workers (Ray's runtime_env working_dir), and the run folders must be on storage that every
machine mounts at the same path (``--runs``), as Ray Tune's storage_path must.
"""

from __future__ import annotations

from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
MAX_RETRIES = 3
"""Times Ray retries a run whose worker process died (killed, out of memory, its machine lost)."""
SHIPPED_EXCLUDES = ["runs/", ".git/", "docs/", "agents/pretrained/", "*.zip", "*.pkl"]
"""Left out of the code shipped to a cluster's workers: run folders, history, pages and models (Ray caps the upload)."""


def connect(address: str | None = None, num_cpus: int | None = None):
    """The ray module, connected: to the cluster at address, else to a new local Ray of num_cpus CPUs (default: all).
    Raises SystemExit with the install command if Ray is missing (it is the [scale] extra)."""
    try:
        import ray
    except ImportError as error:
        raise SystemExit('this command runs on Ray: pip install -e ".[scale]"') from error
    if not ray.is_initialized():
        if address is None:
            ray.init(num_cpus=num_cpus, include_dashboard=False, configure_logging=False)
        else:
            ray.init(address=address, runtime_env={"working_dir": str(REPO), "excludes": SHIPPED_EXCLUDES})
    return ray
