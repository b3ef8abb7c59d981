"""delta.dem: the built-in scenarios against the C++ tool (`delta dem`), a World built by hand,
and the rule that a World running in one thread raises in the others."""

import signal
import threading

import numpy as np
import pytest

import delta


def test_two_particles_restitution(cli_json):
    scenario = delta.dem.two_particles(restitution=0.5)
    world = scenario.world
    assert scenario.name == "two-particles" and world.particle_count == 2
    start = world.positions
    assert start.shape == (2, 3) and world.velocities.shape == (2, 3)
    assert world.velocities[0, 0] > 0 > world.velocities[1, 0]  # approaching along x
    scenario.run()
    meter = scenario.restitution_meter
    assert meter.collided and meter.separated
    assert meter.restitution == pytest.approx(0.5, rel=0.02)
    # The same run as the C++ tool's, bit for bit.
    expected = cli_json("dem", "two-particles", "--restitution", 0.5, "--quiet")
    assert meter.restitution == expected["restitution"]
    assert world.step_count == expected["steps"] == scenario.steps
    assert world.time == expected["time"]
    # After the collision they part along x, momentum conserved.
    assert world.velocities[0, 0] < 0 < world.velocities[1, 0]
    np.testing.assert_allclose(world.linear_momentum, 0.0, atol=1e-12)
    particles = world.particles
    assert particles.dtype == delta.dem.particle_dtype
    np.testing.assert_array_equal(particles["position"], world.positions)
    np.testing.assert_array_equal(particles["velocity"], world.velocities)
    np.testing.assert_allclose(np.linalg.norm(world.orientations, axis=1), 1.0)


def test_contacts_of_a_step_carry_forces():
    scenario = delta.dem.two_particles(restitution=0.5)
    world = scenario.world
    while len(world.contacts) == 0:
        world.step()
        assert world.step_count < scenario.steps, "the particles never touched"
    contacts = world.contacts
    assert contacts.dtype == delta.dem.contact_dtype
    assert (contacts["first"] == 0).all() and (contacts["second"] == 1).all()
    assert not contacts["with_obstacle"].any()
    assert (contacts["force"][:, 0] < 0).all()  # particle 0, on the left, is pushed back
    assert world.statistics["contact_points"] == len(contacts)


def test_settle_equals_the_cli(cli_json):
    scenario = delta.dem.settle(count=8, seed=3)
    assert scenario.world.particle_count == 8 and scenario.world.obstacle_count == 1
    scenario.run(40)
    expected = cli_json("dem", "settle", "--particles", 8, "--seed", 3, "--steps", 40, "--quiet")
    assert scenario.world.time == expected["time"]
    assert scenario.restitution_meter is None


def test_a_world_built_by_hand():
    radius, density = 0.01, 2500.0
    shape = delta.dem.ParticleShape(delta.icosphere(2, radius=radius), density)
    assert shape.mass == pytest.approx(density * shape.volume)
    assert shape.bounding_radius == pytest.approx(radius)
    parameters = delta.dem.Parameters(
        time_step=1e-5, epsilon=radius / 20, filter_distance=radius / 4, stiffness=1e5,
        restitution=0.8,
    )
    world = delta.dem.World(parameters)
    index = world.add_shape(shape)
    world.add_particle(index, position=(0, 0, 2 * radius), velocity=(0, 0, -0.5))
    world.add_obstacle(delta.quad(0.1, 0.1))
    world.set_time_step(world.suggested_time_step)
    heights, rising = [], False
    for _ in range(40):
        world.run(25)
        heights.append(world.positions[0, 2])
        rising = rising or world.velocities[0, 2] > 0
    assert rising, "the sphere did not bounce off the floor"
    assert min(heights) > 0.9 * radius  # it never sank through
    assert world.energies()["total"] < 0.5 * world.particles["shape"].size  # finite and small
    with pytest.raises(delta.Error):
        world.add_particle(5, position=(0, 0, 1))


def test_bad_parameters_raise_delta_error():
    with pytest.raises(delta.Error):
        delta.dem.two_particles(restitution=2.0)
    with pytest.raises(delta.Error):
        delta.dem.settle(count=4, kind="cube")
    with pytest.raises(delta.Error):
        delta.dem.World(delta.dem.Parameters(time_step=-1, epsilon=1, filter_distance=1, stiffness=1))
    with pytest.raises(delta.Error, match="closed"):
        delta.dem.ParticleShape(delta.quad(), 1000.0)


def test_a_step_that_fails_leaves_the_world_as_it_was():
    # Two particles falling along x under 1e71 m/s², stepped by 1e-40 s; a step of 1e-5 s
    # carries them beyond the queries' coordinate range, and their pair's query fails half-way
    # through the step. The positions stayed moved, with the step count as before.
    parameters = delta.dem.Parameters(time_step=1e-40, epsilon=5e-4, filter_distance=2.5e-3,
                                      stiffness=1e4, gravity=(1e71, 0, 0))
    world = delta.dem.World(parameters)
    shape = world.add_shape(delta.icosphere(1).scale(0.01), 2500.0)
    world.add_particle(shape, position=(0, 0, 0))
    world.add_particle(shape, position=(0.05, 0, 0))
    world.run(5)
    before = (world.state_digest, world.step_count, world.time, world.positions.copy())
    world.set_time_step(1e-5)
    with pytest.raises(delta.Error, match="coordinate"):
        world.step()
    assert (world.state_digest, world.step_count, world.time) == before[:3]
    np.testing.assert_array_equal(world.positions, before[3])
    assert np.isfinite(world.energies()["total"])
    world.set_time_step(1e-40)
    world.run(2)
    assert world.step_count == before[1] + 2


def test_a_running_world_refuses_other_threads():
    scenario = delta.dem.two_particles(restitution=0.5)
    world = scenario.world
    runner = threading.Thread(target=world.run, args=(40_000,))
    runner.start()
    refused = False
    while runner.is_alive() and not refused:
        try:
            world.positions
        except RuntimeError as error:
            refused = "in use by another thread" in str(error)
    runner.join()
    assert refused
    assert world.step_count == 40_000


def test_ctrl_c_stops_a_run_between_steps():
    world = delta.dem.two_particles(restitution=0.5).world
    # SIGINT itself, sent to the main thread, with Python's own handler installed for the test:
    # _thread.interrupt_main() does nothing while another handler (SIG_IGN, SIG_DFL) is set,
    # which an earlier test in the same process may leave (the run then went on to its end).
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    main = threading.main_thread().ident
    timer = threading.Timer(0.05, lambda: signal.pthread_kill(main, signal.SIGINT))
    try:
        timer.start()
        with pytest.raises(KeyboardInterrupt):
            # Far longer than the timer on any machine: 200,000 steps take 0.3 s on a Zen 5, so
            # a run of that length could end before the interrupt came (it did once in CI).
            world.run(20_000_000)
    finally:
        timer.join()
        signal.signal(signal.SIGINT, previous)
    assert 0 < world.step_count < 20_000_000
    world.step()  # the world is usable again
