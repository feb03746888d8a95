"""Process communication (SimPy example ``process_communication``): pipes made of Stores.

Senders put time-stamped messages into a pipe every few seconds; receivers take them out, and
between two reads do other work for a while, so a message may wait in the pipe: the receiver
then notes that it is late. A one-to-one or many-to-one pipe is one Store; a one-to-many pipe
broadcasts each message into one Store per receiver and returns an ``all_of`` of the puts.
A sender may put at the very time its receiver comes back for the next message, in either
order of scheduling.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest
import simpy

import fleet_async as fa

SEED = 42
SEND_GAP = (3.0, 10.0)  # between two messages of a sender: a uniform draw (s)
WORK_TIME = (2.0, 9.0)  # a receiver's work between two reads: a uniform draw (s)
SIM_TIME = 100.0  # s
DRAWN = 40  # draws per sender or receiver, more than SIM_TIME needs
TOPOLOGIES = {  # senders, receivers
    "one-to-one": (["sender A"], ["receiver A"]),
    "many-to-one": (["sender A", "sender B"], ["receiver A"]),
    "one-to-many": (["sender A"], ["receiver A", "receiver B"]),
}


@dataclass(frozen=True)
class Party:
    name: str
    waits: tuple[float, ...]  # a sender's gaps, or a receiver's work times


def parties(names: list[str], span: tuple[float, float], rng, on_grid) -> list[Party]:
    return [Party(name, tuple(on_grid(x) for x in rng.uniform(*span, DRAWN))) for name in names]


def draw(topology: str, on_grid) -> tuple[list[Party], list[Party]]:
    """Every sender's and receiver's draws, made before any simulation runs."""
    rng = np.random.default_rng(SEED)
    senders, receivers = TOPOLOGIES[topology]
    return parties(senders, SEND_GAP, rng, on_grid), parties(receivers, WORK_TIME, rng, on_grid)


class Broadcast:
    """A one-to-many pipe: every receiver reads its own copy of each message from its own
    store. Built from a store factory and an ``all_of``, so SimPy and missions share it."""

    def __init__(self, new_store: Callable[[], Any], all_of: Callable[[list], Any]) -> None:
        self._new_store = new_store
        self._all_of = all_of
        self._outputs: list[Any] = []

    def connect(self) -> Any:
        """A new receiving end (a store)."""
        store = self._new_store()
        self._outputs.append(store)
        return store

    def put(self, message: Any) -> Any:
        """Put ``message`` into every receiver's store; an event for all the puts."""
        return self._all_of([store.put(message) for store in self._outputs])


def simpy_pipes(senders: list[Party], receivers: list[Party]) -> list[tuple]:
    env = simpy.Environment()
    log: list[tuple] = []
    if len(receivers) == 1:
        store = simpy.Store(env)
        send, inboxes = store.put, [store]
    else:
        pipe = Broadcast(lambda: simpy.Store(env), env.all_of)
        send, inboxes = pipe.put, [pipe.connect() for _ in receivers]

    def talk(sender: Party):
        for gap in sender.waits:
            yield env.timeout(gap)
            send((env.now, sender.name))
            log.append((env.now, sender.name, "sends"))

    def listen(receiver: Party, inbox: simpy.Store):
        for work in receiver.waits:
            sent_at, sender = yield inbox.get()
            on_time = "late" if sent_at < env.now else "on time"
            log.append((env.now, receiver.name, (on_time, sender, sent_at)))
            yield env.timeout(work)

    for sender in senders:
        env.process(talk(sender))
    for receiver, inbox in zip(receivers, inboxes, strict=True):
        env.process(listen(receiver, inbox))
    env.run(until=SIM_TIME)
    return log


async def mission_pipes(
    sim, senders: list[Party], receivers: list[Party], log: list[tuple]
) -> None:
    if len(receivers) == 1:
        store = fa.Store(sim)
        send, inboxes = store.put, [store]
    else:
        pipe = Broadcast(lambda: fa.Store(sim), sim.all_of)
        send, inboxes = pipe.put, [pipe.connect() for _ in receivers]

    async def talk(sender: Party) -> None:
        for gap in sender.waits:
            await sim.timeout(gap)
            send((sim.now, sender.name))
            log.append((sim.now, sender.name, "sends"))

    async def listen(receiver: Party, inbox: fa.Store) -> None:
        for work in receiver.waits:
            sent_at, sender = await inbox.get()
            on_time = "late" if sent_at < sim.now else "on time"
            log.append((sim.now, receiver.name, (on_time, sender, sent_at)))
            await sim.timeout(work)

    for sender in senders:
        sim.spawn(talk, sender, name=sender.name)
    for receiver, inbox in zip(receivers, inboxes, strict=True):
        sim.spawn(listen, receiver, inbox, name=receiver.name)


@pytest.mark.parametrize("topology", TOPOLOGIES)
def test_process_communication_logs_match_simpy(topology, on_grid, run_missions):
    senders, receivers = draw(topology, on_grid)
    expected = simpy_pipes(senders, receivers)
    log: list[tuple] = []
    run_missions(mission_pipes, senders, receivers, log, until=SIM_TIME)
    assert log == expected
    received = [what[0] for _, who, what in expected if who.startswith("receiver")]
    assert "late" in received and "on time" in received
