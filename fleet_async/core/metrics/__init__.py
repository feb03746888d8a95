"""Fleet KPIs: a collector that observes a simulation from its events and its state store,
and the summary and per-robot rows it returns (``sim.kpis()``).

May import ``sim`` and below; never ``checkpoint`` (its floor-mate).
"""
