"""Computing the explorer's maps off the page's thread: the newest request wins, and a
computation checks its `CancelToken` between bands (`Requests`)."""

from __future__ import annotations

import threading
import time

__all__ = ["CancelToken", "Cancelled", "Requests"]


class Cancelled(Exception):
    """Raised inside a computation whose request a newer one replaced."""


class CancelToken:
    """A flag a computation checks between bands (`check`)."""

    def __init__(self) -> None:
        self._event = threading.Event()

    def cancel(self) -> None:
        """Ask the computation to stop at its next check."""
        self._event.set()

    @property
    def cancelled(self) -> bool:
        return self._event.is_set()

    def check(self) -> None:
        """Raise `Cancelled` if `cancel` was called."""
        if self._event.is_set():
            raise Cancelled()



class Requests:
    """Compute maps off the caller's thread: the newest request wins.

    One worker thread takes the latest request (a newer one replaces a waiting one, and
    cancels the one computing, which stops at its next band), computes its preview,
    progressive steps and final map (`Explorer.stages`) and reports each with
    ``on_result(request_id, result)``; then, with ``on_numbers``, the final map's numbers
    (`Explorer.numbers`) with ``on_numbers(request_id, result, numbers)``. Errors go to
    ``on_error(request_id, exception)``, cancellations to ``on_cancel(request_id)``.
    Callbacks run on the worker thread.

    Parameters
    ----------
    explorer : sweep.explore.model.Explorer
    on_result, on_error, on_cancel, on_numbers : callable
    """

    def __init__(self, explorer, on_result, on_error=None, on_cancel=None,
                 on_numbers=None) -> None:
        self.explorer = explorer
        self.on_result = on_result
        self.on_error = on_error or (lambda request, exc: None)
        self.on_cancel = on_cancel or (lambda request: None)
        self.on_numbers = on_numbers
        self._condition = threading.Condition()
        self._pending = None
        self._token: CancelToken | None = None
        self._closed = False
        self._count = 0
        self._busy = False
        self._thread = threading.Thread(target=self._loop, name="sweep-explore", daemon=True)
        self._thread.start()

    def submit(self, state) -> int:
        """Ask for ``state``'s map; cancels the request computing. Returns its id."""
        with self._condition:
            if self._token is not None:
                self._token.cancel()
            self._count += 1
            self._token = CancelToken()
            self._pending = (self._count, state, self._token)
            self._condition.notify()
            return self._count

    def idle(self, timeout: float | None = None) -> bool:
        """Wait until nothing is pending or computing; False on timeout."""
        end = None if timeout is None else time.monotonic() + timeout
        with self._condition:
            while self._pending is not None or self._busy:
                left = None if end is None else end - time.monotonic()
                if left is not None and left <= 0:
                    return False
                self._condition.wait(left)
        return True

    def close(self) -> None:
        """Cancel what is computing and stop the worker."""
        with self._condition:
            self._closed = True
            if self._token is not None:
                self._token.cancel()
            self._condition.notify_all()

    def _loop(self) -> None:
        while True:
            with self._condition:
                while self._pending is None and not self._closed:
                    self._condition.wait()
                if self._closed:
                    return
                request, state, token = self._pending
                self._pending = None
                self._busy = True
            try:
                final = self.explorer.stages(
                    state, token,
                    lambda result, request=request: self.on_result(request, result))
                if self.on_numbers is not None:
                    token.check()
                    self.on_numbers(request, final, self.explorer.numbers(final))
            except Cancelled:
                self.on_cancel(request)
            except Exception as exc:  # noqa: BLE001 - reported to the page, never raised into the loop
                self.on_error(request, exc)
            finally:
                with self._condition:
                    self._busy = False
                    self._condition.notify_all()
