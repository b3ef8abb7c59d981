"""The Discrete Element Method with Δ: rigid triangulated particles in contact.

A World holds particle shapes, particles and obstacles and advances them by time steps (without
the GIL, in parallel); the built-in scenarios return a ready World::

    import delta

    scenario = delta.dem.two_particles(restitution=0.5)
    scenario.run()                       # scenario.world.run(scenario.steps)
    print(scenario.restitution_meter.restitution)   # about 0.5
    print(scenario.world.positions, scenario.world.velocities)

As `delta dem SCENARIO` on the command line.
"""

from ._delta import dem as _dem

Parameters = _dem.Parameters
ParticleShape = _dem.ParticleShape
RestitutionMeter = _dem.RestitutionMeter
Scenario = _dem.Scenario
World = _dem.World
contact_dtype = _dem.contact_dtype
funnel = _dem.funnel
hopper = _dem.hopper
open_box = _dem.open_box
particle_dtype = _dem.particle_dtype
settle = _dem.settle
two_particles = _dem.two_particles

__all__ = [
    "Parameters",
    "ParticleShape",
    "RestitutionMeter",
    "Scenario",
    "World",
    "contact_dtype",
    "funnel",
    "hopper",
    "open_box",
    "particle_dtype",
    "settle",
    "two_particles",
]
