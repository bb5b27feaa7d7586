"""Dask LocalClusters in the tests: each on a port of its own.

A distributed Scheduler (2026.8) always serves HTTP -- its dashboard, or with
``dashboard_address=None`` still its health and metrics routes -- and without an address
it takes port 8787; when 8787 is taken it warns ("Port 8787 is already in use") and moves
to another. pytest-xdist's workers starting clusters at the same time raced for it, and
wherever that warning is an error the cluster fails to start. ``dashboard_address=":0"``
asks the system for a free port instead: every test cluster (and benchmarks/cluster.py's)
passes `DASHBOARD`, and starts inside `port_8787_taken`, which fails a cluster that asks
for 8787.
"""

import contextlib
import socket
import warnings

#: ``dashboard_address`` of every LocalCluster the tests start: any free port.
DASHBOARD = ":0"

#: The warning of a Scheduler that found 8787 taken (a ``PYTHONWARNINGS`` entry turns it
#: into an error in a subprocess, as `port_8787_taken` does in this one).
PORT_TAKEN_ERROR = "error:Port 8787 is already in use:UserWarning"


@contextlib.contextmanager
def port_8787_taken():
    """Hold port 8787 (unless someone holds it already) and turn the Scheduler's
    "Port 8787 is already in use" warning into an error: a cluster started inside that
    asks for 8787 fails to start, one on a free port starts as usual."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    try:
        sock.bind(("", 8787))
        sock.listen()
    except OSError:
        pass  # taken already: the condition this context is for
    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("error", message="Port 8787 is already in use",
                                    category=UserWarning)
            yield
    finally:
        sock.close()
