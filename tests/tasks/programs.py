"""Random mission programs for differential fuzzing, and two interpreters of them.

A program is a few top-level scripts (lists of ops) over shared primitives: three events, two
resources, two stores and a container. The same program runs

- on fleet_async (``run_fleet``), on asyncio and on trio: their traces must be identical, with
  no internal error, conservation after every event (no slot, amount or item lost or made
  twice, under any interleaving of interrupts, cancels and timeouts), and at the end every
  slot free and every request queue empty; cut into pieces (``run(until=t)`` suspending, the
  next run continuing), the trace must be the one of the uncut run;
- on SimPy (``run_simpy``), when it uses only what SimPy can express (``full=False``): its trace
  must equal fleet_async's, so a consistently wrong order cannot pass.

The two interpreters mirror each other op for op: ``await sim.sleep(k)`` where SimPy has
``yield env.timeout(k)``, ``with res.request() as req: await req`` where SimPy yields it, and so
on. Time is in whole steps (dt = 1).
"""

from __future__ import annotations

import sys
from collections import Counter
from dataclasses import dataclass, field
from typing import Any

import simpy
from hypothesis import strategies as st

import fleet_async as fa

if sys.version_info < (3, 11):
    from exceptiongroup import BaseExceptionGroup

Op = tuple[Any, ...]

N_EVENTS = 3
INTERRUPTIBLE = frozenset({"sleep", "wait", "use", "hold", "join"})
"""States in which the SimPy-comparable programs may be interrupted, and only once until the
interrupt is caught (SimPy leaves an interrupted getter's request queued, and loses an item a
served get had taken; fleet_async withdraws the request and gives the item back, so those
states are left to the fleet_async-only programs)."""


@dataclass
class Program:
    scripts: list[list[Op]]
    capacities: tuple[int, int] = (1, 2)
    store_capacities: tuple[int, int] = (1, 3)
    container: tuple[int, int] = (5, 2)
    until: int = 12
    full: bool = False


# ----- strategies -----------------------------------------------------------------------------


def _ops(depth: int, full: bool) -> st.SearchStrategy[Op]:
    k = st.integers(0, 3)
    simple = [
        st.tuples(st.just("sleep"), k),
        st.tuples(st.just("tvalue"), k),
        st.tuples(st.just("set"), st.integers(0, N_EVENTS - 1)),
        st.tuples(st.just("wait"), st.integers(0, N_EVENTS - 1)),
        st.tuples(
            st.just("use"), st.integers(0, 1), st.integers(0, 3), st.none() | st.integers(0, 3)
        ),
        st.tuples(st.just("put"), st.integers(0, 1), st.sampled_from(["a", "b", "c"])),
        st.tuples(st.just("get"), st.integers(0, 1)),
        st.tuples(st.just("cput"), st.integers(1, 3)),
        st.tuples(st.just("cget"), st.integers(1, 3)),
        st.tuples(st.just("anyof"), k, k),
        st.tuples(st.just("interrupt"), st.integers(0, 3)),
    ]
    if full:
        how = st.sampled_from(["interrupt", "cancel"])
        simple += [
            st.tuples(st.just("cancel"), st.integers(0, 3)),
            st.tuples(st.just("raise"), st.integers(0, 9)),
            # put, then interrupt or cancel a mission as the put is processed: a get the put
            # served is given up before its mission resumed (the conservation cases)
            st.tuples(st.just("kick"), st.integers(0, 1), st.sampled_from(["a", "b"]), k, how),
            st.tuples(st.just("tkick"), st.integers(1, 3), k, how),
        ]
    if depth < 2:
        sub = _script(depth + 1, full)
        simple += [st.tuples(st.just("spawn"), sub), st.tuples(st.just("spawnjoin"), sub)]
        if full:
            simple += [
                st.tuples(st.just("scope"), k, sub),
                st.tuples(st.just("shield"), sub),
                st.tuples(st.just("group"), st.lists(sub, min_size=1, max_size=3)),
                st.tuples(st.just("race"), sub, sub),
            ]
    return st.one_of(simple)


