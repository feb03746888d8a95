"""Random streams: one generator per user of randomness, derived from (seed, key).

``sim.rng`` is the simulation's own generator. Everything else that draws random numbers (a
controller, a plugin, a mission) asks for a stream of its own with ``sim.rng_for(*key)``: a
``numpy.random.Generator`` seeded with ``numpy.random.SeedSequence([seed, *key])``, where the
key names the user (an object, or its id, then ints or strings naming the role: the random walk
controller uses ``sim.rng_for(agent, 0x5A17)``). Streams are independent of each other and of
the order users are built in, so adding a robot does not shift another robot's numbers.

The simulation remembers the streams it handed out, by key (the same key, the same generator),
so it can reseed every one of them in place: ``sim.reseed(seed)`` re-derives ``sim.rng`` and
every stream from the new seed. That is how a sweep branches N different runs from one
checkpoint (``fleet-async sweep --checkpoint --seeds``). A checkpoint saves the streams' states
and restores them into the generators their holders already have.

Keys: an int >= 0 stays itself, a simulation object becomes its id, a string becomes four 32-bit
words of its SHA-256 (stable across processes, unlike ``hash``). ``sim.seed_sequence(*key)``
gives the seed sequence itself, for a generator the simulation need not remember (one per
mission, say); after ``reseed`` it follows the new seed too.
"""

from __future__ import annotations

import hashlib
from typing import Any

import numpy as np

__all__ = ["RandomStreams", "RandomStreamsApi", "stream_key"]

StreamKey = tuple[int, ...]


def stream_key(parts: tuple[Any, ...]) -> StreamKey:
    """The ints a key stands for (see the module's docstring).

    Raises:
        ValueError: for a negative int or a part of another type, naming it.
    """
    key: list[int] = []
    for part in parts:
        if isinstance(part, str):
            digest = hashlib.sha256(part.encode()).digest()
            key.extend(int.from_bytes(digest[i : i + 4], "little") for i in range(0, 16, 4))
            continue
        value = getattr(part, "object_id", part)
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
            raise ValueError(
                f"sim.rng_for: key part {part!r}: expected an int >= 0, a string or a "
                "simulation object"
            )
        key.append(int(value))
    return tuple(key)


class RandomStreams:
    """The streams a simulation handed out, by key, and the seed they derive from."""

    def __init__(self, seed: int) -> None:
        self.seed = int(seed)
        self._streams: dict[StreamKey, np.random.Generator] = {}
        self._keys: dict[int, StreamKey] = {}

    def seed_sequence(self, key: StreamKey) -> np.random.SeedSequence:
        """The seed sequence of ``key`` under the current seed."""
        return np.random.SeedSequence([self.seed, *key])

    def get(self, key: StreamKey) -> np.random.Generator:
        """The stream of ``key`` (made and remembered on first use)."""
        found = self._streams.get(key)
        if found is None:
            found = np.random.Generator(np.random.PCG64(self.seed_sequence(key)))
            self._streams[key] = found
            self._keys[id(found)] = key
        return found

    def key_of(self, generator: object) -> StreamKey | None:
        """The key of ``generator`` if it is one of these streams, else None."""
        key = self._keys.get(id(generator))
        return key if key is not None and self._streams.get(key) is generator else None

    def reseed(self, seed: int) -> None:
        """Re-derive every stream from ``seed``, in place (holders keep their generators)."""
        self.seed = int(seed)
        for key, generator in self._streams.items():
            generator.bit_generator.state = np.random.PCG64(self.seed_sequence(key)).state

    def get_state(self) -> dict[str, Any]:
        """The seed and every stream's state (checkpoints)."""
        return {
            "seed": self.seed,
            "streams": [[list(key), g.bit_generator.state] for key, g in self._streams.items()],
        }

    def set_state(self, state: dict[str, Any]) -> None:
        """Take back :meth:`get_state`: streams the holders already have get the saved state."""
        self.seed = int(state["seed"])
        for key, bit_state in state["streams"]:
            self.get(tuple(key)).bit_generator.state = bit_state


class RandomStreamsApi:
    """``sim.rng_for`` / ``sim.seed_sequence`` / ``sim.reseed`` (mixed into the simulation)."""

    rng: np.random.Generator
    _random_streams: RandomStreams | None = None

    @property
    def random_streams(self) -> RandomStreams:
        """The streams handed out so far (checkpoints save and restore them)."""
        if self._random_streams is None:
            params = getattr(self, "params", None)
            self._random_streams = RandomStreams(getattr(params, "seed", 0))
        return self._random_streams

    def rng_for(self, *key: Any) -> np.random.Generator:
        """The random stream of ``key`` (an object or id, then ints or strings naming the
        role): seeded from ``SeedSequence([seed, *key])``, the same generator for the same key.

        Raises:
            ValueError: for a key part that is not an int >= 0, a string or an object.
        """
        return self.random_streams.get(stream_key(key))

    def seed_sequence(self, *key: Any) -> np.random.SeedSequence:
        """``SeedSequence([seed, *key])`` under the current seed, for a generator the
        simulation does not keep (``numpy.random.default_rng(sim.seed_sequence(...))``)."""
        return self.random_streams.seed_sequence(stream_key(key))

    def reseed(self, seed: int) -> None:
        """Re-derive ``sim.rng`` and every stream from ``seed`` (a branch of a checkpoint).

        Raises:
            ValueError: for a seed that is not an int >= 0.
        """
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ValueError(f"sim.reseed: seed: expected an int >= 0, got {seed!r}")
        self.rng.bit_generator.state = np.random.default_rng(int(seed)).bit_generator.state
        self.random_streams.reseed(int(seed))

    def _reset_random_streams(self, seed: int) -> None:
        """Start over from ``seed``: ``sim.rng`` anew, no stream handed out (``sim.reset``)."""
        self.rng = np.random.default_rng(seed)
        self._random_streams = RandomStreams(seed)
