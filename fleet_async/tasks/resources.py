"""Shared resources in sim time: Resource (slots, with priorities), PreemptiveResource, Lock,
and Container (a level of some continuous or countable matter).

    charger = Resource(sim, capacity=2)

    async with charger.request(priority=1):   # wait for a slot, hold it for the block
        await robot.charge(30.0)

    with charger.request() as req:            # SimPy's form, which composes with a timeout
        got = await (req | sim.timeout(5.0))
        if req in got:
            ...                               # served within 5 s

Requests wait in (priority, request step) order, lower priority first, then first come first
served. A slot handed on by a release reaches the next request when the kernel processes the
release, and the new holder resumes when it processes the grant (SimPy's order).
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from types import TracebackType
from typing import TYPE_CHECKING, Any

from fleet_async.tasks.kernel import kernel_of
from fleet_async.tasks.queueing import GetRequest, PutRequest, Queueing

if TYPE_CHECKING:
    from fleet_async.tasks.missions import Mission

__all__ = [
    "Container",
    "Lock",
    "Preempted",
    "PreemptiveResource",
    "PriorityResource",
    "Release",
    "Request",
    "Resource",
]


@dataclass(frozen=True)
class Preempted:
    """The cause of the Interrupt a preempted holder receives.

    Attributes:
        by: The mission whose request took the slot (None from outside the missions).
        usage_since: Sim time (s) at which the preempted holder got its slot.
        resource: The resource.
    """

    by: Mission | None
    usage_since: float | None
    resource: Resource


class Request(PutRequest):
    """A request for a slot: an event that succeeds once the slot is granted.

    ``async with resource.request():`` waits for the slot and releases it on leaving;
    ``with resource.request() as req: await req`` does the same SimPy's way (leaving the block
    withdraws an unserved request and releases a granted one).
    """

    __slots__ = ("key", "preempt", "priority", "usage_since")

    def __init__(self, resource: Resource, priority: float = 0, preempt: bool = True) -> None:
        kernel = kernel_of(resource.sim, "Resource.request")
        self.priority = priority
        self.preempt = preempt
        self.key = (priority, kernel.now, not preempt)
        self.usage_since: float | None = None
        """Sim time (s) at which the slot was granted."""
        super().__init__(resource, "Resource.request")

    @property
    def resource(self) -> Resource:
        """The resource asked for."""
        owner: Resource = self.owner  # type: ignore[assignment]  # requests of a Resource
        return owner

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.cancel()
        self.resource.release(self)  # also when a stopping run closes the mission

    async def __aenter__(self) -> Request:
        try:
            await self
        except BaseException:
            self.cancel()
            self.resource.release(self)
            raise
        return self

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.resource.release(self)


class Release(GetRequest):
    """Giving a slot back: an event that succeeds at once (a release always succeeds)."""

    __slots__ = ("request",)

    def __init__(self, resource: Resource, request: Request) -> None:
        self.request = request
        super().__init__(resource, "Resource.release")

    def withdraw(self) -> None:
        """A release is never undone (the slot was given back when it was made)."""


class Resource(Queueing):
    """``capacity`` slots, handed out by priority (lower first), then request order.

    Args:
        sim: The simulation.
        capacity: Number of slots (an integer >= 1).

    Raises:
        ValueError: if ``capacity`` is not an integer >= 1.
    """

    def __init__(self, sim: Any, capacity: int = 1) -> None:
        if isinstance(capacity, bool) or not isinstance(capacity, int) or capacity < 1:
            raise ValueError(f"Resource.capacity: expected an integer >= 1, got {capacity!r}")
        super().__init__(sim)
        self.capacity = capacity
        self.users: list[Request] = []
        """Granted requests, in grant order."""
        self._held: list[Request] = []  # taken by ``async with resource:`` blocks

    @property
    def queue(self) -> list[PutRequest]:
        """Requests waiting for a slot, in serving order."""
        return self.put_queue

    @property
    def count(self) -> int:
        """Slots in use."""
        return len(self.users)

    in_use = count

    @property
    def queued(self) -> int:
        """Requests waiting for a slot."""
        return len(self.put_queue)

    def request(self, priority: float = 0, preempt: bool = True) -> Request:
        """Ask for a slot (an event; see :class:`Request`). ``preempt`` matters only for a
        PreemptiveResource."""
        return Request(self, priority, preempt)

    def release(self, request: Request | None = None) -> Release:
        """Give a slot back. Without ``request``, the latest slot the current mission holds.

        Raises:
            RuntimeError: if no request is given and the current mission holds no slot.
        """
        if request is None:
            kernel = kernel_of(self.sim, "Resource.release")
            mine = [r for r in self.users if r.mission is kernel.current]
            if not mine:
                raise RuntimeError("Resource.release: this mission holds no slot of it")
            request = mine[-1]
        return Release(self, request)

    async def acquire(self, priority: float = 0) -> Request:
        """Wait for a slot (``release()`` gives it back); returns the granted request."""
        request = self.request(priority)
        try:
            await request
        except BaseException:
            request.cancel()
            self.release(request)
            raise
        return request

    async def __aenter__(self) -> Resource:
        request = await self.acquire()
        self._held.append(request)
        return self

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        kernel = kernel_of(self.sim, "leaving 'async with resource'")
        mine = [r for r in self._held if r.mission is kernel.current]
        request = mine[-1] if mine else None
        if request is not None:
            self._held.remove(request)
        self.release(request)  # a preempted holder's request is no longer a user: harmless

    def add_put(self, request: PutRequest) -> None:
        """Queue a request in (priority, request step) order, after its equals."""
        bisect.insort_right(self.put_queue, request, key=_request_key)

    def try_put(self, request: Request) -> bool:
        """Grant ``request`` if a slot is free."""
        if len(self.users) < self.capacity:
            self.users.append(request)
            kernel = kernel_of(self.sim, "Resource.request")
            request.usage_since = kernel.now * kernel.timestep
            request.succeed()
        return False

    def try_get(self, release: Release) -> bool:
        """Take the released request off the users (a release always succeeds)."""
        if release.request in self.users:
            self.users.remove(release.request)
        release.succeed()
        return False


def _request_key(request: PutRequest) -> tuple[float, int, bool]:
    key: tuple[float, int, bool] = request.key  # type: ignore[attr-defined]  # a Request
    return key


PriorityResource = Resource
"""Resource already serves by priority (SimPy's PriorityResource)."""


class PreemptiveResource(Resource):
    """A Resource whose holders are preempted by more important requests: the holder with the
    least important request (highest priority value, latest) gets ``Interrupt(Preempted(...))``
    and loses its slot, when a request with ``preempt=True`` is more important."""

    def try_put(self, request: Request) -> bool:
        """Preempt the least important holder if ``request`` outranks it, then grant."""
        if len(self.users) >= self.capacity and request.preempt:
            # The least important holder; among equals the one granted last (SimPy's choice).
            victim = max(reversed(self.users), key=_request_key)
            if victim.key > request.key:
                self.users.remove(victim)
                if victim.mission is not None:  # an ended holder raises, as in SimPy
                    victim.mission.interrupt(
                        Preempted(by=request.mission, usage_since=victim.usage_since, resource=self)
                    )
        return super().try_put(request)


class Lock(Resource):
    """A Resource with one slot: ``async with lock:`` or ``async with lock.request():``."""

    def __init__(self, sim: Any) -> None:
        super().__init__(sim, capacity=1)


class ContainerPut(PutRequest):
    """Putting ``amount`` into a Container (waits while it would overflow)."""

    __slots__ = ("amount",)

    def __init__(self, container: Container, amount: float, give_back: bool = False) -> None:
        if not amount > 0:
            raise ValueError(f"Container.put: amount must be > 0, got {amount!r}")
        self.amount = amount
        super().__init__(container, "Container.put", give_back)


class ContainerGet(GetRequest):
    """Taking ``amount`` out of a Container (waits until there is that much)."""

    __slots__ = ("amount",)

    def __init__(self, container: Container, amount: float) -> None:
        if not amount > 0:
            raise ValueError(f"Container.get: amount must be > 0, got {amount!r}")
        self.amount = amount
        super().__init__(container, "Container.get")


class Container(Queueing):
    """A level of matter between 0 and ``capacity`` (fuel, charge, parts): ``await
    tank.put(amount)`` and ``await tank.get(amount)`` wait until they fit.

    Raises:
        ValueError: if ``capacity`` <= 0, or ``init`` is not in [0, capacity].
    """

    def __init__(self, sim: Any, capacity: float = math.inf, init: float = 0) -> None:
        if not capacity > 0:
            raise ValueError(f"Container.capacity: expected a number > 0, got {capacity!r}")
        if not 0 <= init <= capacity:
            raise ValueError(f"Container.init: expected 0 <= init <= {capacity!r}, got {init!r}")
        super().__init__(sim)
        self.capacity = capacity
        self._level = init

    @property
    def level(self) -> float:
        """How much is in the container now."""
        return self._level

    def put(self, amount: float) -> ContainerPut:
        """Put ``amount`` in (an event that succeeds once it fits)."""
        return ContainerPut(self, amount)

    def get(self, amount: float) -> ContainerGet:
        """Take ``amount`` out (an event that succeeds once there is that much)."""
        return ContainerGet(self, amount)

    def try_put(self, request: ContainerPut) -> bool:
        """Add the amount if it fits; go on with the next put only if it did."""
        if self.capacity - self._level >= request.amount:
            self._level += request.amount
            request.succeed()
            return True
        return False

    def restore(self, request: ContainerGet) -> None:  # type: ignore[override]  # its own gets
        """Give back the amount a cancelled get took: a put first in line, served before any
        other (it waits for room if others filled the container meanwhile)."""
        ContainerPut(self, request.amount, give_back=True)

    def try_get(self, request: ContainerGet) -> bool:
        """Take the amount if there is that much; go on only if it did."""
        if self._level >= request.amount:
            self._level -= request.amount
            request.succeed()
            return True
        return False