def _script(depth: int, full: bool) -> st.SearchStrategy[list[Op]]:
    return st.deferred(lambda: st.lists(_ops(depth, full), max_size=6 if depth == 0 else 3))


def programs(full: bool) -> st.SearchStrategy[Program]:
    """Random programs; ``full=False`` keeps to what SimPy can express."""
    return st.builds(
        Program,
        scripts=st.lists(_script(0, full), min_size=1, max_size=4),
        capacities=st.tuples(st.integers(1, 2), st.integers(1, 2)),
        store_capacities=st.tuples(st.integers(1, 2), st.integers(1, 3)),
        container=st.tuples(st.integers(3, 6), st.integers(0, 3)),
        until=st.integers(4, 16),
        full=st.just(full),
    )


# ----- fleet_async ------------------------------------------------------------------------------


@dataclass
class _World:
    sim: Any
    program: Program
    step0: int
    log: list[tuple[Any, ...]] = field(default_factory=list)
    handles: dict[str, Any] = field(default_factory=dict)
    state: dict[str, str] = field(default_factory=dict)
    started: set[str] = field(default_factory=set)
    pending: set[str] = field(default_factory=set)  # interrupted, not yet caught

    def __post_init__(self) -> None:
        sim, program = self.sim, self.program
        self.events = [fa.Event(sim) for _ in range(N_EVENTS)]
        self.resources = [fa.Resource(sim, c) for c in program.capacities]
        self.stores = [fa.Store(sim, c) for c in program.store_capacities]
        self.tank = fa.Container(sim, *program.container)
        self.puts: list[Any] = []  # every put request the missions made (stores and tank)
        self.gets: list[Any] = []  # every get request, and whether its value was taken
        self.taken: set[int] = set()

    def check_conservation(self) -> None:
        """After every event: each store holds exactly what was put in and not taken out
        (counting what served gets hold for their missions and what waits to go back), the
        tank's level likewise, and no resource has more users than slots."""
        for queueing in [*self.stores, self.tank]:
            tank = queueing is self.tank
            put_in: Counter[Any] = Counter()
            if tank:
                put_in["amount"] += self.program.container[1]
            for put in self.puts:
                if put.owner is queueing and put.triggered and put.ok:
                    put_in[put.amount if tank else put.item] += 1
            held: Counter[Any] = Counter()
            for get in self.gets:
                if get.owner is queueing and get.triggered and get.ok:
                    held[get.amount if tank else get.raw_value] += 1  # taken or still held
            for back in queueing.put_queue:
                if back.mission is None:  # what a withdrawn get took, waiting to go back
                    held[back.amount if tank else back.item] += 1
            if tank:
                total_in = sum(k * v for k, v in put_in.items() if k != "amount")
                total_in += put_in["amount"]
                level = queueing.level + sum(k * v for k, v in held.items())
                assert level == total_in, f"the tank holds {level}, {total_in} went in"
            else:
                assert Counter(queueing.items) + held == put_in, (
                    f"store {self.stores.index(queueing)}: {queueing.items} + held {held} "
                    f"!= put in {put_in}"
                )
        for n, resource in enumerate(self.resources):
            assert resource.count <= resource.capacity, f"resource {n} over capacity"
            assert not set(map(id, resource.users)) & set(map(id, resource.queue)), n

    def now(self) -> int:
        return int(self.sim.step_count - self.step0)

    def note(self, *entry: Any) -> None:
        self.log.append((self.now(), *entry))


async def _fa_script(w: _World, name: str, ops: list[Op]) -> str:
    w.started.add(name)
    for i, op in enumerate(ops):
        try:
            await _fa_op(w, name, i, op)
        except fa.Interrupt as interrupt:
            w.pending.discard(name)
            w.note(name, i, "interrupted", interrupt.cause)
        w.state[name] = "run"
    w.note(name, "end")
    return name


