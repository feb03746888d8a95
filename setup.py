"""Build glue that pyproject.toml cannot express: the examples go into the wheel.

The examples are written once, in the top-level ``examples/`` folder (scripts, scenarios,
worlds). The wheel carries them as the package ``fleet_async.examples``, mapped from that
folder, so ``fleet-async examples`` finds them after a normal install. Everything else about
the build is in pyproject.toml.
"""

from setuptools import find_packages, setup

setup(
    packages=[*find_packages(include=["fleet_async", "fleet_async.*"]), "fleet_async.examples"],
    package_dir={"fleet_async.examples": "examples"},
)
