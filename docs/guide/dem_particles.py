"""The guide's "DEM with triangulated particles" (docs/guide.md) in Python: four granulates of
about a centimetre dropped into an open box, stepped until they come to rest, and their contacts
read."""

import math
import sys

import numpy as np

import delta
from delta import dem

# [guide:begin world]
r = 0.01  # particles of about 1 cm, in SI units
rock = dem.ParticleShape(delta.granulate(7, semi_axes=(r, 0.8 * r, 0.7 * r)), density=2500.0)
epsilon = r / 20  # surfaces closer than 2ε are in contact
stiffness = rock.mass * (1.0 / epsilon) ** 2  # m v² / ε²: stops 1 m/s within ε (section 4)
parameters = dem.Parameters(
    time_step=math.pi * math.sqrt(rock.mass / 2 / stiffness) / 30,  # a thirtieth of a contact
    epsilon=epsilon, filter_distance=r / 4,  # h: a pair's contact points closer than h merge
    stiffness=stiffness, restitution=0.5, friction=0.5)

world = dem.World(parameters)
shape = world.add_shape(rock)  # prepared once, shared by its particles
world.add_obstacle(dem.open_box(0.05, 0.05, 0.03))  # a floor at z = 0 and four walls
for i in range(4):  # at rest unless a velocity is given
    position = (0.025 * (i % 2) - 0.0125, 0.025 * (i // 2) - 0.0125, 0.01 + 0.002 * i)
    world.add_particle(shape, position, delta.Quaternion.from_axis_angle((1, 2, 3), i))

world.run(3000)  # 3000 steps of 37 µs: 0.11 s
for contact in world.contacts:  # one record a contact point: delta.dem.contact_dtype
    other = "wall" if contact["with_obstacle"] else "particle"
    print(f"particle {contact['first']}, {other} {contact['second']}: force {contact['force']} N")
for x, v in zip(world.positions, world.velocities):
    print(f"at {x} m, moving at {np.linalg.norm(v):.2g} m/s")
s = world.statistics
print(f"{s['contact_points']} contact points of {s['pairs_in_contact']} pairs; "
      f"{100 * s['contact_detection_seconds'] / s['total_seconds']:.0f}% of the last step in "
      "contact detection")
# [guide:end world]

# The time step is the library's suggestion (dem::suggestedTimeStep) for this stiffness.
if not math.isclose(parameters.time_step, world.suggested_time_step, rel_tol=1e-12):
    sys.exit(f"time step {parameters.time_step!r}, suggested {world.suggested_time_step!r}")
# They fell into the box and came nearly to rest, on its floor.
x, speed = world.positions, np.linalg.norm(world.velocities, axis=1)
if not np.all((abs(x[:, 0]) < 0.025) & (abs(x[:, 1]) < 0.025) & (x[:, 2] > 0) & (x[:, 2] < 2 * r)
              & (speed < 0.1)):
    sys.exit("a particle left the box or is still fast")
if not world.contacts["with_obstacle"].any():
    sys.exit("no particle rests on the floor")