async def _fa_op(w: _World, name: str, i: int, op: Op) -> None:
    sim, kind = w.sim, op[0]
    if kind == "sleep":
        w.state[name] = "sleep"
        await sim.sleep(op[1])
        w.note(name, i, "slept")
    elif kind == "tvalue":
        w.state[name] = "sleep"
        w.note(name, i, "value", await sim.timeout(op[1], f"v{op[1]}"))
    elif kind == "set":
        event = w.events[op[1]]
        fresh = not event.triggered
        if fresh:
            event.succeed(f"{name}:{i}")
        w.note(name, i, "set", fresh)
    elif kind == "wait":
        w.state[name] = "wait"
        w.note(name, i, "waited", await w.events[op[1]])
    elif kind == "use":
        _, r, hold, patience = op
        w.state[name] = "use"
        with w.resources[r].request() as req:
            if patience is None:
                await req
                got = True
            else:
                got = req in await (req | sim.timeout(patience))
            w.note(name, i, "got" if got else "reneged")
            if got:
                w.state[name] = "hold"
                await sim.sleep(hold)
                w.note(name, i, "released")
    elif kind == "put":
        w.state[name] = "store"
        put = w.stores[op[1]].put(op[2])
        w.puts.append(put)
        await put
        w.note(name, i, "put")
    elif kind == "get":
        w.state[name] = "store"
        get = w.stores[op[1]].get()
        w.gets.append(get)
        w.note(name, i, "got", await get)
    elif kind == "cput":
        w.state[name] = "store"
        put = w.tank.put(op[1])
        w.puts.append(put)
        await put
        w.note(name, i, "cput", w.tank.level)
    elif kind == "cget":
        w.state[name] = "store"
        get = w.tank.get(op[1])
        w.gets.append(get)
        await get
        w.note(name, i, "cget", w.tank.level)
    elif kind == "anyof":
        w.state[name] = "sleep"
        got = await (sim.timeout(op[1], "a") | sim.timeout(op[2], "b"))
        w.note(name, i, "anyof", sorted(got.values()))
    elif kind in ("spawn", "spawnjoin"):
        child = f"{name}.{i}"
        handle = sim.spawn(_fa_script, w, child, op[1], name=child)
        w.handles[child] = handle
        w.note(name, i, "spawned")
        if kind == "spawnjoin":
            w.state[name] = "join"
            try:
                w.note(name, i, "joined", await handle)
            except fa.MissionCancelledError:
                w.note(name, i, "joined a cancelled mission")
    elif kind == "interrupt":
        target = f"m{op[1]}"
        handle = w.handles.get(target)
        ok = (
            handle is not None
            and handle.is_alive
            and target != name
            and target in w.started
            and (
                w.program.full or (w.state.get(target) in INTERRUPTIBLE and target not in w.pending)
            )
        )
        if ok:
            w.pending.add(target)
            handle.interrupt(name)
        w.note(name, i, "interrupt", target, ok)
    else:
        await _fa_full_op(w, name, i, op)


async def _fa_full_op(w: _World, name: str, i: int, op: Op) -> None:
    sim, kind = w.sim, op[0]
    if kind in ("kick", "tkick"):
        # The put's processing serves a waiting get (scheduled after it at this step); this
        # mission resumes in the same processing and kicks the getter before it resumes.
        target, how = f"m{op[-2]}", op[-1]
        put = w.stores[op[1]].put(op[2]) if kind == "kick" else w.tank.put(op[1])
        w.puts.append(put)
        w.state[name] = "store"
        await put
        handle = w.handles.get(target)
        ok = handle is not None and handle.is_alive and target != name
        if ok:
            handle.interrupt(name) if how == "interrupt" else handle.cancel()
        w.note(name, i, kind, target, how, ok)
    elif kind == "cancel":
        handle = w.handles.get(f"m{op[1]}")
        ok = handle is not None and handle.is_alive and f"m{op[1]}" != name
        if ok:
            handle.cancel()
        w.note(name, i, "cancel", op[1], ok)
    elif kind == "raise":
        w.note(name, i, "raise", op[1])
        raise ValueError(f"{name}:{op[1]}")
    elif kind == "scope":
        with sim.move_on_after(op[1]) as scope:
            await _fa_nested(w, name, i, op[2])
        w.note(name, i, "scope", scope.cancelled_caught)
    elif kind == "shield":
        with sim.cancel_scope(shield=True):
            await _fa_nested(w, name, i, op[1])
        w.note(name, i, "shield done")
    elif kind == "group":
        try:
            async with sim.task_group() as tg:
                for k, sub in enumerate(op[1]):
                    tg.start_soon(_fa_script, w, f"{name}.{i}.{k}", sub, name=f"{name}.{i}.{k}")
        except BaseExceptionGroup as group:
            w.note(name, i, "group failed", [str(e) for e in group.exceptions])
        else:
            w.note(name, i, "group done")
    elif kind == "race":
        try:
            index, _ = await sim.race(
                _fa_script(w, f"{name}.{i}.a", op[1]), _fa_script(w, f"{name}.{i}.b", op[2])
            )
            w.note(name, i, "race", index)
        except ValueError as error:
            w.note(name, i, "race failed", str(error))
    else:  # pragma: no cover
        raise AssertionError(f"unknown op {op!r}")


