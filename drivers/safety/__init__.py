"""The collision monitor on the driver side: the profile's ``safety:`` settings and the base wrapper.

The algorithm is pure and lives in :mod:`perception.collision_monitor`; here are the declared
settings (:mod:`drivers.safety.settings`), the :class:`~drivers.interfaces.Base` that applies it
to every command (:mod:`drivers.safety.guarded_base`) and the record of its interventions
(:mod:`drivers.safety.log`).
"""
