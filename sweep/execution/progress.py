"""Progress of a run: a `tqdm` bar (a widget in Jupyter) with trajectories done, rate and
time left, shown only where someone can see it."""

from __future__ import annotations

import os
import sys
from contextlib import contextmanager

__all__ = ["progress_bar", "wanted"]

_FALSE = ("", "0", "false", "no", "off")


def _in_notebook() -> bool:
    """True inside a Jupyter (IPython kernel) session, where stderr is no terminal."""
    shell = sys.modules.get("IPython")
    try:
        return shell is not None and "IPKernelApp" in shell.get_ipython().config
    except AttributeError:  # IPython imported, no shell running
        return False


def wanted(progress: bool | None) -> bool:
    """Whether to show progress: ``progress`` when given; by default on when stderr is
    a terminal or in a Jupyter notebook, and off under continuous integration (the
    environment variable ``CI`` set to anything but false)."""
    if progress is not None:
        return bool(progress)
    if os.environ.get("CI", "").strip().lower() not in _FALSE:
        return False
    return sys.stderr.isatty() or _in_notebook()


class _Silent:
    """The bar's interface, doing nothing."""

    def update(self, n: int) -> None:
        pass


@contextmanager
def progress_bar(progress: bool | None, total: int, *, initial: int = 0, unit: str = "traj",
                 desc: str = "sweep"):
    """A bar over ``total`` trajectories, ``initial`` of them already done (resumed from a
    checkpoint: they do not count in the rate); `wanted` decides whether it shows.

    Yields
    ------
    object with ``update(n)``
        Add ``n`` trajectories done. The bar closes when the block ends.
    """
    if not wanted(progress):
        yield _Silent()
        return
    from tqdm.auto import tqdm

    bar = tqdm(total=total, initial=initial, unit=unit, unit_scale=total >= 10_000,
               desc=desc, file=sys.stderr, dynamic_ncols=True, mininterval=0.5,
               smoothing=0.1)
    try:
        yield bar
    finally:
        bar.close()