async def _fa_nested(w: _World, name: str, i: int, ops: list[Op]) -> None:
    for j, op in enumerate(ops):
        try:
            await _fa_op(w, name, i * 100 + j, op)
        except fa.Interrupt as interrupt:
            w.pending.discard(name)
            w.note(name, i * 100 + j, "interrupted", interrupt.cause)
        w.state[name] = "run"


def run_fleet(
    sim: Any, program: Program, backend: str, cuts: tuple[int, ...] = ()
) -> tuple[list[tuple[Any, ...]], str]:
    """Run ``program`` on fleet_async; return its trace and how the run ended.

    Args:
        sim: The simulation (reused across programs).
        program: What to run.
        backend: "asyncio" or "trio".
        cuts: Steps (after the start, before ``program.until``) at which the run stops with
            its missions suspended, to be continued by the next ``fleet_async.run``.

    Raises:
        AssertionError: if conservation breaks after an event, or a slot is still held or a
            request still queued at the end.
    """
    w = _World(sim, program, sim.step_count)
    sim.mission_runtime.kernel.after_event = w.check_conservation

    async def main() -> None:
        for n, ops in enumerate(program.scripts):
            w.handles[f"m{n}"] = sim.spawn(_fa_script, w, f"m{n}", ops, name=f"m{n}")

    start, dt = sim.sim_time, sim.params.timestep
    pieces = [*sorted(set(cuts)), program.until]
    try:
        for k, end in enumerate(pieces):
            last = k == len(pieces) - 1
            runtime = sim.mission_runtime
            if runtime is not None:
                runtime.kernel.after_event = w.check_conservation
            fa.run(
                sim,
                main if k == 0 else None,
                until=start + end * dt,
                then="cancel" if last else "suspend",
                backend=backend,
                watchdog=10.0,
            )
        outcome = "ok"
    except (ValueError, BaseExceptionGroup) as error:
        outcome = f"{type(error).__name__}: {_leaves(error)}"
    w.check_conservation()
    for n, resource in enumerate(w.resources):
        assert resource.count == 0, f"resource {n} still has users {resource.users}"
        assert not resource.queue, f"resource {n} still has requests queued"
    for n, queueing in enumerate([*w.stores, w.tank]):
        assert not queueing.get_queue, f"get requests left in {n}"
        # Only give-backs (what a cancelled get had taken, owned by no mission) may still wait
        # for room: nobody took from the store again after them.
        assert all(r.mission is None for r in queueing.put_queue), f"put requests left in {n}"
    return w.log, outcome


def _leaves(error: BaseException) -> list[str]:
    if isinstance(error, BaseExceptionGroup):
        return [leaf for inner in error.exceptions for leaf in _leaves(inner)]
    return [f"{type(error).__name__}({error})"]


# ----- SimPy ------------------------------------------------------------------------------------


