"""Fleet-scale benchmark: step time, real-time factor, spawn time and memory per agent.

The workload and its report live in :mod:`fleet_async.bench` (also run by ``fleet-async bench``);
see there for what is measured.

Run:  python benchmarks/fleet_bench.py [--n 100 1000 10000] [--large] [--json] [--profile]
"""

from __future__ import annotations

from fleet_async.bench import main

if __name__ == "__main__":
    raise SystemExit(main())
