"""Ray, the engine the baselines and the sweeps run on: a local Ray by default, a running cluster with an address.

On one machine nothing needs setting up: ``ray.init()`` starts a local Ray with one worker per CPU and stops it with
the driver. On a cluster, start Ray on each machine (``ray start --head`` on one, ``ray start --address HEAD:6379`` on
the others, each with RAY_AUTH_MODE=token and the head's token: docs/scaling.md) and give the head's address
(``--address HEAD:6379``, or ``auto`` on a cluster machine) from a shell with the same two: the repository's
code is shipped to the workers (Ray's runtime_env working_dir), and the run folders must be on storage that every
machine mounts at the same path (``--runs``), as Ray Tune's storage_path must.
"""

from __future__ import annotations

import argparse
import socket
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
MAX_RETRIES = 3
"""Times Ray retries a run whose worker process died (killed, out of memory, its machine lost)."""
SHIPPED_EXCLUDES = ["runs/", ".git/", "docs/", "agents/pretrained/", "*.zip", "*.pkl"]
"""Left out of the code shipped to a cluster's workers: run folders, history, pages and models (Ray caps the upload)."""
PROBE_SECONDS = 5.0
"""How long connect waits for the cluster's address to accept a TCP connection; ray.init retries for minutes."""


def host_port(address: str) -> tuple[str, int] | None:
    """(host, port) of HOST:PORT or ray://HOST:PORT ([HOST] for IPv6), None for 'auto'; ValueError otherwise."""
    if address == "auto":
        return None
    host, colon, port = address.removeprefix("ray://").rpartition(":")
    if not (colon and host and port.isdigit() and 0 < int(port) < 2**16):
        raise ValueError(f"{address!r} is not a Ray address: HOST:PORT (e.g. 10.0.0.1:6379), ray://HOST:PORT or auto")
    return host.strip("[]"), int(port)


def address(text: str) -> str:
    """argparse type: a Ray address, as host_port reads it."""
    try:
        host_port(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from error
    return text


def probe(address: str):
    """ConnectionError naming the address unless it accepts a TCP connection within PROBE_SECONDS, so that a wrong
    address fails at once (ray.init would retry for minutes). 'auto' is left to Ray, which finds the address."""
    target = host_port(address)
    if target is None:
        return
    try:
        socket.create_connection(target, PROBE_SECONDS).close()
    except OSError as error:
        raise ConnectionError(
            f"--address {address}: nothing answers there ({error}); give the address `ray start --head` printed"
        ) from error


def connect(address: str | None = None, num_cpus: int | None = None):
    """The ray module, connected: to the cluster at address, else to a new local Ray of num_cpus CPUs (default: all).
    Raises SystemExit with the install command if Ray is missing (it is the [scale] extra), ConnectionError if
    nothing answers at the address."""
    try:
        import ray
    except ImportError as error:
        raise SystemExit('this command runs on Ray: pip install -e ".[scale]"') from error
    if address is not None:
        probe(address)
    if not ray.is_initialized():
        if address is None:
            ray.init(num_cpus=num_cpus, include_dashboard=False, configure_logging=False)
        else:
            ray.init(address=address, runtime_env={"working_dir": str(REPO), "excludes": SHIPPED_EXCLUDES})
    return ray
