"""What Resource, Container and Store share: put and get requests served in queue order.

A request is an event. Creating one queues it and serves what can be served at once; a served
request is *triggered* (scheduled), and its waiter resumes when the kernel processes it, so
even a free resource makes the requester yield once, as SimPy does. When a put request is
processed, waiting gets are served again, and the other way round: a release hands the slot on
when the kernel processes it, and the new holder resumes when its own grant is processed.

What a mission that stops waiting leaves behind follows SimPy, with conservation as the
invariant (no slot, amount or item is ever lost or made twice):

- cancelled (a timeout, a lost race, a task group): its request is withdrawn; what a served
  get took goes back first in line, and awaiting that get again raises;
- interrupted: its request stays as it is, queued or served, for the mission to await again
  (a served get hands over what it took then); leaving the request's ``with`` block, or the
  mission's end, withdraws it as a cancellation would.
"""

from __future__ import annotations

from collections.abc import Callable
from types import TracebackType
from typing import Any

from fleet_async.tasks.kernel import SimEvent, kernel_of

__all__ = ["GetRequest", "PutRequest", "Queueing"]


class Queueing:
    """Put and get queues, served by the subclass's ``try_put`` / ``try_get``.

    ``try_put(request)`` / ``try_get(request)`` trigger the request if it can be served now,
    and return whether to go on trying later requests of the same queue.

    Args:
        sim: The simulation whose runs serve the requests.
    """

    def __init__(self, sim: Any) -> None:
        self.sim = sim
        self.put_queue: list[PutRequest] = []
        """Put requests not served yet, in serving order."""
        self.get_queue: list[GetRequest] = []
        """Get requests not served yet, in serving order."""

    def try_put(self, request: Any) -> bool:
        """Serve ``request`` if possible; return whether to try the next put too."""
        raise NotImplementedError

    def try_get(self, request: Any) -> bool:
        """Serve ``request`` if possible; return whether to try the next get too."""
        raise NotImplementedError

    def restore(self, request: GetRequest) -> None:
        """Give back what a served get took, when its only waiter gave up before resuming
        (nothing to give back by default)."""

    def add_put(self, request: PutRequest) -> None:
        """Queue a new put request (in serving order)."""
        self.put_queue.append(request)

    def serve_puts(self, _: SimEvent | None = None) -> None:
        """Serve waiting puts in queue order (a get was processed, or a put was made)."""
        _serve(self.put_queue, self.try_put)

    def serve_gets(self, _: SimEvent | None = None) -> None:
        """Serve waiting gets in queue order (a put was processed, or a get was made)."""
        _serve(self.get_queue, self.try_get)


def _serve(queue: list[Any], try_one: Callable[[Any], bool]) -> None:
    """Try the requests of ``queue`` in order, dropping those served, until one says stop."""
    i = 0
    while i < len(queue):
        request = queue[i]
        proceed = try_one(request)
        if request.triggered:
            del queue[i]
        else:
            i += 1
        if not proceed:
            break


class _Request(SimEvent):
    __slots__ = ("mission", "owner")

    fails_run_unhandled = False  # only a withdrawn get fails, and only for a late awaiter

    def __init__(self, owner: Queueing, what: str) -> None:
        kernel = kernel_of(owner.sim, what)
        super().__init__(kernel)
        self.owner = owner
        self.mission = kernel.current
        """The mission that made the request (None from outside the missions)."""

    def __enter__(self) -> Any:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.cancel()

    def cancel(self) -> None:
        """Withdraw the request if it has not been served yet."""
        raise NotImplementedError

    def abandon(self, mission: Any, cancelled: bool = True) -> None:
        """Its waiting mission was cancelled (withdraw the request, unless someone else
        waits on it) or interrupted (keep it, and withdraw it when the mission ends without
        having awaited it again)."""
        if self.callbacks is None or len(self.callbacks) != 1:  # only the serve callback left
            return
        if cancelled:
            self.withdraw()
        elif self.mission is not None and self.mission is mission:
            self.mission.keep_request(self)

    def withdraw(self) -> None:
        """Nobody will take what this request got: undo it (see the subclasses)."""
        self.cancel()


class PutRequest(_Request):
    """A request to put into a Queueing (a resource request, a store or container put)."""

    __slots__ = ()

    def __init__(self, owner: Queueing, what: str, give_back: bool = False) -> None:
        super().__init__(owner, what)
        if give_back:  # what a cancelled get took: first in line, owned by no mission
            self.mission = None
            owner.put_queue.insert(0, self)
        else:
            owner.add_put(self)
        self.callbacks.append(owner.serve_gets)  # type: ignore[union-attr]  # a fresh event
        owner.serve_puts()

    def cancel(self) -> None:
        """Withdraw the request if it has not been served yet (a granted slot is released by
        the ``with`` block or ``acquire`` that holds it)."""
        if not self.triggered and self in self.owner.put_queue:
            self.owner.put_queue.remove(self)


class GetRequest(_Request):
    """A request to get from a Queueing (a release, a store or container get)."""

    __slots__ = ()

    def __init__(self, owner: Queueing, what: str) -> None:
        super().__init__(owner, what)
        owner.get_queue.append(self)
        self.callbacks.append(owner.serve_puts)  # type: ignore[union-attr]  # a fresh event
        owner.serve_gets()

    def cancel(self) -> None:
        """Withdraw the request: unserved, it leaves the queue; served to a mission that was
        interrupted before it took the result, what it took goes back (nothing is lost)."""
        if not self.triggered:
            if self in self.owner.get_queue:
                self.owner.get_queue.remove(self)
        elif self.mission is not None and self.mission.drop_kept_request(self):
            self.withdraw()

    def withdraw(self) -> None:
        """Withdraw it unserved, or give back what it took: awaiting it afterwards raises
        (what it took is back in line, so handing it over too would make it twice)."""
        if not self.triggered:
            self.cancel()
        elif self.ok:
            self.owner.restore(self)
            self.ok = False
            self.raw_value = RuntimeError(
                f"{self!r} was withdrawn when its mission stopped waiting on it; what it took "
                "went back"
            )