@dataclass
class _SimPyWorld:
    env: simpy.Environment
    program: Program
    log: list[tuple[Any, ...]] = field(default_factory=list)
    handles: dict[str, Any] = field(default_factory=dict)
    state: dict[str, str] = field(default_factory=dict)
    started: set[str] = field(default_factory=set)
    pending: set[str] = field(default_factory=set)  # interrupted, not yet caught

    def __post_init__(self) -> None:
        env, program = self.env, self.program
        self.events = [env.event() for _ in range(N_EVENTS)]
        self.resources = [simpy.Resource(env, c) for c in program.capacities]
        self.stores = [simpy.Store(env, c) for c in program.store_capacities]
        capacity, init = program.container
        self.tank = simpy.Container(env, capacity, init)

    def note(self, *entry: Any) -> None:
        self.log.append((int(self.env.now), *entry))


def _sp_script(w: _SimPyWorld, name: str, ops: list[Op]) -> Any:
    w.started.add(name)
    for i, op in enumerate(ops):
        try:
            yield from _sp_op(w, name, i, op)
        except simpy.Interrupt as interrupt:
            w.pending.discard(name)
            w.note(name, i, "interrupted", interrupt.cause)
        w.state[name] = "run"
    w.note(name, "end")
    return name


def _sp_op(w: _SimPyWorld, name: str, i: int, op: Op) -> Any:
    env, kind = w.env, op[0]
    if kind == "sleep":
        w.state[name] = "sleep"
        yield env.timeout(op[1])
        w.note(name, i, "slept")
    elif kind == "tvalue":
        w.state[name] = "sleep"
        w.note(name, i, "value", (yield env.timeout(op[1], f"v{op[1]}")))
    elif kind == "set":
        event = w.events[op[1]]
        fresh = not event.triggered
        if fresh:
            event.succeed(f"{name}:{i}")
        w.note(name, i, "set", fresh)
    elif kind == "wait":
        w.state[name] = "wait"
        w.note(name, i, "waited", (yield w.events[op[1]]))
    elif kind == "use":
        _, r, hold, patience = op
        w.state[name] = "use"
        with w.resources[r].request() as req:
            if patience is None:
                yield req
                got = True
            else:
                got = req in (yield req | env.timeout(patience))
            w.note(name, i, "got" if got else "reneged")
            if got:
                w.state[name] = "hold"
                yield env.timeout(hold)
                w.note(name, i, "released")
    elif kind == "put":
        w.state[name] = "store"
        yield w.stores[op[1]].put(op[2])
        w.note(name, i, "put")
    elif kind == "get":
        w.state[name] = "store"
        w.note(name, i, "got", (yield w.stores[op[1]].get()))
    elif kind == "cput":
        w.state[name] = "store"
        yield w.tank.put(op[1])
        w.note(name, i, "cput", w.tank.level)
    elif kind == "cget":
        w.state[name] = "store"
        yield w.tank.get(op[1])
        w.note(name, i, "cget", w.tank.level)
    elif kind == "anyof":
        w.state[name] = "sleep"
        got = yield env.timeout(op[1], "a") | env.timeout(op[2], "b")
        w.note(name, i, "anyof", sorted(got.values()))
    elif kind in ("spawn", "spawnjoin"):
        child = f"{name}.{i}"
        handle = env.process(_sp_script(w, child, op[1]))
        w.handles[child] = handle
        w.note(name, i, "spawned")
        if kind == "spawnjoin":
            w.state[name] = "join"
            w.note(name, i, "joined", (yield handle))
    elif kind == "interrupt":
        target = f"m{op[1]}"
        handle = w.handles.get(target)
        ok = (
            handle is not None
            and handle.is_alive
            and target != name
            and target in w.started
            and w.state.get(target) in INTERRUPTIBLE
            and target not in w.pending
        )
        if ok:
            w.pending.add(target)
            handle.interrupt(name)
        w.note(name, i, "interrupt", target, ok)
    else:  # pragma: no cover
        raise AssertionError(f"SimPy cannot run {op!r}")


def run_simpy(program: Program) -> list[tuple[Any, ...]]:
    """Run a SimPy-expressible ``program`` on SimPy; return its trace."""
    assert not program.full
    env = simpy.Environment()
    w = _SimPyWorld(env, program)
    for n, ops in enumerate(program.scripts):
        w.handles[f"m{n}"] = env.process(_sp_script(w, f"m{n}", ops))
    env.run(until=program.until)
    return w.log
