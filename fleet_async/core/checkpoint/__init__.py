"""Checkpoints: save a kinematic simulation and restore it into one built the same way.

``sim.save_state(path)`` writes the state of a simulation between two steps; in a fresh
process, ``sim.restore_state(path)`` on a simulation freshly built from the same scenario
brings it to that state, and from there the two continue step for step identically (same
poses, same events, same random numbers). A sweep can so branch many runs from one warmed-up
state (``fleet-async sweep --checkpoint``).

Saved: the clock (step count, collisions so far, paused); the random generator and every random
stream (``sim.rng_for``); every
object's pose, velocity, angular velocity, collision mode, name and "moved since the last
collision check" flag; attachments; the kinematic engine (paths in progress, segment
progress, velocity commands); every action queue (queued and running actions with their
progress, timers); each agent's controllers, agent plugins (battery) and joints; the
simulation plugins; the schedules of callbacks and plugins; the collision system's active pairs
and check schedule; the safety fields (each robot's field parameters and footprint, whether it
is stopped and since when, its stops and time stopped, the deadlock watch; a map's obstacle
boxes come with the scenario's maps). Objects that actions, controllers or plugins refer to
are saved by id.

Not saved, and refused where it matters:

- **missions**: a coroutine waiting mid-await cannot be saved, so ``save_state`` refuses while
  ``fleet_async.run`` is in progress. Save before it starts or after it returns, and start new
  missions after a restore (the actions they had queued are saved with the queues).
- **physics**: PyBullet's dynamic state (contacts, solver) is not captured: ``physics=True`` is
  refused on both sides.
- **per-object callbacks** (``obj.register_callback``): refused.
- **added motion systems** (``sim.add_motion_system``), among them the devices' (doors, lifts,
  workcells, whose state lives in that system and in the devices): refused.
- **callbacks** (``sim.register_callback``) are code: the restoring scenario registers the same
  ones, in the same order; only their schedules are restored. The same holds for plugins,
  controllers and agent plugins, whose state goes through their ``get_state`` / ``set_state``.
- the KPI collector, recordings, the GUI and the monitor.

Restoring checks that the target was built the same way (the same objects, of the same types,
with the same ids, controllers and plugins, the same timestep) and has not stepped yet, and
checks the whole state against it before changing anything; it refuses otherwise, naming the
difference, and the simulation is left as it was.

The file holds plain data only (format 2): reading one runs no code from it. Controller and
plugin state must be plain data (``save_state`` names the one that is not). Format-1 files were
pickles; they are read only with ``restore_state(path, unsafe=True)``.

``api.py`` is the simulation's side (``save_state`` / ``restore_state``), ``format.py`` the file
(an npz of a JSON header, a JSON state and arrays), ``codec.py`` the state tree as plain data,
``references.py`` the simulation's objects and random streams by id and key, ``saving.py`` and
``restoring.py`` the two directions (``validation.py`` the checks before a restore changes
anything), ``legacy.py`` format 1. May import ``sim`` and below; never ``metrics`` (its
floor-mate).
"""
