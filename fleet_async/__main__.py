"""``python -m fleet_async``: the ``fleet-async`` command."""

from __future__ import annotations

from fleet_async.cli import main

if __name__ == "__main__":
    raise SystemExit(main())
