"""A sparse, event-driven model (SimPy's machine shop, at its documentation's size) on SimPy
and as missions, side by side in one run.

Ten machines make parts (normal, mean 10 min) and break down (exponential, mean 300 min); one
repairman repairs them (30 min) with a preemptive resource that outranks his own jobs (30 min).
Four weeks of minutes at a timestep of 0.5 min: 80,640 steps of which almost none moves
anything, so the mission driver jumps over the empty steps (``sim.idle_steps``) instead of
running them. Durations are drawn before either run and rounded onto the step grid, so both
make the same parts, and the script checks that they do.

Run:  python benchmarks/sparse_bench.py [--weeks 4] [--machines 10] [--repeat 3] [--no-skip]
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np
import simpy

import fleet_async as fa

DT = 0.5
PART_MEAN, PART_SIGMA = 10.0, 2.0
MTTF = 300.0
REPAIR_TIME = 30.0
JOB_TIME = 30.0


def _on_grid(t: float) -> float:
    return max(DT, round(t / DT) * DT)


def _draws(machines: int, minutes: float, seed: int = 42) -> list[tuple[list[float], list[float]]]:
    rng = np.random.default_rng(seed)
    parts = int(minutes / PART_MEAN * 2) + 10
    failures = int(minutes / MTTF * 3) + 10
    return [
        (
            [_on_grid(t) for t in rng.normal(PART_MEAN, PART_SIGMA, parts)],
            [_on_grid(t) for t in rng.exponential(MTTF, failures)],
        )
        for _ in range(machines)
    ]


def simpy_shop(draws: list[Any], minutes: float) -> list[int]:
    """Parts made per machine, on SimPy."""
    env = simpy.Environment()
    repairman = simpy.PreemptiveResource(env, capacity=1)
    made = [0] * len(draws)
    broken = [False] * len(draws)

    def machine(i: int, parts: list[float]) -> Any:
        for part_time in parts:
            left = part_time
            while left:
                start = env.now
                try:
                    yield env.timeout(left)
                    left = 0
                except simpy.Interrupt:
                    broken[i] = True
                    left -= env.now - start
                    with repairman.request(priority=1) as req:
                        yield req
                        yield env.timeout(REPAIR_TIME)
                    broken[i] = False
            made[i] += 1

    def breaker(i: int, proc: Any, failures: list[float]) -> Any:
        for ttf in failures:
            yield env.timeout(ttf)
            if not broken[i]:
                proc.interrupt()

    def other_jobs() -> Any:
        while True:
            left = JOB_TIME
            while left:
                with repairman.request(priority=2) as req:
                    yield req
                    start = env.now
                    try:
                        yield env.timeout(left)
                        left = 0
                    except simpy.Interrupt:
                        left -= env.now - start

    for i, (parts, failures) in enumerate(draws):
        proc = env.process(machine(i, parts))
        env.process(breaker(i, proc, failures))
    env.process(other_jobs())
    env.run(until=minutes)
    return made


def mission_shop(draws: list[Any], minutes: float, backend: str, skip: bool) -> list[int]:
    """Parts made per machine, as fleet_async missions."""
    params = fa.SimulationParams(
        gui=False, monitor=False, target_rtf=0.0, timestep=DT, enable_floor=False
    )
    with fa.MultiRobotSimulationCore(params) as sim:
        if not skip:  # a per-step subscriber keeps every step (for comparison)
            sim.events.on(fa.SimEvents.POST_STEP, lambda **_: None)
        repairman = fa.PreemptiveResource(sim, capacity=1)
        made = [0] * len(draws)
        broken = [False] * len(draws)

        async def machine(i: int, parts: list[float]) -> None:
            for part_time in parts:
                left = part_time
                while left:
                    start = sim.now
                    try:
                        await sim.timeout(left)
                        left = 0
                    except fa.Interrupt:
                        broken[i] = True
                        left -= sim.now - start
                        with repairman.request(priority=1) as req:
                            await req
                            await sim.timeout(REPAIR_TIME)
                        broken[i] = False
                made[i] += 1

        async def breaker(i: int, proc: fa.Mission, failures: list[float]) -> None:
            for ttf in failures:
                await sim.timeout(ttf)
                if not broken[i]:
                    proc.interrupt()

        async def other_jobs() -> None:
            while True:
                left = JOB_TIME
                while left:
                    with repairman.request(priority=2) as req:
                        await req
                        start = sim.now
                        try:
                            await sim.timeout(left)
                            left = 0
                        except fa.Interrupt:
                            left -= sim.now - start

        async def main() -> None:
            for i, (parts, failures) in enumerate(draws):
                proc = sim.spawn(machine, i, parts)
                sim.spawn(breaker, i, proc, failures)
            sim.spawn(other_jobs)

        fa.run(sim, main, backend=backend, until=minutes)
        return made


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--weeks", type=float, default=4.0)
    parser.add_argument("--machines", type=int, default=10)
    parser.add_argument("--repeat", type=int, default=3, help="interleaved runs; best reported")
    parser.add_argument("--no-skip", action="store_true", help="also time every step run")
    args = parser.parse_args(argv)
    minutes = args.weeks * 7 * 24 * 60
    draws = _draws(args.machines, minutes)
    modes: dict[str, Any] = {"simpy": lambda: simpy_shop(draws, minutes)}
    for backend in ("asyncio", "trio"):
        modes[backend] = lambda b=backend: mission_shop(draws, minutes, b, skip=True)
        if args.no_skip:
            modes[f"{backend} (every step)"] = lambda b=backend: mission_shop(
                draws, minutes, b, skip=False
            )
    best: dict[str, float] = {}
    made: dict[str, list[int]] = {}
    for _ in range(max(1, args.repeat)):
        for mode, fn in modes.items():
            t0 = time.process_time()
            made[mode] = fn()
            best[mode] = min(best.get(mode, 1e9), time.process_time() - t0)
    reference = made["simpy"]
    print(
        f"machine shop: {args.machines} machines, {args.weeks:g} weeks = "
        f"{int(minutes / DT):,} steps of {DT} min; parts made: {sum(reference)}"
    )
    for mode, seconds in best.items():
        same = "same parts as SimPy" if made[mode] == reference else f"DIFFERENT: {made[mode]}"
        ratio = seconds / best["simpy"]
        print(f"  {mode:<22} {seconds:7.3f} s CPU ({ratio:5.1f}x SimPy)  {same}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
